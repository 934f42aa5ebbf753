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
    /// The records database, when the sink writes to one (the record
    /// pages read it).
    fn store(&self) -> Option<echothigh_records::BlockingStore> {
        None
    }
    /// When the records no longer go where [`Self::describe`] said (the
    /// database failed): what happened and where they are, in plain words.
    fn fault(&self) -> Option<String> {
        None
    }
    /// The session is over (a case left open stays unfinished).
    fn end(&mut self) -> Result<(), LogError> {
        Ok(())
    }
}

/// Per case started: its name and its records, shared.
pub type CaseLogs = Arc<Mutex<Vec<(String, Arc<Mutex<MemoryLog>>)>>>;

/// Keeps every case's records in memory, readable by tests.
#[derive(Clone, Default)]
pub struct MemorySink {
    /// Per case started: its name and its records.
    pub cases: CaseLogs,
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
    fn doppler(&mut self, c: &echothigh_exam::DopplerCall) -> Result<(), LogError> {
        self.lock().doppler(c)
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

/// Records into the trainee's database (`echothigh-records`): the session
/// row opens with the first case, each case gets its attempt row with its
/// ground truth, and every event, call and score is committed before the
/// exam goes on. When the database fails mid-exam, the records go on into
/// a fallback journal next to it ([`echothigh_records::SessionRecorder`]),
/// and each case log's [`ExamLog::fault`] says so and where.
pub struct DbSink {
    recorder: echothigh_records::SessionRecorder,
}

impl DbSink {
    /// A sink for `trainee` (created on first use) in `store`.
    pub fn new(
        store: echothigh_records::BlockingStore,
        trainee: &str,
    ) -> Result<DbSink, echothigh_records::RecordsError> {
        Ok(DbSink {
            recorder: echothigh_records::SessionRecorder::new(store, trainee)?,
        })
    }

    /// A sink that goes on with `session`, a session of `trainee` that
    /// never ended, and the resume point of its records (the last attempt,
    /// if unfinished, reopened into the same rows).
    pub fn resume(
        store: echothigh_records::BlockingStore,
        trainee: &str,
        session: &echothigh_records::ResumedSession,
    ) -> Result<(DbSink, super::ResumePoint), echothigh_records::RecordsError> {
        let recorder = echothigh_records::SessionRecorder::resume(store, trainee, session)?;
        let point = super::ResumePoint::of_records(session, |c| {
            Box::new(recorder.continue_case(c)) as CaseLog
        });
        Ok((DbSink { recorder }, point))
    }

    /// The session's recorder (its fault and journal).
    pub fn recorder(&self) -> &echothigh_records::SessionRecorder {
        &self.recorder
    }
}

impl RecordSink for DbSink {
    fn begin_case(&mut self, case: &Case, protocol: Protocol) -> Result<CaseLog, LogError> {
        let truth = echothigh_records::TruthSegment::of_case(case);
        Ok(Box::new(self.recorder.begin_case(
            protocol.name(),
            &case.file.name,
            &truth,
        )))
    }

    fn describe(&self) -> String {
        match self.recorder.fault() {
            Some(f) => f,
            None => format!("recorded in {}", self.recorder.store().name()),
        }
    }

    fn store(&self) -> Option<echothigh_records::BlockingStore> {
        Some(self.recorder.store())
    }

    fn fault(&self) -> Option<String> {
        self.recorder.fault()
    }

    fn end(&mut self) -> Result<(), LogError> {
        self.recorder.end()
    }
}
