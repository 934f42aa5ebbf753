//! Typed errors of the imaging crate.
//!
//! Every error names what was wrong and where: a configuration key as
//! `"{prefix}.{field}"` (e.g. `imaging.anatomy.vein_diameter`), a field of the
//! deformation input, or the file being written.

use thiserror::Error;

/// Errors of configuration, per-frame input and PNG output.
#[derive(Debug, Error)]
pub enum ImagingError {
    /// A configuration value outside its valid range.
    #[error("invalid configuration `{key}` = {value}: {reason}")]
    Config {
        /// Full key, e.g. `imaging.columns`.
        key: String,
        /// The offending value, printed.
        value: String,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// A per-frame input (deformation, pressure, time, buffer) that cannot be used.
    #[error("invalid imaging input `{field}`: {reason}")]
    Input {
        /// The offending field, e.g. `deformation.lateral[3]`.
        field: &'static str,
        /// What the field must satisfy.
        reason: &'static str,
    },
    /// A vein state name that is not `healthy`, `acute` or `chronic`.
    #[error("unknown vein state `{0}` (expected healthy, acute or chronic)")]
    VeinState(String),
    /// Writing a PNG failed.
    #[error("cannot write PNG `{path}`: {message}")]
    Png {
        /// The file being written.
        path: String,
        /// The encoder's or the file system's message.
        message: String,
    },
}

impl ImagingError {
    /// An [`ImagingError::Config`] for `"{prefix}.{field}"`.
    pub fn invalid(prefix: &str, field: &str, value: impl ToString, reason: &'static str) -> Self {
        ImagingError::Config {
            key: format!("{prefix}.{field}"),
            value: value.to_string(),
            reason,
        }
    }

    /// Checks that `value` is finite and strictly positive.
    pub fn positive(prefix: &str, field: &str, value: f64) -> Result<(), ImagingError> {
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

    /// Checks that `value` is finite (any sign).
    pub fn finite(prefix: &str, field: &str, value: f64) -> Result<(), ImagingError> {
        if value.is_finite() {
            Ok(())
        } else {
            Err(Self::invalid(prefix, field, value, "must be finite"))
        }
    }

    /// Checks that `value` is finite and non-negative.
    pub fn non_negative(prefix: &str, field: &str, value: f64) -> Result<(), ImagingError> {
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

    /// Checks that `value` lies in `[lo, hi]`.
    pub fn in_range(
        prefix: &str,
        field: &str,
        value: f64,
        lo: f64,
        hi: f64,
        reason: &'static str,
    ) -> Result<(), ImagingError> {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            // Debug keeps 1e308 short (Display writes all 309 digits).
            Err(Self::invalid(prefix, field, format!("{value:?}"), reason))
        }
    }
}
