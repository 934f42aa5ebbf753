//! Subcommands other than benchmarks.

pub mod calibrate;
pub mod devices;
pub mod image;
pub mod net;
pub mod run;
