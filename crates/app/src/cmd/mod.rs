//! Subcommands other than benchmarks.

pub mod calibrate;
pub mod image;
pub mod net;
pub mod psf;
pub mod run;
