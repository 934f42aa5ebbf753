//! Subcommands other than benchmarks.

pub mod anatomy;
pub mod calibrate;
pub mod calibrate_device;
pub mod cases;
pub mod device_arg;
pub mod devices;
pub mod doppler;
pub mod doppler_color;
pub mod exam;
#[cfg(feature = "viewer")]
pub mod exam_live;
pub mod image;
pub mod image_site;
#[cfg(feature = "viewer")]
pub mod live_device;
pub mod net;
pub mod psf;
pub mod records;
pub mod report;
pub mod run;
#[cfg(feature = "viewer")]
pub mod view;
