//! The 3D anatomy of echothigh (issue 12): a right leg from the inguinal
//! ligament to just below the knee, with its vessel tree, bones and
//! landmarks, built for one patient, and the section of it under a probe.
//!
//! - [`frame`]: the leg frame (x lateral, y anterior, z proximal; `s = −z`
//!   below the inguinal ligament, θ from the anterior line towards medial).
//! - [`Patient`]: the TOML patient description and its presets.
//! - [`LegShape`]: the skin (tapered elliptic generalized cylinder, popliteal fossa).
//! - [`Tube`], [`Ellipsoid`]: the structures (vessels as centrelines with
//!   radius profiles, femur, tibia, sartorius; the lymph node).
//! - [`Anatomy`]: queries — skin point and normal, inside-the-leg, depth of
//!   the femur along a ray, the image plane of a probe pose, the section
//!   (ellipses in image coordinates), the exam sites.
//! - [`ThrombusSpec`], [`Thrombi`], [`LumenState`]: thrombus segments on
//!   named veins (issue 13) and the state of a vein's lumen at one `s`.
//!
//! Units are SI (m, rad). Every anatomical number cites its source where it
//! is defined (`patient.rs`, `levels.rs`, `vessels.rs`, `leg.rs`), or is
//! marked "(estimate)" or "(derived)". The crate does no I/O: the app reads
//! patient files and passes their text to [`Patient::from_toml_str`].
//!
//! ```
//! use echothigh_anatomy::{Anatomy, Patient, Site, StructureId};
//! let anatomy = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
//! let section = anatomy.section(&anatomy.site_pose(Site::FvMid)).unwrap();
//! let (fv, fa) = (section.get(StructureId::Fv).unwrap(), section.get(StructureId::Fa).unwrap());
//! assert!(fv.ellipse.depth > fa.ellipse.depth); // the vein lies deep to the artery at mid-thigh
//! ```
#![warn(missing_docs)]

pub mod anatomy;
pub mod cut;
pub mod error;
pub mod frame;
pub mod interp;
pub mod leg;
pub mod levels;
pub mod lumen_state;
pub mod patient;
pub mod section;
pub mod structure;
pub mod tables;
pub mod thrombus;
pub mod vessels;

pub use anatomy::{cut_tube, Anatomy};
pub use cut::Ellipse;
pub use error::AnatomyError;
pub use frame::Vec3;
pub use leg::LegShape;
pub use levels::{LegLevel, Levels};
pub use lumen_state::{tail_sway, Layout, LumenState, Thrombi, TruthPiece, VeinTruth};
pub use patient::{Patient, Sex, PRESETS};
pub use section::{ImagePlane, ProbePose, Section, SectionStructure, Site};
pub use structure::{CrossSection, Ellipsoid, Kind, StructureId, Tube};
pub use thrombus::{Thrombus, ThrombusKind, ThrombusSpec};
