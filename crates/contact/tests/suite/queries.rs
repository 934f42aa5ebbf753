//! The haptic queries against finite differences and physics (issue 3):
//! `∇D` against central differences of `D`; `k` against finite differences
//! of the quasi-static contact force; stability of a stiff contact.

use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn top_pose(depth: f64) -> Isometry3<f64> {
    let top = ModelConfig::default().thigh.semi_axis_y;
    Probe::exam_pose(Vec3::new(0.0, top - depth, 0.0))
}

#[test]
fn distance_gradient_matches_central_differences() {
    let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let g = model.config().thigh.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut tested = 0;
    for _ in 0..16 {
        let theta = std::f64::consts::FRAC_PI_2 + rng.gen_range(-0.6..0.6);
        let z = rng.gen_range(-0.1..0.1);
        let e = rng.gen_range(0.002..0.02);
        let s = g.surface_point(theta, z);
        let n = g.surface_normal(theta);
        let p = Vec3::new(s[0], s[1], s[2]) + e * Vec3::new(n[0], n[1], n[2]);
        let rot = UnitQuaternion::from_euler_angles(
            rng.gen_range(-0.3..0.3),
            0.0,
            theta - std::f64::consts::FRAC_PI_2 + rng.gen_range(-0.3..0.3),
        );
        let mut d_at = |q: Vec3| {
            let pose = Isometry3::from_parts(Translation3::from(q), rot);
            pc.contact_mut().set_probe(pose, Vec3::zeros());
            pc.sample(&mut model).0
        };
        let s0 = d_at(p);
        if s0.in_contact {
            continue; // a tilted corner touches: D is the force-based one
        }
        // The facets lie inside the smooth ellipse by at most their sagitta.
        assert!(
            s0.distance > 0.0 && s0.distance <= e + 5e-4,
            "D {} e {e}",
            s0.distance
        );
        assert!((s0.gradient.norm() - 1.0).abs() < 1e-12);
        let h = 1e-6;
        let mut fd = Vec3::zeros();
        for i in 0..3 {
            let mut dp = Vec3::zeros();
            dp[i] = h;
            fd[i] = (d_at(p + dp).distance - d_at(p - dp).distance) / (2.0 * h);
        }
        let err = (fd - s0.gradient).norm() / s0.gradient.norm();
        assert!(
            err < 1e-4,
            "pose {p:?}: ∇D {:?} vs FD {fd:?} (rel. err {err:e})",
            s0.gradient
        );
        tested += 1;
    }
    assert!(tested >= 12, "only {tested} poses out of contact");
}

/// Quasi-static normal force on the probe at `depth` below first touch (N),
/// with the sample there.
fn settled(
    pc: &mut ProbeContact,
    model: &mut ThighModel,
    depth: f64,
) -> echothigh_contact::HapticSample {
    let (_, step) = pc.settle(model, &top_pose(depth), 0.05, 400, 1e-8);
    assert!(step.physics.finite);
    step.sample
}

#[test]
fn stiffness_matches_finite_differences_of_quasi_static_force() {
    let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let eps = 1e-4;
    let mut last_k = 0.0;
    for depth in [0.003, 0.006, 0.009] {
        let f_minus = settled(&mut pc, &mut model, depth - eps).force.y;
        let f_plus = settled(&mut pc, &mut model, depth + eps).force.y;
        let s = settled(&mut pc, &mut model, depth);
        assert!(s.in_contact);
        let k_fd = (f_plus - f_minus) / (2.0 * eps);
        let rel = (s.stiffness - k_fd).abs() / k_fd;
        assert!(
            rel < 0.05,
            "depth {depth}: k {} vs FD {k_fd} ({rel:.3})",
            s.stiffness
        );
        assert!(
            s.stiffness > last_k,
            "k must grow with depth: {} after {last_k}",
            s.stiffness
        );
        last_k = s.stiffness;
        // The distance sent makes the first-order model exact at the sample.
        assert!(
            (-s.distance * s.stiffness - s.force.norm()).abs() < 1e-9 * s.force.norm().max(1.0)
        );
        assert!((s.gradient - Vec3::y()).norm() < 1e-12);
        // Symmetric press on the symmetric thigh: no torque about x or y
        // beyond the mesh's own asymmetry.
        assert!(
            s.torque.norm() < 0.02 * s.force.norm() * 0.02,
            "torque {:?}",
            s.torque
        );
    }
}

#[test]
fn stiff_contact_is_stable_at_the_default_step() {
    let config = ModelConfig::default();
    let h = config.integrator.time_step;
    // λ_c per unit area against the tissue's initial stiffness per unit area.
    let tissue = 1.0 / config.tissue.normal_b;
    for factor in [100.0, 1000.0] {
        let mut model = ThighModel::new(&config).unwrap();
        let params = ContactParams {
            stiffness: factor * tissue,
            ..ContactParams::default()
        };
        let mut pc = ProbeContact::new(&model, Probe::default(), params).unwrap();
        let mut hold_energy = None;
        for i in 1..=100 {
            let depth = 0.010 * (i as f64 / 50.0).min(1.0);
            let step = pc.step(&mut model, &top_pose(depth), h);
            let e = model.energy().total();
            assert!(
                step.physics.finite && e.is_finite(),
                "λ_c = {factor}× at step {i}"
            );
            assert!(
                step.sample.force.iter().all(|f| f.is_finite()) && step.sample.force.norm() < 100.0
            );
            if i == 55 {
                hold_energy = Some(e);
            }
            if let Some(e0) = hold_energy {
                assert!(
                    e <= 1.05 * e0 + 1e-6,
                    "energy grows while holding: {e} > {e0}"
                );
            }
        }
        let vmax = model
            .velocities()
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        assert!(vmax < 1e-3, "still moving after the hold: {vmax} m/s");
    }
}
