//! A case in the live system (issue 13): `isolated-fv-mid-acute` (lean
//! male, acute occlusive thrombus in the FV over s = 170–230 mm) loaded into
//! the running system, the probe pressed over the FV to the default exam
//! force (10 N, `scenarios/default.toml` `[exam]`) 1 cm inside the segment
//! and 1 cm outside it: the imaging thread's reading of the section under
//! the probe (`LiveStatus::section`) gives the vein open inside (> 60 % of
//! rest, issue 13's occlusive criterion) and coapted outside (< 10 %, its
//! healthy one, the walls met). Real threads on the real clock: only
//! states are asserted, each wait bounded generously (120 s) so a loaded
//! machine slows the test, not fails it.

use echothigh_anatomy::StructureId;
use echothigh_cases::builtin;
use echothigh_runtime::live::{LiveCommand, LiveControl, LiveSnapshot, SectionReading};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::time::{Duration, Instant};

/// The default exam force (N).
const EXAM_FORCE: f64 = 10.0;

/// How far from the target `s` the drawn section may be (m). The imaging
/// thread rebuilds the section only once the probe has moved more than its
/// threshold from it (`section_follow.rs`), and pressing moves the probe's
/// contact a little along the leg: a section 1.2 mm from the target was
/// seen here, and a 1 mm bound never met. Within 3 mm of a target 1 cm
/// inside (outside) a segment whose ends blend over 4 mm, the cut is still
/// ≥ 3 mm clear of the blend: the full thrombus (no thrombus) state there
/// is the one the test means.
const SECTION_TOLERANCE: f64 = 3e-3;

fn snapshot(system: &LiveSystem) -> LiveSnapshot {
    let mut snap = LiveSnapshot::default();
    system.snapshot(&mut snap);
    snap
}

fn wait_for<T>(what: &str, mut done: impl FnMut() -> Option<T>) -> T {
    let start = Instant::now();
    loop {
        if let Some(t) = done() {
            return t;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "timed out: {what}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Presses the probe over the FV at `s` (m) until the physics' contact
/// force reaches the exam force, and returns the reading of a section drawn
/// within [`SECTION_TOLERANCE`] of `s` from a frame of a physics state after the press
/// settled (the force within 10 % of the exam force for that frame's time).
fn press_over(system: &LiveSystem, case: &echothigh_cases::Case, s: f64) -> SectionReading {
    let pose = case.anatomy.pose_over(s, StructureId::Fv).unwrap();
    let centre_s = Scenario::builtin().unwrap().thigh.centre_s;
    // The page's placement: theta = −θ_leg, z = centre_s − s.
    let (theta, z) = (-pose.theta, centre_s - s);
    let place = |depth: f64| {
        system
            .command(LiveCommand::Probe {
                theta,
                z,
                depth,
                tilt: 0.0,
            })
            .unwrap()
    };
    place(0.0);
    std::thread::sleep(Duration::from_millis(300));
    // Press in 0.5 mm steps (the page's own wheel step) until 10 N.
    let mut depth = 0.0;
    let force = |sys: &LiveSystem| {
        let f = snapshot(sys).status.physics_force;
        (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
    };
    loop {
        place(depth);
        std::thread::sleep(Duration::from_millis(150));
        let f = wait_for("the physics to publish", || Some(force(system)));
        if f >= EXAM_FORCE {
            break;
        }
        depth += 5e-4;
        assert!(depth <= 0.035, "10 N not reached by 35 mm at s = {s}");
    }
    let pressed_at = snapshot(system).status.time;
    wait_for("a reading of the pressed section", || {
        let snap = snapshot(system);
        let f = force(system);
        snap.status.section.filter(|r| {
            r.time > pressed_at
                && (r.s - s).abs() < SECTION_TOLERANCE
                && (f - EXAM_FORCE).abs() < 0.1 * EXAM_FORCE
        })
    })
}

#[test]
fn the_live_vein_stays_open_inside_the_segment_and_coapts_outside() {
    let case = builtin("isolated-fv-mid-acute").unwrap();
    let system = LiveSystem::start_with_case(Scenario::builtin().unwrap(), Some(&case)).unwrap();
    assert_eq!(system.case_name().as_deref(), Some("isolated-fv-mid-acute"));
    system.page_opened();

    let inside = press_over(&system, &case, 0.180);
    eprintln!("1 cm inside: {inside:?}");
    system.command(LiveCommand::Lift).unwrap();
    let outside = press_over(&system, &case, 0.160);
    eprintln!("1 cm outside: {outside:?}");

    assert_eq!(inside.vein, Some(StructureId::Fv));
    assert_eq!(outside.vein, Some(StructureId::Fv));
    // Issue 13: an occlusive segment keeps > 60 % of its lumen, a healthy
    // one coapts (< 10 %).
    assert!(inside.vein_lumen_ratio > 0.60, "inside: {inside:?}");
    assert!(!inside.walls_met);
    assert!(outside.vein_lumen_ratio < 0.10, "outside: {outside:?}");
    assert!(outside.walls_met);

    // Clearing the case restores the scenario's healthy leg: the same
    // place inside the former segment now coapts.
    system.set_case(None).unwrap();
    assert_eq!(system.case_name(), None);
    let cleared = press_over(&system, &case, 0.180);
    eprintln!("cleared, at 180 mm: {cleared:?}");
    assert!(cleared.walls_met, "cleared: {cleared:?}");

    let snap = snapshot(&system);
    assert_eq!(snap.fault, None);
    system.shutdown().unwrap();
}
