//! Probe–thigh contact, the haptic queries and the calibration of the tissue
//! springs (d'Aulignac, Balaniuk & Laugier, §2–§3; `DESIGN.md` §2).

#![warn(missing_docs)]

pub mod calibration;
pub mod driver;
pub mod error;
pub mod grid;
pub mod lm;
pub mod params;
pub mod penalty;
pub mod probe;
pub mod stiffness;
pub mod surface;

pub use driver::{ContactStep, HapticSample, ProbeContact, QueryStats};
pub use error::{ConfigError, CsvError};
pub use grid::SurfaceGrid;
pub use params::ContactParams;
pub use penalty::{PenaltyContact, SampleContact, SampleSurface, Wrench};
pub use probe::{OrientedBox, Probe};
pub use stiffness::{ContactSet, ContactSpring, LocalStiffness};
pub use surface::{Adjacency, SurfaceDistance, SurfacePoint};
