//! Calibration of the tissue springs to force–indentation data (the paper's
//! parameters "have been fitted to match the real deformation measured on a
//! human thigh", its ref. [4]).

pub mod data;
pub mod fit;
pub mod indentation;

pub use data::IndentationCurve;
pub use fit::{calibrate, Calibration, CalibrationReport, FitParameter};
pub use indentation::Indentation;

use crate::error::ConfigError;
use thiserror::Error;

/// Failure of an indentation experiment or a calibration.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CalibrationError {
    /// The model configuration is invalid (the message names the key).
    #[error("model configuration: {0}")]
    Model(String),
    /// The probe or contact configuration is invalid.
    #[error(transparent)]
    Contact(#[from] ConfigError),
    /// No surface lies under the probe at the indentation site.
    #[error("no thigh surface under the probe at the indentation site")]
    NoSurface,
    /// The simulation produced a non-finite state.
    #[error("the simulation diverged at depth {depth} m")]
    Diverged {
        /// Depth reached, m.
        depth: f64,
    },
    /// The fitter failed.
    #[error("fit failed: {0}")]
    Fit(String),
}
