//! Errors of the Doppler crate: every one names the offending key or input.

use thiserror::Error;

/// An invalid Doppler setting or input.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DopplerError {
    /// A setting outside its accepted range.
    #[error("{key} = {value}: {reason}")]
    Invalid {
        /// The key, e.g. `doppler.pw.prf`.
        key: String,
        /// The value given, as text.
        value: String,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A buffer of the wrong size handed to a frame or line routine.
    #[error("{what}: expected {expected} elements, got {got}")]
    Size {
        /// Which buffer.
        what: &'static str,
        /// Its required length.
        expected: usize,
        /// Its length.
        got: usize,
    },
}

impl DopplerError {
    /// Checks that `value` is finite and in `[lo, hi]`, naming `"{prefix}.{field}"`.
    pub fn in_range(
        prefix: &str,
        field: &str,
        value: f64,
        lo: f64,
        hi: f64,
        reason: &'static str,
    ) -> Result<(), DopplerError> {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            Err(DopplerError::Invalid {
                key: format!("{prefix}.{field}"),
                value: value.to_string(),
                reason,
            })
        }
    }

    /// Checks a buffer's length.
    pub fn size(what: &'static str, expected: usize, got: usize) -> Result<(), DopplerError> {
        if expected == got {
            Ok(())
        } else {
            Err(DopplerError::Size {
                what,
                expected,
                got,
            })
        }
    }
}
