//! The `hold` and `direct` force paths leave and re-enter through the ramp
//! (issue 20, item 2): a stall of the physics never kicks the device, the
//! force after a stale period comes back from zero no faster than
//! `max_force / fade_time`, a non-finite force is a fault rendered as zero,
//! and "faded to zero" is said only when the force is zero.
//!
//! Defaults of `[haptics.render]`: max_force 20 N, stale_age 0.1 s,
//! fade_time 0.1 s, max_tick_interval 1 ms, so the ramp moves at most
//! 20 / 0.1 × 1e-3 = 0.2 N per tick.

use echothigh_haptics::{HapticsConfig, Vec3};
use echothigh_runtime::haptic_side::{haptic_side, ForceSource, SampleSink};
use echothigh_runtime::live::CouplingMode;
use echothigh_transport::SampleMsg;

const DT: f64 = 1e-3;

fn pair(mode: CouplingMode) -> (SampleSink, ForceSource, f64) {
    let config = HapticsConfig::default();
    let (sink, source) = haptic_side(mode, &config, f64::INFINITY).unwrap();
    let step = config.render.ramp_rate() * config.render.max_tick_interval;
    (sink, source, step)
}

fn sample(fy: f64) -> SampleMsg {
    SampleMsg {
        force: [0.0, fy, 0.0],
        ..Default::default()
    }
}

/// Rounding slack on a per-tick bound: a few ulps of a 20 N force.
const EPS: f64 = 1e-12;

#[test]
fn hold_reenters_through_the_ramp_after_a_stall() {
    let (mut sink, mut source, step) = pair(CouplingMode::Hold);
    assert!((step - 0.2).abs() < EPS, "ramp step {step}");
    let p = Vec3::zeros();
    let mut t = 0.0;
    let mut prev = 0.0;
    let mut max_jump: f64 = 0.0;
    // 1. Samples of 10 N every 10 ms (100 Hz physics) for 0.5 s: the first
    //    force enters from zero through the ramp, then is held as is.
    for i in 0..500 {
        if i % 10 == 0 {
            sink.on_sample(&sample(10.0), t);
        }
        let f = source.tick(p, t).force.norm();
        max_jump = max_jump.max((f - prev).abs());
        prev = f;
        t += DT;
    }
    assert!((prev - 10.0).abs() < EPS, "held force {prev}");
    assert!(max_jump <= step + EPS, "entry jump {max_jump} > {step}");
    // 2. A 1 s stall: after stale_age the force is released at the ramp
    //    rate, reaching zero 50 ticks later (10 N / 0.2 N), and stays there.
    let stall_start = t;
    let mut zero_at = None;
    for _ in 0..1000 {
        let r = source.tick(p, t);
        let f = r.force.norm();
        assert!(
            (f - prev).abs() <= step + EPS,
            "release jump {} at {t}",
            f - prev
        );
        assert!(f <= 10.0 + EPS, "no force above the held one");
        if f == 0.0 && zero_at.is_none() {
            zero_at = Some(t - stall_start);
        }
        assert_eq!(
            source.faded_to_zero(),
            f == 0.0,
            "'faded to zero' must say exactly whether the force is zero (t = {t})"
        );
        prev = f;
        t += DT;
    }
    let z = zero_at.expect("released to zero during the stall");
    // The last sample came 10 ms before the stall, so it goes stale 0.09 s
    // into it; then 50 ticks of 0.2 N: zero at 0.14 s, ±1 tick of rounding.
    assert!(
        (0.138..=0.142).contains(&z),
        "reached zero {z} s into the stall"
    );
    // 3. Samples come back at 16 N: the force re-enters from zero at the
    //    ramp rate, never jumping; 80 ticks to reach 16 N.
    let back = t;
    let mut reached = None;
    for i in 0..300 {
        if i % 10 == 0 {
            sink.on_sample(&sample(16.0), t);
        }
        let f = source.tick(p, t).force.norm();
        assert!(
            (f - prev).abs() <= step + EPS,
            "re-entry jump {} at {t}",
            f - prev
        );
        if (f - 16.0).abs() < EPS && reached.is_none() {
            reached = Some(t - back);
        }
        prev = f;
        t += DT;
    }
    let r = reached.expect("the force came back");
    // 80 ticks of 0.2 N, the first on the tick the sample arrives: 79 ms
    // after it, ±1 tick of rounding.
    assert!(
        (0.078..=0.080).contains(&r),
        "re-entry took {r} s, expected 0.079"
    );
}

#[test]
fn a_stalled_loop_changes_the_force_by_one_step_at_most() {
    // The loop itself stalls 0.35 s (SIGSTOP of the client) while fresh
    // samples keep coming: the first tick after the stall is credited one
    // max_tick_interval, so the force moves by one ramp step at most.
    let (mut sink, mut source, step) = pair(CouplingMode::Hold);
    let p = Vec3::zeros();
    let mut t = 0.0;
    for i in 0..300 {
        if i % 10 == 0 {
            sink.on_sample(&sample(8.0), t);
        }
        source.tick(p, t);
        t += DT;
    }
    let before = source.tick(p, t).force.norm();
    assert!((before - 8.0).abs() < EPS);
    // The physics went on without us: its sample is fresh, at 12 N.
    t += 0.35;
    sink.on_sample(&sample(12.0), t - 0.005);
    let after = source.tick(p, t).force.norm();
    // Fresh (5 ms old) and tracking: the held force is displayed as is —
    // the paper's zero-order hold, no rate limit in this mode.
    assert!((after - 12.0).abs() < EPS, "{after}");
    // Now a stale one: the physics stalled with the loop.
    let (mut sink, mut source, _) = pair(CouplingMode::Hold);
    let mut t = 0.0;
    for i in 0..300 {
        if i % 10 == 0 {
            sink.on_sample(&sample(8.0), t);
        }
        source.tick(p, t);
        t += DT;
    }
    t += 0.35;
    let f1 = source.tick(p, t).force.norm();
    assert!(
        (f1 - 8.0).abs() <= step + EPS,
        "first tick after a 0.35 s stall moved the force by {} N",
        8.0 - f1
    );
}

#[test]
fn direct_force_enters_through_the_ramp_and_faults_are_zero() {
    let (_, mut source, step) = pair(CouplingMode::Direct);
    let p = Vec3::zeros();
    let mut prev = 0.0;
    let mut t = 0.0;
    // The physics force is already 10 N on the first tick (a session
    // started pressed): it enters from zero at the ramp rate.
    for _ in 0..100 {
        let f = source.direct(Vec3::new(0.0, 10.0, 0.0), p, t).force.norm();
        assert!(f - prev <= step + EPS, "jump {}", f - prev);
        prev = f;
        t += DT;
    }
    assert!((prev - 10.0).abs() < EPS, "{prev}");
    // A NaN force is a fault: zero at once, then back through the ramp.
    let r = source.direct(Vec3::new(f64::NAN, 0.0, 0.0), p, t);
    assert!(r.fault);
    assert_eq!(r.force, Vec3::zeros());
    t += DT;
    let f = source.direct(Vec3::new(0.0, 10.0, 0.0), p, t).force.norm();
    assert!(
        f <= step + EPS,
        "after a fault the force re-enters from zero: {f}"
    );
    // Clamped to max_force (20 N) whatever the physics says.
    for _ in 0..200 {
        t += DT;
        let f = source.direct(Vec3::new(0.0, 1e6, 0.0), p, t).force.norm();
        assert!(f <= 20.0 + EPS, "{f}");
    }
}
