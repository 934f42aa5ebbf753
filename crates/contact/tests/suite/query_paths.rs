//! The queries' fast path (issue 18) against the previous implementation
//! and against cold and tight solves, over a press, a hold, a tilted slide
//! and a release on the default mesh:
//!
//! - the warm-started stiffness, the cold one (from `w = 0`) and the fast
//!   path's (some of whose steps check the warm start matrix-free and
//!   assemble nothing) all lie within the solver's propagated bound
//!   `tol |b| |S(w* − 1)|` of a solve to 1e-12 (`crate::stiffness` derives
//!   it: `k(w̃) − k(w*) = (w* − 1)ᵀ S r`, `|r| ≤ tol |b|`);
//! - the grid kept up to date finds exactly the candidates and the surfaces
//!   under the face that a grid rebuilt from scratch finds, and the
//!   physics is bitwise the same on both paths.

use echothigh_contact::{ContactParams, HapticSample};
use echothigh_contact::{
    ContactSet, GridUpdate, LocalStiffness, Probe, ProbeContact, QueryPath, SurfaceGrid,
};
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Steps of the trajectory.
const STEPS: usize = 110;

/// The probe pose at step `i` of 10 ms: from 3 mm above the skin down to
/// 10 mm deep (40 steps), a hold (10), a slide of 15 mm across and 20 mm
/// along the thigh tilting by 0.1 rad (40), then back up to 4 mm above (20).
fn pose(i: usize) -> Isometry3<f64> {
    let top = ModelConfig::default().thigh.semi_axis_y;
    let ramp = |a: f64, b: f64, t: f64| a + (b - a) * t.clamp(0.0, 1.0);
    let i = i as f64;
    let depth = if i < 50.0 {
        ramp(-0.003, 0.010, i / 40.0)
    } else {
        ramp(0.010, -0.004, (i - 90.0) / 20.0)
    };
    let slide = ((i - 50.0) / 40.0).clamp(0.0, 1.0);
    Isometry3::from_parts(
        Translation3::new(0.015 * slide, top - depth, 0.020 * slide),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 0.1 * slide),
    )
}

/// `(k, |S b|, |S(w − 1)|)` of `set` at `model`'s state with `stiffness`.
fn solve(
    model: &mut ThighModel,
    stiffness: &mut LocalStiffness,
    set: &ContactSet,
) -> (f64, f64, f64, u32) {
    let (k, stats) = stiffness.compute(model, &mut set.clone());
    assert!(stats.converged && !stats.indefinite, "{stats:?}");
    let fixed = model.fixed();
    let (mut b2, mut e2) = (0.0, 0.0);
    for (m, (b, w)) in stiffness
        .rhs()
        .iter()
        .zip(stiffness.node_sensitivity())
        .enumerate()
    {
        if fixed[m] {
            continue;
        }
        let one = if *b != Vec3::zeros() {
            set.direction
        } else {
            Vec3::zeros()
        };
        b2 += b.norm_squared();
        e2 += (w - one).norm_squared();
    }
    (k, b2.sqrt(), e2.sqrt(), stats.iterations)
}

#[test]
fn warm_cold_and_fast_stiffness_agree_within_the_solver_bound() {
    let config = ModelConfig::default();
    let tol = config.integrator.stiffness_tol;
    let mut tight_config = config.clone();
    let tight = 1e-12;
    tight_config.integrator.stiffness_tol = tight;
    tight_config.integrator.cg_max_iterations = 5000;
    let mut model = ThighModel::new(&config).unwrap();
    let mut exact_model = ThighModel::new(&tight_config).unwrap();
    let mut exact = LocalStiffness::new(&exact_model);
    // The reference evaluates T w matrix-free: independent of the fast
    // path's A w − C w.
    exact.set_matrix_free(true);
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let (mut warm_iterations, mut cold_iterations, mut checked) = (0, 0, 0);
    let mut unassembled = 0;
    for i in 0..STEPS {
        let step = pc.step(&mut model, &pose(i), 0.01);
        assert!(step.physics.finite);
        let set = pc.stiffness_set().clone();
        if set.springs.is_empty() {
            continue;
        }
        let k_warm = step.sample.stiffness;
        warm_iterations += step.query.stiffness_solve.iterations;
        if step.query.stiffness_unassembled {
            // The skip is PCG's own stop test passed without assembly.
            assert_eq!(step.query.stiffness_solve.iterations, 0, "step {i}");
            unassembled += 1;
        }
        // Cold: a fresh solver (w = 0) on a copy of the state.
        let mut cold_model = model.clone();
        let mut cold = LocalStiffness::new(&cold_model);
        let (k_cold, _, _, it) = solve(&mut cold_model, &mut cold, &set);
        cold_iterations += it;
        // The reference: the same state solved to 1e-12, T w matrix-free.
        exact_model.set_state(model.positions(), model.velocities());
        let (k_exact, b, e, _) = solve(&mut exact_model, &mut exact, &set);
        // |k − k*| ≤ tol |b| |S(w* − 1)| for either solve, and the
        // reference's own error is tight/tol = 1e-7 of that.
        let bound = (tol + tight) * b * e;
        assert!(
            k_exact > 0.0 && bound < 1e-3 * k_exact,
            "step {i}: k* = {k_exact} N/m, bound {bound:e}"
        );
        for (name, k) in [("warm", k_warm), ("cold", k_cold)] {
            assert!(
                (k - k_exact).abs() <= bound,
                "step {i}: {name} k = {k}, exact {k_exact}, |Δk| = {:e} > bound {bound:e}",
                (k - k_exact).abs()
            );
        }
        assert!((k_warm - k_cold).abs() <= 2.0 * bound);
        checked += 1;
    }
    assert!(checked > 90, "only {checked} steps had a stiffness set");
    // The hold and the slow parts of the trajectory skip the assembly (the
    // bound above was checked on those steps too).
    assert!(unassembled > 5, "{unassembled} steps without assembly");
    // Not a timing goal: the warm start must save solver iterations.
    assert!(
        warm_iterations < cold_iterations,
        "warm {warm_iterations} vs cold {cold_iterations} iterations"
    );
}

/// The sample fields that do not depend on `k` agree exactly.
fn same_geometry(a: &HapticSample, b: &HapticSample) -> bool {
    a.p == b.p
        && a.force == b.force
        && a.torque == b.torque
        && a.in_contact == b.in_contact
        && (a.in_contact || (a.distance == b.distance && a.gradient == b.gradient))
}

#[test]
fn fast_and_reference_paths_find_the_same_contact_over_a_press_and_a_slide() {
    let config = ModelConfig::default();
    let mut models = [
        ThighModel::new(&config).unwrap(),
        ThighModel::new(&config).unwrap(),
    ];
    let new = || ProbeContact::new(&models[0], Probe::default(), ContactParams::default());
    let (mut fast, mut reference) = (new().unwrap(), new().unwrap());
    reference.set_query_path(QueryPath::Reference);
    assert_eq!(fast.query_path(), QueryPath::Fast);
    let n = models[0].node_count();
    let mut fresh = SurfaceGrid::new(n, fast.contact().grid().cell_size());
    let (mut kept, mut moved, mut in_contact) = (0, 0, 0);
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for i in 0..STEPS {
        let [m0, m1] = &mut models;
        let a = fast.step(m0, &pose(i), 0.01);
        let b = reference.step(m1, &pose(i), 0.01);
        assert_eq!(m0.positions(), m1.positions(), "step {i}");
        assert!(same_geometry(&a.sample, &b.sample), "step {i}: {a:?} {b:?}");
        assert_eq!(
            fast.contact().sample_surfaces(),
            reference.contact().sample_surfaces(),
            "step {i}"
        );
        // The kept grid's candidates for the probe's body box (2 cm margin)
        // against those of a grid rebuilt from scratch on the same nodes.
        let x = m0.positions();
        fresh.rebuild(x);
        let body = Probe::default().body_box(&pose(i), 0.02);
        fast.contact().grid().query_box(x, &body, &mut got);
        fresh.query_box(x, &body, &mut want);
        assert!(!want.is_empty() && got == want, "step {i}");
        match fast.contact().grid().last_update() {
            GridUpdate::Unchanged => kept += 1,
            GridUpdate::Rebinned => moved += 1,
            // Built at the first step's advance, then kept: the nodes never
            // leave the padded box on this trajectory.
            GridUpdate::Rebuilt => panic!("step {i}: the sample rebuilt the grid"),
        }
        assert_eq!(
            reference.contact().grid().last_update(),
            GridUpdate::Rebuilt
        );
        if a.sample.in_contact {
            in_contact += 1;
            // Each k is within the bound of k*, which the test above finds
            // below 1e-3 k* on this trajectory: the two within 2e-3. (D =
            // −|F·n|/k: the relative gap of D is that of k.)
            let (ka, kb) = (a.sample.stiffness, b.sample.stiffness);
            assert!(
                (ka - kb).abs() <= 2e-3 * kb && ka > 0.0,
                "step {i}: k {ka} vs {kb}"
            );
        }
    }
    assert!(in_contact > 60, "{in_contact} steps in contact");
    assert!(
        kept > 0 && moved > 0,
        "grid updates: {kept} unchanged, {moved} rebinned"
    );
}
