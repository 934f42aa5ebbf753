//! Where an exam's records go as the exam goes (issue 14: "written as the
//! exam goes, a crash loses nothing already done"). The runtime calls these
//! as each event, call and score happens; `echothigh-records` implements it
//! over the database, tests over a vector.

use crate::{Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall};

/// Why a record could not be kept (the sink says what and where).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct LogError(pub String);

/// The sink of one case's records, called in the order things happen.
pub trait ExamLog {
    /// A compression event has ended.
    fn event(&mut self, event: &CompressionEvent) -> Result<(), LogError>;
    /// The trainee made a call.
    fn call(&mut self, call: &Call) -> Result<(), LogError>;
    /// The trainee made a Doppler call.
    fn doppler(&mut self, call: &DopplerCall) -> Result<(), LogError>;
    /// The case is over: its coverage strip and score.
    fn finish(&mut self, coverage: &[CoverageBin], score: &CaseScore) -> Result<(), LogError>;
    /// When the records no longer go where they were meant to (the
    /// database failed and a fallback keeps them elsewhere, or nowhere):
    /// what happened and where the records are, in plain words for the
    /// page. `None` while all is well (the default).
    fn fault(&self) -> Option<String> {
        None
    }
}

/// An [`ExamLog`] that keeps everything in memory (tests, `--json` without
/// a database).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MemoryLog {
    /// Events, in order.
    pub events: Vec<CompressionEvent>,
    /// Calls, in order.
    pub calls: Vec<Call>,
    /// Doppler calls, in order.
    pub doppler: Vec<DopplerCall>,
    /// The final coverage, once finished.
    pub coverage: Vec<CoverageBin>,
    /// The score, once finished.
    pub score: Option<CaseScore>,
}

impl ExamLog for MemoryLog {
    fn event(&mut self, event: &CompressionEvent) -> Result<(), LogError> {
        self.events.push(event.clone());
        Ok(())
    }
    fn call(&mut self, call: &Call) -> Result<(), LogError> {
        self.calls.push(call.clone());
        Ok(())
    }
    fn doppler(&mut self, call: &DopplerCall) -> Result<(), LogError> {
        self.doppler.push(call.clone());
        Ok(())
    }
    fn finish(&mut self, coverage: &[CoverageBin], score: &CaseScore) -> Result<(), LogError> {
        self.coverage = coverage.to_vec();
        self.score = Some(score.clone());
        Ok(())
    }
}
