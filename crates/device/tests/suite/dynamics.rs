//! The simulated device's and hand's dynamics against closed-form solutions.

use echothigh_device::{
    DeviceConfig, HandConfig, HapticDevice, SimulatedDevice, SimulatedHand, Vec3,
};

/// Free device, viscous friction only: `v(t) = v₀ e^{−bt/m}`,
/// `x(t) = x₀ + v₀ (m/b)(1 − e^{−bt/m})`.
#[test]
fn free_device_decays_as_closed_form() {
    let config = DeviceConfig::default();
    let (m, b, h) = (
        config.mass,
        config.viscous_friction,
        1.0 / config.substep_rate,
    );
    let v0 = Vec3::new(0.1, -0.05, 0.02);
    let mut device = SimulatedDevice::new(config, Vec3::zeros()).unwrap();
    device.set_state(Vec3::zeros(), v0);
    let mut max_err_x: f64 = 0.0;
    for tick in 1..=300 {
        device.advance(1e-3);
        let t = tick as f64 * 1e-3;
        let decay = (-b * t / m).exp();
        // Continuous solution: first-order error bound ~ t b² h / (2 m²) relative.
        let v_exact = v0 * decay;
        let rel_bound = t * b * b * h / (m * m);
        assert!(
            (device.velocity() - v_exact).norm() <= rel_bound * v0.norm() + 1e-15,
            "t={t}: v={:?} exact={v_exact:?}",
            device.velocity()
        );
        let x_exact = v0 * (m / b) * (1.0 - decay);
        max_err_x = max_err_x.max((device.position() - x_exact).norm());
        // Discrete solution of the implicit-damping scheme, exactly.
        let n = tick as f64 * 10.0;
        let r = 1.0 / (1.0 + h * b / m);
        let v_disc = v0 * r.powf(n);
        let x_disc = v0 * (h * r * (1.0 - r.powf(n)) / (1.0 - r));
        assert!((device.velocity() - v_disc).norm() < 1e-12);
        assert!((device.position() - x_disc).norm() < 1e-12);
    }
    // Position error O(h): below 1 % of the total travel v₀ m / b.
    assert!(
        max_err_x < 0.01 * v0.norm() * m / b,
        "max position error {max_err_x}"
    );
}

fn step_response_error(substep_rate: f64) -> f64 {
    let config = DeviceConfig {
        substep_rate,
        ..DeviceConfig::default()
    };
    let hand_cfg = HandConfig::default();
    let s = Vec3::new(0.0, 0.01, 0.0);
    let hand = SimulatedHand::new(hand_cfg, s).unwrap();
    let mut device = SimulatedDevice::with_hand(config, hand).unwrap();
    device.set_state(Vec3::zeros(), Vec3::zeros());
    let m = config.mass + hand_cfg.mass;
    let c = config.viscous_friction + hand_cfg.damping;
    let k = hand_cfg.stiffness;
    let w0 = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    assert!(zeta < 1.0, "defaults are underdamped");
    let wd = w0 * (1.0 - zeta * zeta).sqrt();
    let mut max_err: f64 = 0.0;
    for tick in 1..=2000 {
        device.advance(1e-3);
        let t = tick as f64 * 1e-3;
        let y =
            s.y - s.y * (-zeta * w0 * t).exp() * ((wd * t).cos() + zeta * w0 / wd * (wd * t).sin());
        max_err = max_err.max((device.position().y - y).abs());
        assert!(device.position().x == 0.0 && device.position().z == 0.0);
    }
    max_err / s.y
}

/// Hand spring-damper step response: `m ẍ + c ẋ + k x = k s` from rest,
/// `x(t) = s [1 − e^{−ζω₀t}(cos ω_d t + ζω₀/ω_d sin ω_d t)]`, with
/// `m = m_device + m_hand`, `c = b + B`, `k = K`.
#[test]
fn hand_step_response_matches_second_order() {
    let e10 = step_response_error(10_000.0);
    let e20 = step_response_error(20_000.0);
    // Within 1 % of the step at 10 kHz (ω₀h ≈ 2.3e-3)…
    assert!(e10 < 0.01, "relative error {e10} at 10 kHz");
    // …and first-order convergent: halving h roughly halves the error.
    let ratio = e10 / e20;
    println!("step response: relative error {e10:.2e} at 10 kHz, {e20:.2e} at 20 kHz");
    assert!(
        (1.6..2.4).contains(&ratio),
        "error ratio {ratio} ({e10} / {e20})"
    );
}

#[test]
fn device_force_accelerates_total_mass_and_is_clamped() {
    let config = DeviceConfig {
        viscous_friction: 0.0,
        ..DeviceConfig::default()
    };
    let hand = SimulatedHand::new(
        HandConfig {
            stiffness: 0.0,
            damping: 0.0,
            ..HandConfig::default()
        },
        Vec3::zeros(),
    )
    .unwrap();
    let mut device = SimulatedDevice::with_hand(config, hand).unwrap();
    // 10 N commanded, clamped to the 6 N peak along +x.
    device.set_force(Vec3::new(10.0, 0.0, 0.0));
    assert_eq!(device.force(), Vec3::new(6.0, 0.0, 0.0));
    assert_eq!(device.faults().clamped, 1);
    device.advance(0.01);
    let a = 6.0 / (config.mass + 0.5);
    assert!((device.velocity().x - a * 0.01).abs() < 1e-12);
    // x = a h² n(n+1)/2 for semi-implicit Euler.
    let (h, n) = (1e-4, 100.0);
    assert!((device.position().x - a * h * h * n * (n + 1.0) / 2.0).abs() < 1e-12);
    // NaN renders zero and is counted; the device then coasts.
    device.set_force(Vec3::new(f64::NAN, 0.0, 0.0));
    assert_eq!(device.force(), Vec3::zeros());
    assert_eq!(device.faults().non_finite, 1);
    let v = device.velocity();
    device.advance(0.01);
    assert!((device.velocity() - v).norm() < 1e-15);
}

#[test]
fn advance_is_step_size_invariant_and_deterministic() {
    let run = |dt: f64, steps: usize| {
        let hand = SimulatedHand::new(HandConfig::default(), Vec3::new(0.0, 0.01, 0.0)).unwrap();
        let mut d = SimulatedDevice::with_hand(DeviceConfig::default(), hand).unwrap();
        d.set_state(Vec3::zeros(), Vec3::zeros());
        d.set_force(Vec3::new(0.5, 0.0, -0.2));
        for _ in 0..steps {
            d.advance(dt);
        }
        (d.position(), d.velocity())
    };
    // 10 × 1 ms and 1 × 10 ms are the same 100 sub-steps of 100 µs.
    assert_eq!(run(1e-3, 10), run(1e-2, 1));
    assert_eq!(run(1e-3, 500), run(1e-3, 500));
    // Bad dt is ignored.
    let mut d = SimulatedDevice::new(DeviceConfig::default(), Vec3::zeros()).unwrap();
    d.set_force(Vec3::new(1.0, 0.0, 0.0));
    d.advance(f64::NAN);
    d.advance(-1.0);
    assert_eq!(d.position(), Vec3::zeros());
    assert_eq!(d.time(), 0.0);
}
