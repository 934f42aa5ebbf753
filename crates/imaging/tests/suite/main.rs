//! The integration tests of `echothigh-imaging` as one test binary.
//!
//! Each module was a test binary of its own; together they link the crate
//! once instead of once per file (CI's disk filled while linking ~160 test
//! binaries, stops 30 and 33). Files that install a global allocator or read
//! process-wide state stay binaries of their own in `tests/`. A file added
//! here must be declared below: `suite_lists_every_file` checks it.

mod artery_cue;
mod beam;
mod column_attenuation;
#[path = "../common/mod.rs"]
mod common;
mod config;
mod contrast;
mod cyst;
mod femur_depth;
mod lumen;
mod pan;
mod section_structures;
mod speckle_psf;
mod specular;
mod target_band;
mod texture;
mod thrombus_shape;
mod tracking;
mod vein_condition;
mod vessel_shape;

/// Every `.rs` file of this folder is declared above.
#[test]
fn suite_lists_every_file() {
    echothigh_testkit::suite::assert_lists_every_file(env!("CARGO_MANIFEST_DIR"));
}
