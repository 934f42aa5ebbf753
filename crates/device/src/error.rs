//! Typed errors of the device crate.
//!
//! Every error names what was wrong and where: a configuration key as
//! `"{prefix}.{field}"` (e.g. `exam.phases[2].speed`), or a CSV line number.

use thiserror::Error;

/// A configuration value outside its valid range, or a TOML document that
/// does not parse into the expected structure.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ConfigError {
    /// A value outside its valid range.
    #[error("invalid configuration `{key}` = {value}: {reason}")]
    Invalid {
        /// Full key, e.g. `hand.stiffness` or `exam.phases[1].rate`.
        key: String,
        /// The offending value, printed.
        value: String,
        /// What the value must satisfy.
        reason: &'static str,
    },
}

impl ConfigError {
    /// An [`ConfigError::Invalid`] for `"{prefix}.{field}"`.
    pub fn invalid(prefix: &str, field: &str, value: impl ToString, reason: &'static str) -> Self {
        ConfigError::Invalid {
            key: format!("{prefix}.{field}"),
            value: value.to_string(),
            reason,
        }
    }

    /// Checks that `value` is finite and strictly positive.
    pub fn positive(prefix: &str, field: &str, value: f64) -> Result<(), ConfigError> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(Self::invalid(
                prefix,
                field,
                value,
                "must be finite and > 0",
            ))
        }
    }

    /// Checks `lo <= value <= hi` (NaN fails); `reason` states the range
    /// with its unit and why, e.g. `must be in [0.01, 5] kg (...)`.
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
            Err(Self::invalid(prefix, field, format!("{value:?}"), reason))
        }
    }

    /// Checks that every component of a point lies in `[lo, hi]`; the error
    /// names the first one outside, `"{prefix}.{field}[i]"`.
    pub fn in_range3(
        prefix: &str,
        field: &str,
        value: [f64; 3],
        (lo, hi): (f64, f64),
        reason: &'static str,
    ) -> Result<(), ConfigError> {
        match value.iter().position(|c| !(*c >= lo && *c <= hi)) {
            None => Ok(()),
            Some(i) => Err(Self::invalid(
                prefix,
                &format!("{field}[{i}]"),
                format!("{:?}", value[i]),
                reason,
            )),
        }
    }

    /// Checks that `value` is finite and non-negative.
    pub fn non_negative(prefix: &str, field: &str, value: f64) -> Result<(), ConfigError> {
        if value.is_finite() && value >= 0.0 {
            Ok(())
        } else {
            Err(Self::invalid(
                prefix,
                field,
                value,
                "must be finite and >= 0",
            ))
        }
    }

    /// Checks that every component of a point is finite.
    pub fn finite3(prefix: &str, field: &str, value: [f64; 3]) -> Result<(), ConfigError> {
        if value.iter().all(|c| c.is_finite()) {
            Ok(())
        } else {
            Err(Self::invalid(
                prefix,
                field,
                format!("{value:?}"),
                "must be finite",
            ))
        }
    }

    /// Checks that a direction is finite and of non-zero length.
    pub fn direction(prefix: &str, field: &str, value: [f64; 3]) -> Result<(), ConfigError> {
        Self::finite3(prefix, field, value)?;
        let norm2: f64 = value.iter().map(|c| c * c).sum();
        if norm2 > 1e-24 {
            Ok(())
        } else {
            Err(Self::invalid(
                prefix,
                field,
                format!("{value:?}"),
                "must have non-zero length",
            ))
        }
    }
}

/// A malformed trajectory CSV file for [`crate::ReplayDevice`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReplayError {
    /// The file could not be opened or read.
    #[error("cannot read trajectory `{path}`: {message}")]
    Io {
        /// The path given.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// The CSV layer failed (unequal row lengths, invalid UTF-8, ...).
    #[error("line {line}: malformed CSV: {message}")]
    Csv {
        /// 1-based line number (0 when unknown).
        line: u64,
        /// The CSV reader's message.
        message: String,
    },
    /// A required column is absent from the header line.
    #[error(
        "line {line}: missing column `{column}` (header must contain t,x,y,z; found: {found})"
    )]
    MissingColumn {
        /// 1-based line of the header.
        line: u64,
        /// The required column name.
        column: &'static str,
        /// The header as read.
        found: String,
    },
    /// A field is not a number.
    #[error("line {line}: column `{column}` is not a number: {value:?}")]
    NotNumeric {
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: &'static str,
        /// The text found.
        value: String,
    },
    /// A field is NaN or infinite.
    #[error("line {line}: column `{column}` is not finite: {value}")]
    NotFinite {
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: &'static str,
        /// The value parsed.
        value: f64,
    },
    /// Time does not strictly increase from one row to the next.
    #[error("line {line}: time {time} s does not increase (previous row: {previous} s)")]
    NonIncreasingTime {
        /// 1-based line number.
        line: u64,
        /// Time on this line (s).
        time: f64,
        /// Time on the previous data line (s).
        previous: f64,
    },
    /// The file is larger than [`crate::MAX_TRAJECTORY_BYTES`].
    #[error("trajectory larger than {limit} bytes; refused")]
    TooLarge {
        /// The bound (bytes).
        limit: u64,
    },
    /// The file has a header but no data rows.
    #[error("trajectory has no data rows")]
    Empty,
    /// The samples handed to [`crate::ReplayDevice::from_samples`] are inconsistent.
    #[error("invalid trajectory samples: {0}")]
    Samples(&'static str),
    /// The device limits are invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
}

impl From<echothigh_table::TableError> for ReplayError {
    fn from(e: echothigh_table::TableError) -> Self {
        use echothigh_table::TableError as T;
        match e {
            T::Io(message) => ReplayError::Io {
                path: "(reader)".into(),
                message,
            },
            T::TooLarge { limit } => ReplayError::TooLarge { limit },
            T::NoHeader => ReplayError::Empty,
            T::MissingColumn {
                line,
                column,
                found,
            } => ReplayError::MissingColumn {
                line,
                column,
                found,
            },
            T::NotANumber { line, column, text } => ReplayError::NotNumeric {
                line,
                column,
                value: text,
            },
            T::Syntax { line, message } => ReplayError::Csv { line, message },
            T::ShortRow {
                line,
                expected,
                found,
            } => ReplayError::Csv {
                line,
                message: format!("expected {expected} fields, found {found}"),
            },
        }
    }
}
