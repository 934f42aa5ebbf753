//! Typed errors of the contact crate.
//!
//! Every error names what was wrong and where: a configuration key as
//! `"{prefix}.{field}"`, a CSV line number, or the failing solve.

use thiserror::Error;

/// A configuration value outside its valid range.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("invalid configuration `{key}` = {value}: {reason}")]
pub struct ConfigError {
    /// Full key, e.g. `probe.half_width`.
    pub key: String,
    /// The offending value, printed.
    pub value: String,
    /// What the value must satisfy.
    pub reason: &'static str,
}

impl ConfigError {
    /// Checks that `value` is finite and strictly positive.
    pub fn positive(prefix: &str, field: &str, value: f64) -> Result<(), ConfigError> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(ConfigError {
                key: format!("{prefix}.{field}"),
                value: value.to_string(),
                reason: "must be finite and > 0",
            })
        }
    }

    /// Checks `lo <= value <= hi` (NaN fails); `reason` states the range
    /// with its unit and why, e.g. `must be in [0.005, 0.05] m (...)`.
    pub fn in_range(
        prefix: &str,
        field: &str,
        value: f64,
        (lo, hi): (f64, f64),
        reason: &'static str,
    ) -> Result<(), ConfigError> {
        if value >= lo && value <= hi {
            Ok(())
        } else {
            Err(ConfigError {
                key: format!("{prefix}.{field}"),
                value: format!("{value:?}"),
                reason,
            })
        }
    }

    /// Checks that `value` is finite and non-negative.
    pub fn non_negative(prefix: &str, field: &str, value: f64) -> Result<(), ConfigError> {
        if value.is_finite() && value >= 0.0 {
            Ok(())
        } else {
            Err(ConfigError {
                key: format!("{prefix}.{field}"),
                value: value.to_string(),
                reason: "must be finite and >= 0",
            })
        }
    }
}

/// A malformed force–indentation CSV file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CsvError {
    /// The file could not be read at all.
    #[error("cannot read calibration data: {0}")]
    Io(String),
    /// The table itself is malformed: syntax, a missing column, a short
    /// row, a field that is not a number (each naming its line).
    #[error(transparent)]
    Table(#[from] echothigh_table::TableError),
    /// A field is a number but not a finite one (NaN, ±∞).
    #[error("line {line}: column `{column}`: {value} is not a finite number")]
    NotFinite {
        /// Line number (1-based).
        line: u64,
        /// Column name.
        column: &'static str,
        /// The value.
        value: f64,
    },
    /// Depths must increase strictly from row to row.
    #[error("line {line}: depth {depth_mm} mm does not increase (previous row: {previous_mm} mm)")]
    NonMonotonicDepth {
        /// Line number (1-based).
        line: u64,
        /// The depth on this line, mm.
        depth_mm: f64,
        /// The depth on the previous data line, mm.
        previous_mm: f64,
    },
    /// A negative depth or force.
    #[error("line {line}: column `{column}` must be >= 0, found {value}")]
    Negative {
        /// Line number (1-based).
        line: u64,
        /// Column name.
        column: &'static str,
        /// The value.
        value: f64,
    },
    /// Too few data rows to fit anything.
    #[error("calibration data has {found} data rows, at least {required} are needed")]
    TooFewRows {
        /// Rows found.
        found: usize,
        /// Rows required.
        required: usize,
    },
}
