//! Subcommands other than benchmarks.

pub mod calibrate;
pub mod image;
