//! Proxy invariants over random device paths (proptest), friction cones, and
//! consistency with the physics convention `D = −|F|/k`.

use echothigh_haptics::{
    handoff, BufferModel, FitConfig, HapticRenderer, LocalModel, ModelManager, ModelParams,
    ModelPublisher, Plane, RenderConfig, Sample, Sphere, Vec3,
};
use proptest::prelude::*;

const DT: f64 = 1e-3;

fn publish(tx: &mut ModelPublisher, params: ModelParams, k: f64, seq: u64, t: f64) {
    tx.publish(BufferModel {
        params,
        stiffness: k,
        sample_time: t,
        period: 0.01,
        sequence: seq,
    });
}

/// Renderer with safety limits out of the way (the proxy is under test):
/// the widest values the configuration accepts (200 N, 1e12 N/s, 5 s),
/// far beyond what these paths reach (≤ 500 N/m × a few cm ≈ 10 N, 1 s).
fn renderer(mu_s: f64, mu_k: f64, params: ModelParams) -> HapticRenderer {
    let (mut tx, rx) = handoff();
    publish(&mut tx, params, 500.0, 1, 0.0);
    let cfg = RenderConfig {
        static_friction: mu_s,
        kinetic_friction: mu_k,
        max_force: 200.0,
        force_rate_limit: 1e12,
        stale_age: 5.0,
        ..RenderConfig::default()
    };
    HapticRenderer::new(&cfg, rx).unwrap()
}

fn sphere() -> ModelParams {
    ModelParams::Sphere(Sphere {
        center: Vec3::new(0.0, -0.08, 0.0),
        radius: 0.08,
    })
}

fn plane() -> ModelParams {
    ModelParams::Plane(Plane {
        normal: Vec3::new(0.1, 1.0, -0.05).normalize(),
        offset: 0.0,
    })
}

/// Random walk starting 1 cm above the origin, steps up to 1.5 mm per axis.
fn paths() -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
    prop::collection::vec((-1.5e-3..1.5e-3, -1.5e-3..1.2e-3, -1.5e-3..1.5e-3), 50..300)
}

fn check_path(model: ModelParams, mu_s: f64, mu_k: f64, steps: &[(f64, f64, f64)]) {
    let mut r = renderer(mu_s, mu_k, model);
    let mut p = Vec3::new(0.0, 0.01, 0.0);
    for (i, s) in steps.iter().enumerate() {
        p += Vec3::new(s.0, s.1, s.2);
        let f = r.tick(p, i as f64 * DT);
        let out = *r.output();
        let x = out.proxy;
        let eps = 1e-9;
        assert!(
            model.value(&x) >= -eps,
            "proxy inside: φ = {}",
            model.value(&x)
        );
        if model.value(&p) >= 0.0 {
            assert_eq!(x, p, "free proxy must equal the device");
            assert_eq!(f, Vec3::zeros());
        } else {
            assert!(model.value(&x).abs() <= eps, "proxy off the surface");
            let n = model.gradient(&x);
            let fn_ = f.dot(&n);
            let ft = (f - fn_ * n).norm();
            assert!(fn_ >= -1e-9, "force pulls into the surface");
            if mu_s == 0.0 {
                assert!(
                    ft <= 1e-9 * fn_ + 1e-9,
                    "frictionless force not normal: {ft} vs {fn_}"
                );
            } else {
                assert!(
                    ft <= mu_s * fn_ * (1.0 + 1e-6) + 1e-9,
                    "outside static cone: {ft} > {mu_s}·{fn_}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn proxy_invariants_sphere_frictionless(steps in paths()) {
        check_path(sphere(), 0.0, 0.0, &steps);
    }
    #[test]
    fn proxy_invariants_plane_frictionless(steps in paths()) {
        check_path(plane(), 0.0, 0.0, &steps);
    }
    #[test]
    fn proxy_invariants_sphere_friction(steps in paths()) {
        check_path(sphere(), 0.3, 0.2, &steps);
    }
    #[test]
    fn proxy_invariants_plane_friction(steps in paths()) {
        check_path(plane(), 0.4, 0.4, &steps);
    }
}

#[test]
fn friction_sticks_inside_the_static_cone() {
    let mut r = renderer(0.3, 0.2, plane());
    let n = Vec3::new(0.1, 1.0, -0.05).normalize();
    let t1 = n.cross(&Vec3::z()).normalize();
    // Press straight in 10 mm, then move tangentially 2.5 mm (< 0.3 · 10 mm).
    let mut t = 0.0;
    for i in 0..=10 {
        r.tick(n * (0.001 - 0.001 * i as f64), t);
        t += DT;
    }
    let stuck = r.output().proxy;
    for i in 1..=25 {
        r.tick(-n * 0.01 + t1 * (1e-4 * i as f64), t);
        t += DT;
        assert!(
            (r.output().proxy - stuck).norm() < 1e-12,
            "proxy moved while in the cone"
        );
        assert!(!r.output().sliding);
    }
    // Beyond 3 mm it breaks away and trails at the kinetic edge (2 mm).
    r.tick(-n * 0.01 + t1 * 0.005, t);
    let out = *r.output();
    assert!(out.sliding);
    let off = out.proxy - out.device;
    let tangential = (off - off.dot(&n) * n).norm();
    assert!(
        (tangential - 0.002).abs() < 1e-9,
        "kinetic edge: {tangential}"
    );
}

#[test]
fn rendered_force_matches_physics_force_at_the_sample() {
    // Physics: a sphere-shaped thigh, force F = k·depth along the normal;
    // reports D = −|F|/k in contact (DESIGN §2).
    let (c, radius, k) = (Vec3::new(0.0, -0.09, 0.0), 0.09, 650.0);
    let sample_at = |p: Vec3, t: f64| {
        let n = (p - c).normalize();
        let depth = radius - (p - c).norm();
        let force = n * (k * depth.max(0.0));
        let distance = if depth > 0.0 {
            -force.norm() / k
        } else {
            -depth
        };
        (
            Sample {
                time: t,
                p,
                distance,
                gradient: n,
                stiffness: k,
            },
            force,
        )
    };
    let (tx, rx) = handoff();
    let mut manager = ModelManager::new(&FitConfig::default(), tx).unwrap();
    // The physics force here is frictionless (normal), so render without
    // friction: with it the proxy would (rightly) hold a tangential offset
    // from the oblique approach.
    let cfg = RenderConfig {
        static_friction: 0.0,
        kinetic_friction: 0.0,
        ..RenderConfig::default()
    };
    let mut r = HapticRenderer::new(&cfg, rx).unwrap();
    // Approach and press along a slightly oblique line, physics at 100 Hz.
    let dir = Vec3::new(0.02, -1.0, 0.01).normalize();
    let start = Vec3::new(0.0, 0.005, 0.0);
    let mut last_force = Vec3::zeros();
    let mut p = start;
    for i in 0..400 {
        let t = i as f64 * DT;
        if i < 200 {
            p = start + dir * (0.015 * t / 0.2);
        }
        if i % 10 == 0 {
            let (s, f) = sample_at(p, t);
            manager.update(&s);
            last_force = f;
        }
        r.tick(p, t);
    }
    let f = r.output().force;
    assert!(
        last_force.norm() > 5.0,
        "the test must press: {}",
        last_force.norm()
    );
    let rel = (f - last_force).norm() / last_force.norm();
    assert!(
        rel < 0.01,
        "rendered {f:?} vs physics {last_force:?} ({rel})"
    );
}
