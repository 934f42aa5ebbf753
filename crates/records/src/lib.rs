//! The trainees' records of the compression exam (issue 14): trainees,
//! sessions, case attempts, compression events, calls, coverage and
//! scores, in SQLite (one file under the user's data directory by
//! default) or PostgreSQL (`--db postgres://…`, a classroom's server),
//! through one code path (sqlx's Any driver) and one versioned schema
//! (`migrations/`).
//!
//! Two faces:
//! - [`Store`], async: for code on a tokio runtime (the viewer's axum
//!   handlers). Open it on the runtime that uses it.
//! - [`BlockingStore`], sync: owns a records thread with its own
//!   current-thread runtime, so sync code (the headless exam, the CLI) and
//!   code inside another runtime call it without a nested-runtime panic.
//!   [`BlockingStore::begin_case`] returns a [`CaseRecorder`], the
//!   `echothigh_exam::ExamLog` the exam writes to; each record is
//!   committed before the call returns.
//!
//! When the database fails mid-exam, [`SessionRecorder`] (the live
//! exam's recorder) turns to a fallback journal next to the database
//! ([`journal`]); [`BlockingStore::import_journal`] replays it once the
//! database works again, idempotently.
//!
//! The statistics (sensitivity and specificity for acute DVT, coverage,
//! pressure adequacy, their trend over sessions) are pure functions in
//! [`stats`], with the counting rules documented there.
#![warn(missing_docs)]

mod blocking;
pub mod breakdown;
mod doppler;
mod error;
mod fallback;
mod import;
pub mod journal;
mod read;
mod resume;
pub mod schema;
pub mod stats;
mod store;
mod url;

pub use blocking::{BlockingStore, CaseRecorder};
pub use error::RecordsError;
pub use fallback::{CaseWriter, SessionRecorder};
pub use import::ImportReport;
pub use journal::{CaseKey, SessionKey};
pub use read::{
    CaseDetail, CaseSummary, ScoreNumbers, SessionRecord, SiteStats, TraineeHistory, TraineeSummary,
};
pub use resume::{ResumedCase, ResumedSession};
pub use store::{
    now_ms, validate_name, CaseId, SessionId, Store, Trainee, TruthSegment, MAX_NAME_CHARS,
};
pub use url::{default_path, sqlite_url, Backend, DbUrl};
