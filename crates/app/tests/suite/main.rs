//! The integration tests of `echothigh-app` as one test binary.
//!
//! Each module was a test binary of its own; together they link the crate
//! once instead of once per file (CI's disk filled while linking ~160 test
//! binaries, stops 30 and 33). Files that install a global allocator or read
//! process-wide state stay binaries of their own in `tests/`. A file added
//! here must be declared below: `suite_lists_every_file` checks it.

mod anatomy_cli;
mod cases_cli;
mod device_run;
mod devices_cli;
mod exam_cli;
mod faults;
mod haply_run;
mod image_site_cli;
mod net;
mod records_cli;
mod report_cli;
mod stall;
mod view_device;

/// Every `.rs` file of this folder is declared above.
#[test]
fn suite_lists_every_file() {
    echothigh_testkit::suite::assert_lists_every_file(env!("CARGO_MANIFEST_DIR"));
}
