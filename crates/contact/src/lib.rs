//! Probe–thigh contact, the haptic queries and the calibration of the tissue
//! springs (d'Aulignac, Balaniuk & Laugier, §2–§3; `DESIGN.md` §2).

#![warn(missing_docs)]

pub mod calibration;
pub mod error;
pub mod grid;
pub mod lm;
pub mod probe;
pub mod surface;

pub use error::{ConfigError, CsvError};
pub use grid::SurfaceGrid;
pub use probe::{OrientedBox, Probe};
pub use surface::{SurfaceDistance, SurfacePoint};
