//! The exam that teaches (issue 14): the vocabulary of a compression exam as
//! it is recorded and scored — the findings a trainee calls, the compression
//! events detected from the live state, the coverage of each vein in 2 cm
//! bins, and a case's score. Kept free of the database and of the runtime:
//! `echothigh-records` stores these types, the runtime produces them.
//!
//! Clinical source: `shared/reference/cus-exam-fidelity.md` §1 (protocols,
//! positive criterion, what novices get wrong) and §3 (scoring).
#![warn(missing_docs)]

pub mod case_exam;
pub mod coverage;
pub mod detector;
pub mod doppler;
mod finding;
mod log;
pub mod protocol;
mod record;
pub mod score;

pub use case_exam::{CaseExam, CaseExamError};
pub use coverage::Coverage;
pub use detector::{EventDetector, ExamSample};
pub use doppler::{DopplerCall, DopplerFinding, DopplerScore, DopplerSiteScore, FlowPattern};
pub use finding::Finding;
pub use log::{ExamLog, LogError, MemoryLog};
pub use protocol::{Protocol, ProtocolSite};
pub use record::{
    BinState, Call, CaseScore, CompressionEvent, CoverageBin, MissedSegment, SiteScore,
};
pub use score::{score_case, ScoreInput};
