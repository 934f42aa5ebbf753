//! Probe–thigh contact, the haptic queries and the calibration of the tissue
//! springs (d'Aulignac, Balaniuk & Laugier, §2–§3; `DESIGN.md` §2).
//!
//! - [`Probe`]: the rigid box (face `y = 0`, body towards `+y`, `k̂ = −y`).
//! - [`SurfaceGrid`]: the broad phase (uniform grid, kept up to date per step).
//! - [`PenaltyContact`]: Eq. 2 as a [`echothigh_model::ForceModel`], the
//!   penetrated volume measured by sampling the face.
//! - [`ProbeContact`]: one physics step with the probe and the queries sent
//!   to the haptic side, [`HapticSample`] (`D`, `∇D`, `k`, force, torque).
//! - [`calibration`]: the indentation experiment, the CSV reader and the
//!   Levenberg–Marquardt fit ([`lm`]) of the tissue springs.
//!
//! ```no_run
//! use echothigh_contact::{ContactParams, Probe, ProbeContact};
//! use echothigh_model::{ModelConfig, ThighModel, Vec3};
//! let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
//! let mut contact = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
//! let pose = Probe::exam_pose(Vec3::new(0.0, 0.072 - 0.005, 0.0)); // 5 mm deep
//! let step = contact.step(&mut model, &pose, 0.01);
//! println!("F = {} N, k = {} N/m, D = {} m", step.sample.force.norm(), step.sample.stiffness, step.sample.distance);
//! ```

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

pub use driver::{ContactStep, HapticSample, ProbeContact, QueryPath, QueryStats};
pub use error::{ConfigError, CsvError};
pub use grid::{GridUpdate, SurfaceGrid};
pub use params::ContactParams;
pub use penalty::{PenaltyContact, SampleContact, SampleSurface, Wrench};
pub use probe::{OrientedBox, Probe};
pub use stiffness::{ContactSet, ContactSpring, LocalStiffness};
pub use surface::{Adjacency, SurfaceDistance, SurfacePoint};
