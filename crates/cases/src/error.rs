//! Errors of case files: each names the key at fault (or carries the TOML
//! parser's message, which names key and line).

use echothigh_anatomy::AnatomyError;
use thiserror::Error;

/// What is wrong with a case.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CaseError {
    /// The TOML does not parse or has an unknown key or a wrong type.
    #[error("case file: {0}")]
    Parse(String),
    /// A key of the case has a bad value.
    #[error("case: {key} {reason}")]
    Key {
        /// The key, e.g. `vignette.wells`.
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// The `[patient]` table is invalid (the error names `patient.<key>`).
    #[error("case: {0}")]
    Patient(AnatomyError),
    /// A `[[thrombus]]` entry is invalid (the error names `thrombus[i].<key>`).
    #[error("case: {0}")]
    Thrombus(AnatomyError),
    /// No built-in case has this name.
    #[error("unknown case `{0}` (see `echothigh cases list`)")]
    Unknown(String),
    /// A generator setting is out of range.
    #[error("cases generate: {what} = {value}: {reason}")]
    Generator {
        /// The setting (`--count`, `--prevalence`).
        what: &'static str,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        reason: &'static str,
    },
}
