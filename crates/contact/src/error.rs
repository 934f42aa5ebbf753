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
    /// Malformed CSV (invalid UTF-8, an unterminated quote, ...).
    #[error("line {line}: malformed CSV: {message}")]
    Malformed {
        /// Line number (1-based).
        line: u64,
        /// The CSV reader's message.
        message: String,
    },
    /// A required column is absent from the header line.
    #[error("line {line}: missing column `{column}` (header has: {found})")]
    MissingColumn {
        /// Line number of the header (1-based).
        line: u64,
        /// The required column name.
        column: &'static str,
        /// The columns that were found.
        found: String,
    },
    /// A field could not be parsed as a finite number.
    #[error("line {line}: column `{column}`: `{text}` is not a finite number")]
    NotANumber {
        /// Line number (1-based).
        line: u64,
        /// Column name.
        column: &'static str,
        /// The offending text.
        text: String,
    },
    /// A row has fewer fields than the header.
    #[error("line {line}: expected {expected} fields, found {found}")]
    ShortRow {
        /// Line number (1-based).
        line: u64,
        /// Number of header fields.
        expected: usize,
        /// Number of fields found.
        found: usize,
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

impl From<echothigh_table::TableError> for CsvError {
    fn from(e: echothigh_table::TableError) -> Self {
        use echothigh_table::TableError as T;
        match e {
            T::Io(message) => CsvError::Io(message),
            e @ T::TooLarge { .. } => CsvError::Io(e.to_string()),
            T::NoHeader => CsvError::TooFewRows {
                found: 0,
                required: crate::calibration::data::MIN_ROWS,
            },
            T::Syntax { line, message } => CsvError::Malformed { line, message },
            T::MissingColumn {
                line,
                column,
                found,
            } => CsvError::MissingColumn {
                line,
                column,
                found,
            },
            T::ShortRow {
                line,
                expected,
                found,
            } => CsvError::ShortRow {
                line,
                expected,
                found,
            },
            T::NotANumber { line, column, text } => CsvError::NotANumber { line, column, text },
        }
    }
}
