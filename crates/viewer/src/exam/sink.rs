//! Where an exam session's records go: one [`ExamLog`] per case, opened
//! when the case starts. [`MemorySink`] keeps them in memory (practice, and
//! tests); the `exam` command's database sink (`echothigh-records`)
//! commits each record before the call returns.

use echothigh_cases::Case;
use echothigh_exam::{ExamLog, LogError, MemoryLog, Protocol};
use std::sync::{Arc, Mutex};

/// A case's log, movable to the observer thread.
pub type CaseLog = Box<dyn ExamLog + Send>;

/// Opens one log per case.
pub trait RecordSink: Send {
    /// A log for `case` examined under `protocol`.
    fn begin_case(&mut self, case: &Case, protocol: Protocol) -> Result<CaseLog, LogError>;
    /// Where the records go, in plain words (shown on the page).
    fn describe(&self) -> String;
    /// The session is over (a case left open stays unfinished).
    fn end(&mut self) -> Result<(), LogError> {
        Ok(())
    }
}

/// Keeps every case's records in memory, readable by tests.
#[derive(Clone, Default)]
pub struct MemorySink {
    /// Per case started: its name and its records.
    pub cases: Arc<Mutex<Vec<(String, Arc<Mutex<MemoryLog>>)>>>,
}

/// A shared [`MemoryLog`].
struct SharedLog(Arc<Mutex<MemoryLog>>);

impl ExamLog for SharedLog {
    fn event(&mut self, e: &echothigh_exam::CompressionEvent) -> Result<(), LogError> {
        self.lock().event(e)
    }
    fn call(&mut self, c: &echothigh_exam::Call) -> Result<(), LogError> {
        self.lock().call(c)
    }
    fn finish(
        &mut self,
        coverage: &[echothigh_exam::CoverageBin],
        score: &echothigh_exam::CaseScore,
    ) -> Result<(), LogError> {
        self.lock().finish(coverage, score)
    }
}

impl SharedLog {
    fn lock(&self) -> std::sync::MutexGuard<'_, MemoryLog> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl RecordSink for MemorySink {
    fn begin_case(&mut self, case: &Case, _protocol: Protocol) -> Result<CaseLog, LogError> {
        let log = Arc::new(Mutex::new(MemoryLog::default()));
        self.cases
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((case.file.name.clone(), log.clone()));
        Ok(Box::new(SharedLog(log)))
    }

    fn describe(&self) -> String {
        "not recorded (practice)".into()
    }
}
