//! Stalls in contact (issue 20, item 2): the physics stops publishing for
//! 0.05, 0.15, 0.35, 1 and 3 s while the device presses 10 mm into a plane
//! of 1000 N/m (10 N), or the haptic loop itself stalls for as long. The
//! renderer runs at 1 kHz on a virtual clock with a synthetic buffer model
//! republished at 100 Hz (the physics rate) whenever the physics runs.
//!
//! Asserted on every tick:
//! - the force never changes by more than the ramp's per-tick bound,
//!   `max_force / fade_time · 1 ms = 20 N / 0.1 s · 1 ms = 0.2 N` (the
//!   normal per-tick change of pressing reported in issue 20 is 0.24 N;
//!   the device moves here by at most 0.037 N per tick, see `SINK_SPEED`);
//! - the force never exceeds the force before the stall by more than the
//!   margin the device's own motion justifies: 0 N when the hand holds its
//!   depth (a rate-limited approach is a convex step, it cannot overshoot a
//!   constant target), `k · Δd` when the hand sank `Δd` (the deeper target
//!   itself: the extra depth only grows, so the last target is the
//!   largest), never above `max_force`;
//! - once the loss is declared, the force does not increase before it has
//!   reached zero (samples arriving after the loss are not rendered until
//!   the ramp restarts from zero), and the renderer says "faded to zero"
//!   only on ticks whose force is exactly zero.

use echothigh_haptics::{
    flags, handoff, BufferModel, HapticRenderer, ModelParams, ModelPublisher, Plane, RenderConfig,
    RenderState, Vec3,
};

const DT: f64 = 1e-3;
const K: f64 = 1000.0;
const DEPTH: f64 = 0.01;
/// Force before the stall, N: `K · DEPTH`.
const F0: f64 = K * DEPTH;
/// Sinking hand: 13 mm in 0.35 s, as measured in issue 20 (m/s).
const SINK_SPEED: f64 = 0.013 / 0.35;
/// Largest extra depth of the sinking hand, m (issue 20: 13 mm).
const SINK_MAX: f64 = 0.013;
const STALLS: [f64; 5] = [0.05, 0.15, 0.35, 1.0, 3.0];
/// Stall start, s (the force has long settled at F0).
const T_STALL: f64 = 0.5;

fn publish(tx: &mut ModelPublisher, seq: u64, t: f64) {
    tx.publish(BufferModel {
        params: ModelParams::Plane(Plane {
            normal: Vec3::y(),
            offset: 0.0,
        }),
        stiffness: K,
        sample_time: t,
        period: 0.01,
        sequence: seq,
    });
}

#[derive(Clone, Copy, PartialEq)]
enum Who {
    /// The physics stops publishing; the loop keeps ticking.
    Physics,
    /// The haptic process stops: no ticks and no models during the stall.
    Loop,
}

struct Run {
    forces: Vec<f64>,
    step_bound: f64,
    margin: f64,
    end_target: f64,
}

/// Runs one stall of `stall` s; `sink` lets the hand sink while the force
/// is below F0 (else it holds its depth).
fn run(who: Who, stall: f64, sink: bool) -> Run {
    let cfg = RenderConfig::default();
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&cfg, rx).unwrap();
    // Per-tick bound of the ramp at a 1 kHz tick: rate · 1 ms.
    let step_bound = cfg.ramp_rate() * DT;
    assert!((step_bound - 0.2).abs() < 1e-12);
    let n = ((T_STALL + stall + 1.5) / DT).round() as u64;
    let (i0, i1) = (
        (T_STALL / DT).round() as u64,
        ((T_STALL + stall) / DT).round() as u64,
    );
    let mut seq = 0;
    let mut extra = 0.0_f64;
    let mut forces = Vec::new();
    let mut loss_seen = false;
    let mut zero_after_loss = false;
    let mut prev = 0.0;
    for i in 0..n {
        let t = i as f64 * DT;
        let stalled = i >= i0 && i < i1;
        if stalled && who == Who::Loop {
            continue; // the whole haptic process is stopped
        }
        // After a stall of the haptic process its first tick comes before
        // the first model (the link and the manager catch up after it).
        let catching_up = who == Who::Loop && i >= i1 && i < i1 + 5;
        if i % 10 == 0 && !stalled && !catching_up {
            seq += 1;
            publish(&mut tx, seq, t);
        }
        if sink && i >= i0 && prev < F0 - 1e-9 {
            extra = (extra + SINK_SPEED * DT).min(SINK_MAX);
        }
        let p = Vec3::new(0.0, -(DEPTH + extra), 0.0);
        let f = r.tick(p, t).norm();
        let out = r.output();
        if i >= i0 {
            if out.flags & flags::STALE != 0 {
                loss_seen = true;
            }
            if loss_seen && !zero_after_loss {
                assert!(
                    f <= prev + 1e-12,
                    "stall {stall} s: force rose to {f} N at t = {t} before reaching zero"
                );
                zero_after_loss = f == 0.0;
            }
        }
        if r.faded_to_zero() {
            assert_eq!(f, 0.0, "'faded to zero' while rendering {f} N");
            assert!(matches!(
                r.state(),
                RenderState::Released | RenderState::NoModel
            ));
        }
        forces.push(f);
        prev = f;
    }
    if stall > cfg.stale_age + 2.0 * DT {
        assert!(loss_seen, "stall {stall} s: loss never declared");
        assert!(zero_after_loss, "stall {stall} s: never reached zero");
    }
    if stall < cfg.stale_age - 2.0 * DT {
        assert!(
            !loss_seen,
            "stall {stall} s shorter than stale_age declared a loss"
        );
    }
    // The hand's extra depth only grows, so the deepest target is the last.
    let margin = (K * extra).min(cfg.max_force - F0);
    Run {
        forces,
        step_bound,
        margin,
        end_target: (K * (DEPTH + extra)).min(cfg.max_force),
    }
}

fn check(who: Who, sink: bool) {
    for stall in STALLS {
        let run = run(who, stall, sink);
        // Warm-up: the first model ramps in from zero at the same bound.
        let (at, worst) = run
            .forces
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .enumerate()
            .fold((0, 0.0), |a, (i, d)| if d > a.1 { (i, d) } else { a });
        assert!(
            worst <= run.step_bound + 1e-9,
            "stall {stall} s: tick {at} changed the force by {worst} N > {} N",
            run.step_bound
        );
        let peak = run.forces.iter().copied().fold(0.0, f64::max);
        assert!(
            peak <= F0 + run.margin + 1e-9,
            "stall {stall} s: {peak} N exceeds {F0} N + margin {} N",
            run.margin
        );
        let last = *run.forces.last().unwrap();
        assert!(
            (last - run.end_target).abs() < 1e-9,
            "stall {stall} s: force {last} N did not come back to {} N",
            run.end_target
        );
    }
}

#[test]
fn physics_stall_with_the_hand_holding_its_depth() {
    check(Who::Physics, false);
}

#[test]
fn physics_stall_with_a_sinking_hand() {
    check(Who::Physics, true);
}

#[test]
fn haptic_loop_stall() {
    check(Who::Loop, false);
    check(Who::Loop, true);
}

/// A model arriving in the middle of the release is not rendered: the force
/// keeps falling to zero, then ramps in from zero (0.15 s stall: the loss is
/// declared at 0.1 s, the model returns with the force half released).
#[test]
fn a_model_arriving_mid_release_waits_for_zero() {
    let cfg = RenderConfig::default();
    let (mut tx, rx) = handoff();
    let mut r = HapticRenderer::new(&cfg, rx).unwrap();
    let p = Vec3::new(0.0, -DEPTH, 0.0);
    let mut t = 0.0;
    for i in 0..200 {
        if i % 10 == 0 {
            publish(&mut tx, i / 10 + 1, t);
        }
        r.tick(p, t);
        t += DT;
    }
    assert_eq!(r.state(), RenderState::Live);
    assert!((r.output().force.norm() - F0).abs() < 1e-9);
    // Stale from t ≈ 0.1 s; release at 0.2 N per tick.
    while r.state() != RenderState::Releasing {
        r.tick(p, t);
        t += DT;
    }
    for _ in 0..25 {
        r.tick(p, t);
        t += DT;
    }
    let mid = r.output().force.norm();
    assert!(mid > 0.0 && mid < F0, "{mid}");
    publish(&mut tx, 100, t);
    let mut ticks_to_zero = 0;
    loop {
        let f = r.tick(p, t).norm();
        t += DT;
        if f == 0.0 {
            break;
        }
        assert_eq!(r.state(), RenderState::Releasing);
        ticks_to_zero += 1;
        assert!(ticks_to_zero < 100, "never reached zero");
    }
    // mid / 0.2 N per tick, the last step landing on zero.
    assert_eq!(ticks_to_zero, (mid / 0.2).ceil() as i32 - 1);
    let f = r.tick(p, t).norm();
    assert_eq!(r.state(), RenderState::Ramping);
    assert!((f - 0.2).abs() < 1e-9, "ramping from zero: {f}");
}
