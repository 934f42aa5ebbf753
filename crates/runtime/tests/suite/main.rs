//! The integration tests of `echothigh-runtime` as one test binary.
//!
//! Each module was a test binary of its own; together they link the crate
//! once instead of once per file (CI's disk filled while linking ~160 test
//! binaries, stops 30 and 33). Files that install a global allocator or read
//! process-wide state stay binaries of their own in `tests/`, and so do the
//! live systems' (`live_*.rs`, `client_startup.rs`): their loops run on real
//! threads at real rates, and run as a binary of their own they share the
//! two cores only with their own file's tests, as the rates they check
//! assume (in one binary, `live_imaging`'s hurried frames fell from ≈ 80 to
//! 30 in 2 s beside another file's frame-rendering test). A file added
//! here must be declared below: `suite_lists_every_file` checks it.

mod case_compression;
mod case_images;
mod chronic_image;
mod coaptation_along_leg;
mod direct_force_only;
mod direct_window;
mod exam_run;
mod exam_site;
mod hold_ramp;
mod image_physics;
mod newton_contact_cycle;
mod one_tick;
mod patient_forces;
mod patient_scale;
mod runtime;
mod scenario_fuzz;
mod scenario_ranges;
mod section_follow;
mod sections_everywhere;
mod site_probe;
mod slide;
mod tail_motion;

/// Every `.rs` file of this folder is declared above.
#[test]
fn suite_lists_every_file() {
    echothigh_testkit::suite::assert_lists_every_file(env!("CARGO_MANIFEST_DIR"));
}
