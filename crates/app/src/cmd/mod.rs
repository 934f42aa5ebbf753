//! Subcommands other than benchmarks.

pub mod calibrate;
pub mod image;
pub mod integrity;
pub mod net;
pub mod run;
