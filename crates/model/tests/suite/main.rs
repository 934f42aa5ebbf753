//! The integration tests of `echothigh-model` as one test binary.
//!
//! Each module was a test binary of its own; together they link the crate
//! once instead of once per file (CI's disk filled while linking ~160 test
//! binaries, stops 30 and 33). Files that install a global allocator or read
//! process-wide state stay binaries of their own in `tests/`. A file added
//! here must be declared below: `suite_lists_every_file` checks it.

#[path = "../common/mod.rs"]
mod common;
mod concentrated_load;
mod config;
mod edge_form;
mod equilibrium;
mod integrator;
mod leg;
mod mesh;
mod pcg;
mod properties;
mod simd_kernels;
mod springs;
mod unassembled_start;
mod window;

/// Every `.rs` file of this folder is declared above.
#[test]
fn suite_lists_every_file() {
    echothigh_testkit::suite::assert_lists_every_file(env!("CARGO_MANIFEST_DIR"));
}
