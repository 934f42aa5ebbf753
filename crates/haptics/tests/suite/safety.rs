//! Force shading across a model step, stale fade, clamp, faults, config.

use echothigh_haptics::{
    flags, handoff, BufferModel, HapticRenderer, HapticsConfig, LocalModel, ModelParams,
    ModelPublisher, Plane, RenderConfig, Vec3,
};

const DT: f64 = 1e-3;

fn plane(normal: Vec3, offset: f64) -> ModelParams {
    ModelParams::Plane(Plane {
        normal: normal.normalize(),
        offset,
    })
}

fn publish(tx: &mut ModelPublisher, params: ModelParams, k: f64, seq: u64) {
    tx.publish(BufferModel {
        params,
        stiffness: k,
        sample_time: seq as f64 * 0.01,
        period: 0.01,
        sequence: seq,
    });
}

fn frictionless(rate: f64, shading: bool) -> RenderConfig {
    RenderConfig {
        static_friction: 0.0,
        kinetic_friction: 0.0,
        force_rate_limit: rate,
        shading,
        ..RenderConfig::default()
    }
}

/// Holds the device at `p` against model A until settled, then publishes B;
/// returns per-tick forces after the switch, the tick of the switch, and
/// the static forces of A and B.
fn step_run(cfg: &RenderConfig) -> (Vec<Vec3>, Vec3, Vec3) {
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(cfg, rx).unwrap();
    let a = plane(Vec3::y(), 0.0);
    let b = plane(Vec3::new(0.3, 1.0, 0.0), 0.004);
    let p = Vec3::new(0.0, -0.01, 0.0);
    publish(&mut tx, a, 500.0, 1);
    let mut t = 0.0;
    r.tick(Vec3::new(0.0, 0.01, 0.0), t);
    for _ in 0..40 {
        t += DT;
        r.tick(p, t);
    }
    let fa = -a.gradient(&p) * a.value(&p) * 500.0;
    assert!((r.output().force - fa).norm() < 1e-9, "settled on A");
    publish(&mut tx, b, 800.0, 2);
    let mut forces = vec![r.output().force];
    for _ in 0..30 {
        t += DT;
        forces.push(r.tick(p, t));
    }
    let fb = -b.gradient(&p) * b.value(&p) * 800.0;
    (forces, fa, fb)
}

fn largest_step(forces: &[Vec3]) -> f64 {
    forces
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .fold(0.0, f64::max)
}

#[test]
fn shading_bounds_the_step_and_converges_within_one_period() {
    let cfg = frictionless(2000.0, true);
    let (forces, fa, fb) = step_run(&cfg);
    assert!((fb - fa).norm() > 5.0, "a real step: {}", (fb - fa).norm());
    assert!(largest_step(&forces) <= 2000.0 * DT + 1e-9);
    // One physics period = 10 ticks after the model arrived (tick 1).
    for f in &forces[11..] {
        assert!((f - fb).norm() < 1e-9, "not converged: {f:?} vs {fb:?}");
    }
}

#[test]
fn shading_alone_spreads_the_step_over_the_period() {
    let (shaded, fa, fb) = step_run(&frictionless(1e12, true));
    let (unshaded, _, _) = step_run(&frictionless(1e12, false));
    let jump = (fb - fa).norm();
    assert!(
        (largest_step(&unshaded) - jump).abs() < 1e-9,
        "no shading: one jump"
    );
    assert!(
        largest_step(&shaded) < 0.2 * jump,
        "shaded step {} vs jump {jump}",
        largest_step(&shaded)
    );
    assert!((shaded[11] - fb).norm() < 1e-9);
}

#[test]
fn stale_model_is_released_at_the_ramp_rate_and_re_enters_from_zero() {
    let cfg = RenderConfig {
        stale_age: 0.05,
        fade_time: 0.08,
        ..frictionless(2000.0, true)
    };
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&cfg, rx).unwrap();
    publish(&mut tx, plane(Vec3::y(), 0.0), 1000.0, 1);
    let p = Vec3::new(0.0, -0.01, 0.0);
    r.tick(Vec3::new(0.0, 0.001, 0.0), 0.0);
    let mut prev = f64::INFINITY;
    for i in 1..=200 {
        let t = i as f64 * DT;
        let f = r.tick(p, t).norm();
        if t > 0.02 && t <= 0.05 {
            assert!((f - 10.0).abs() < 1e-9, "full force before stale_age");
        }
        if t > 0.05 {
            assert!(f <= prev + 1e-12, "fade is monotone");
            assert!(r.output().flags & flags::STALE != 0);
        }
        if t >= 0.05 + 0.08 - 1e-12 {
            assert_eq!(f, 0.0, "faded out at t = {t}");
        }
        prev = f;
    }
    assert!(r.faded_to_zero());
    // A new model restores the force through the ramp from zero at
    // max_force / fade_time = 20 N / 0.08 s = 250 N/s, 0.25 N per tick: the
    // 10 N come back in 40 ticks, not in the 5 the 2000 N/s limit allows.
    let mut prev = 0.0;
    for i in 201..=260 {
        if i % 10 == 1 {
            // The physics is back at 100 Hz.
            publish(&mut tx, plane(Vec3::y(), 0.0), 1000.0, i as u64);
        }
        let f = r.tick(p, i as f64 * DT).norm();
        assert!(f - prev <= 0.25 + 1e-9, "tick {i}: {prev} → {f}");
        if i <= 239 {
            assert!(f < 10.0 - 1e-9, "tick {i}: back too fast ({f} N)");
        }
        prev = f;
    }
    assert!((r.output().force.norm() - 10.0).abs() < 1e-9);
}

#[test]
fn clamp_and_non_finite_inputs_never_leak() {
    let cfg = RenderConfig {
        max_force: 5.0,
        ..frictionless(1e12, true)
    };
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&cfg, rx).unwrap();
    // No model yet: zero force, proxy on the device.
    assert_eq!(r.tick(Vec3::new(0.0, -0.01, 0.0), 0.0), Vec3::zeros());
    assert!(r.output().flags & flags::NO_MODEL != 0);
    publish(&mut tx, plane(Vec3::y(), 0.0), 1000.0, 1);
    r.tick(Vec3::new(0.0, 0.01, 0.0), 0.001);
    let f = r.tick(Vec3::new(0.0, -0.05, 0.0), 0.002);
    assert!((f.norm() - 5.0).abs() < 1e-12 && r.output().flags & flags::CLAMPED != 0);
    // NaN device position or time: zero force and a fault flag.
    for (p, t) in [
        (Vec3::new(f64::NAN, 0.0, 0.0), 0.003),
        (Vec3::new(0.0, f64::INFINITY, 0.0), 0.003),
        (Vec3::new(0.0, -0.01, 0.0), f64::NAN),
    ] {
        assert_eq!(r.tick(p, t), Vec3::zeros());
        assert!(r.output().flags & flags::FAULT_INPUT != 0);
    }
    // A non-finite model is ignored (fault flag), the old one kept.
    tx.publish(BufferModel {
        params: plane(Vec3::y(), f64::NAN),
        stiffness: 1000.0,
        sample_time: 0.02,
        period: 0.01,
        sequence: 2,
    });
    // After the faults the force re-enters through the ramp from zero:
    // max_force / fade_time = 5 N / 0.1 s = 50 N/s, 0.05 N per 1 ms tick.
    let f = r.tick(Vec3::new(0.0, -0.003, 0.0), 0.004);
    assert!(r.output().flags & flags::FAULT_MODEL != 0);
    assert_eq!(r.output().model_sequence, 1);
    assert!((f - Vec3::new(0.0, 0.05, 0.0)).norm() < 1e-9, "{f:?}");
    let mut t = 0.004;
    for _ in 0..70 {
        t += DT;
        r.tick(Vec3::new(0.0, -0.003, 0.0), t);
    }
    assert!((r.output().force - Vec3::new(0.0, 3.0, 0.0)).norm() < 1e-9);
}

#[test]
fn config_parses_validates_and_names_keys() {
    let text = r#"
        [fit]
        model = "plane"
        window = 4
        [render]
        max_force = 12.0
        [loop]
        rate_hz = 2000.0
    "#;
    let cfg: HapticsConfig = toml::from_str(text).unwrap();
    assert!(cfg.validate("haptics").is_ok());
    assert_eq!(cfg.fit.window, 4);
    assert_eq!(cfg.runner.rate_hz, 2000.0);
    assert!(toml::from_str::<HapticsConfig>("[render]\nmax_forse = 1.0").is_err());
    let mut bad = cfg.clone();
    bad.fit.forgetting = 1.5;
    let e = bad.validate("haptics").unwrap_err().to_string();
    assert!(e.starts_with("haptics.fit.forgetting"), "{e}");
    let mut bad = cfg.clone();
    bad.render.kinetic_friction = 0.5;
    let e = bad.validate("haptics").unwrap_err().to_string();
    assert!(e.starts_with("haptics.render.kinetic_friction"), "{e}");
    let mut bad = cfg;
    bad.render.max_force = f64::NAN;
    let e = bad.validate("haptics").unwrap_err().to_string();
    assert!(e.starts_with("haptics.render.max_force"), "{e}");
    let d = HapticsConfig::default();
    assert!(d.validate("haptics").is_ok());
    assert_eq!((d.fit.window, d.fit.forgetting), (8, 0.7));
}

/// Lift-off: successive fits on either side of a device that is outside
/// both (spheres whose centres are offset sideways, as fits of a surface
/// springing back under a receding probe). A blend of their parameters
/// would bulge 10 mm over the device; shading the constraint functions must
/// render no force at any tick, across an early arrival as well.
#[test]
fn shading_never_renders_contact_outside_both_models() {
    use echothigh_haptics::Sphere;
    let sphere = |x: f64| {
        ModelParams::Sphere(Sphere {
            center: Vec3::new(x, 0.0, 0.0),
            radius: 0.07,
        })
    };
    let (a, b, c) = (sphere(0.05), sphere(-0.05), sphere(0.04));
    let p = Vec3::new(0.0, 0.06, 0.0);
    assert!(a.value(&p) > 0.0 && b.value(&p) > 0.0 && c.value(&p) > 0.0);
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&frictionless(1e6, true), rx).unwrap();
    publish(&mut tx, a, 1000.0, 1);
    let mut t = 0.0;
    for i in 0..40 {
        match i {
            5 => publish(&mut tx, b, 1000.0, 2),
            // 6 ticks into a 10-tick blend: an early arrival.
            11 => publish(&mut tx, c, 1000.0, 3),
            14 => publish(&mut tx, a, 1000.0, 4),
            _ => {}
        }
        let f = r.tick(p, t);
        assert_eq!(
            f,
            Vec3::zeros(),
            "tick {i}: contact rendered outside every model"
        );
        assert!(!r.output().in_contact);
        t += DT;
    }
}

/// A model stiffer than the device's stable limit is rendered at the limit
/// (and flagged); a softer one is untouched; a limit ≤ 0 or NaN is refused.
#[test]
fn stiffness_is_limited_to_the_device() {
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&frictionless(1e9, false), rx).unwrap();
    assert!(r.set_max_stiffness(0.0).is_err());
    assert!(r.set_max_stiffness(f64::NAN).is_err());
    r.set_max_stiffness(3000.0).unwrap();
    let p = Vec3::new(0.0, -0.005, 0.0);
    publish(&mut tx, plane(Vec3::y(), 0.0), 10_000.0, 1);
    r.tick(Vec3::new(0.0, 0.01, 0.0), 0.0);
    let f = r.tick(p, DT);
    assert!((f - Vec3::new(0.0, 15.0, 0.0)).norm() < 1e-9, "{f:?}");
    assert_eq!(r.output().stiffness, 3000.0);
    assert_ne!(r.output().flags & flags::STIFFNESS_LIMITED, 0);
    publish(&mut tx, plane(Vec3::y(), 0.0), 2000.0, 2);
    let f = r.tick(p, 2.0 * DT);
    assert!((f - Vec3::new(0.0, 10.0, 0.0)).norm() < 1e-9, "{f:?}");
    assert_eq!(r.output().flags & flags::STIFFNESS_LIMITED, 0);
}
