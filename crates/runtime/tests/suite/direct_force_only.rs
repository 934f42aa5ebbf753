//! The real-time `direct` tick's force-only step (issue 18) renders the
//! ground truth unchanged: [`PhysicsSide::step_force`] runs the very stages
//! of [`PhysicsSide::step`] before its haptic queries, and the queries only
//! read the model (their solve has its own scratch), so the two give the
//! same force and the same deformed state, step after step, on the
//! built-in scenario's whole-leg mesh (the lean-male femur, groin to knee,
//! 48 × 27 nodes) with 1 ms steps through a press, a hold and a slide.

use crate::site_probe::probe;
use echothigh_model::Vec3;
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;

#[test]
fn the_force_only_step_is_the_full_step_without_its_queries() {
    let s = Scenario::builtin().unwrap();
    let mut full = PhysicsSide::new(&s).unwrap();
    let mut fast = PhysicsSide::new(&s).unwrap();
    assert_eq!(full.model().node_count(), 48 * 27);
    let h = 1e-3;
    // 0.5 s from 3 mm above the skin to 12 mm in, 0.2 s held, 0.3 s
    // sliding 10 mm along the leg: contact onset, the stiff hold and a
    // moving contact patch.
    let n = 1000;
    let mut peak: f64 = 0.0;
    let mut contact_steps = 0;
    for i in 0..n {
        let t = i as f64 * h;
        let depth = -0.003 + 0.015 * (t / 0.5).min(1.0);
        let slide = 0.010 * ((t - 0.7) / 0.3).clamp(0.0, 1.0);
        let msg = probe(&full, depth, slide);
        let (sample, _) = full.step(&msg, h, t);
        let (force, record) = fast.step_force(&msg, h, t);
        assert_eq!(
            full.model().positions(),
            fast.model().positions(),
            "step {i}: the deformed states parted"
        );
        // The same stages on the same state give the same bits: any
        // difference would mean the queries changed the physics.
        assert_eq!(
            Vec3::from(sample.force),
            force,
            "step {i}: force {:?} with the queries, {force:?} without",
            sample.force
        );
        assert_eq!(record.force, sample.force, "step {i}: the record's force");
        assert_eq!(record.stiffness, 0.0, "step {i}: k is not computed");
        peak = peak.max(force.norm());
        contact_steps += usize::from(force.norm() > 0.0);
    }
    assert_eq!(
        full.model().positions(),
        fast.model().positions(),
        "the deformed states parted"
    );
    assert_eq!(full.model().velocities(), fast.model().velocities());
    // The trajectory must press (a 12 mm press on the thigh is several N).
    assert!(
        peak > 2.0 && contact_steps > 300,
        "peak {peak} N, {contact_steps} steps in contact"
    );
    let last = fast.last_sample().unwrap();
    assert!(last.in_contact && last.distance == f64::INFINITY);
}
