//! Calibration of the tissue springs to force–indentation data (the paper's
//! parameters "have been fitted to match the real deformation measured on a
//! human thigh", its ref. [4]).

pub mod data;

pub use data::IndentationCurve;
