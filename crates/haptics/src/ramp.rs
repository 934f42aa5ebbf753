//! [`ForceRamp`]: the one way a rendered force leaves and re-enters the
//! device — through zero, at a bounded rate.
//!
//! Used by the renderer for the stale-model fade and the re-entry after it
//! (issue 20, item 2: a stall must never kick the device), and reusable by
//! any other force path (a zero-order hold, a direct coupling, a reset or a
//! new exam question): call [`ForceRamp::release`] to take the force to
//! zero, [`ForceRamp::engage`] to bring it back, and [`ForceRamp::step`]
//! once per tick with the force the path would render.
//!
//! Phases: `Tracking` (the output is the target), `Releasing` (the output
//! moves to zero, targets ignored), `Released` (zero), `Engaging` (the
//! output moves from zero towards the target until it catches up). In
//! `Releasing` and `Engaging` the output moves by at most
//! `rate · min(dt, max_dt)` per step (N): a late or stalled tick (large
//! `dt`) is credited at most `max_dt`, so a loop that resumes after a
//! stall of the caller itself changes the force by no more than one normal
//! step. Each move is a convex step (`limit_rate`), so the output never
//! leaves the ball spanned by the previous output and the target: it never
//! overshoots a constant target. No allocation.

use crate::config::ConfigError;
use crate::safety::limit_rate;
use crate::Vec3;

/// Phase of a [`ForceRamp`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RampPhase {
    /// The output follows the target.
    Tracking,
    /// The output moves to zero at the ramp rate; targets are ignored.
    Releasing,
    /// The output is zero and stays zero until [`ForceRamp::engage`].
    Released,
    /// The output moves from zero towards the target at the ramp rate.
    Engaging,
}

/// A rate-bounded path of a force through zero (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceRamp {
    rate: f64,
    max_dt: f64,
    output: Vec3,
    phase: RampPhase,
    engage_pending: bool,
    /// Least time an engagement stays rate-limited, s (see [`Self::with_settle`]).
    settle: f64,
    /// Time left of the current engagement's settle window, s.
    settle_left: f64,
    /// True once the output has tracked a target: only a re-entry (after a
    /// release) settles, the first engagement tracks as soon as it catches up.
    tracked: bool,
}

impl ForceRamp {
    /// A ramp moving at most `rate` N/s, crediting at most `max_dt` s per
    /// step, starting `Released` at zero (the first force enters through the
    /// ramp). Both must be finite and > 0; `key` names them in the error.
    pub fn new(rate: f64, max_dt: f64, key: &str) -> Result<Self, ConfigError> {
        for (what, v) in [("rate (N/s)", rate), ("max_dt (s)", max_dt)] {
            if !v.is_finite() || v <= 0.0 {
                return Err(ConfigError::Invalid {
                    key: key.to_owned(),
                    reason: format!("force ramp {what} must be finite and > 0, got {v}"),
                });
            }
        }
        Ok(ForceRamp {
            rate,
            max_dt,
            output: Vec3::zeros(),
            phase: RampPhase::Released,
            engage_pending: false,
            settle: 0.0,
            settle_left: 0.0,
            tracked: false,
        })
    }

    /// Keeps every re-entry (an engagement after the output has tracked a
    /// target and been released) rate-limited for at least `settle` s (≥ 0,
    /// finite), even once the output has caught up with the target. After a
    /// stall the force comes back while the hand that sank is pushed out
    /// again and the physics' models change fast between steps; tracking
    /// them at once lets each model change or friction slip through in one
    /// tick (up to 2 N measured after a 0.35 s stall, issue 20), where the
    /// undisturbed exam changes the force by 0.24 N per tick at most. The
    /// renderer uses `settle = fade_time`.
    pub fn with_settle(mut self, settle: f64) -> Self {
        self.settle = if settle.is_finite() {
            settle.max(0.0)
        } else {
            0.0
        };
        self
    }

    /// Largest change of the output in one step, N: `rate · max_dt`.
    pub fn max_step(&self) -> f64 {
        self.rate * self.max_dt
    }

    /// The ramp rate, N/s.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The current phase.
    pub fn phase(&self) -> RampPhase {
        self.phase
    }

    /// The last output, N.
    pub fn output(&self) -> Vec3 {
        self.output
    }

    /// True when the output is exactly zero and stays so until engaged.
    pub fn is_released(&self) -> bool {
        self.phase == RampPhase::Released
    }

    /// Starts taking the force to zero (from `Tracking` or `Engaging`). A
    /// pending [`Self::engage`] is cancelled.
    pub fn release(&mut self) {
        self.engage_pending = false;
        if matches!(self.phase, RampPhase::Tracking | RampPhase::Engaging) {
            self.phase = RampPhase::Releasing;
        }
    }

    /// Asks for the force back. From `Released` the ramp starts from zero at
    /// once; while `Releasing` it first reaches zero, then ramps up (the
    /// force is never brought back without passing through zero).
    pub fn engage(&mut self) {
        match self.phase {
            RampPhase::Released => {
                self.phase = RampPhase::Engaging;
                self.settle_left = if self.tracked { self.settle } else { 0.0 };
            }
            RampPhase::Releasing => self.engage_pending = true,
            RampPhase::Tracking | RampPhase::Engaging => {}
        }
    }

    /// Drops the output to zero now, `Released` (after a fault, when the
    /// force was zeroed by someone else); the next [`Self::engage`] ramps
    /// from zero.
    pub fn zero(&mut self) {
        self.output = Vec3::zeros();
        self.phase = RampPhase::Released;
        self.engage_pending = false;
    }

    /// One step of `dt` s towards `target` (N); returns the output (N) and
    /// whether the ramp limited it.
    pub fn step(&mut self, target: Vec3, dt: f64) -> (Vec3, bool) {
        let dt = if dt.is_finite() {
            dt.clamp(0.0, self.max_dt)
        } else {
            self.max_dt
        };
        match self.phase {
            RampPhase::Tracking => {
                self.output = target;
                (target, false)
            }
            RampPhase::Released => {
                self.output = Vec3::zeros();
                (self.output, !(target == Vec3::zeros()))
            }
            RampPhase::Releasing => {
                let (f, _) = limit_rate(self.output, Vec3::zeros(), self.rate, dt);
                self.output = f;
                if f == Vec3::zeros() {
                    self.phase = if self.engage_pending {
                        self.settle_left = if self.tracked { self.settle } else { 0.0 };
                        RampPhase::Engaging
                    } else {
                        RampPhase::Released
                    };
                    self.engage_pending = false;
                }
                (f, true)
            }
            RampPhase::Engaging => {
                let (f, limited) = limit_rate(self.output, target, self.rate, dt);
                self.output = f;
                self.settle_left -= dt;
                if !limited && self.settle_left <= 0.0 {
                    self.phase = RampPhase::Tracking;
                    self.tracked = true;
                }
                (f, limited)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> ForceRamp {
        // 200 N/s credited at most 2 ms: at most 0.4 N per step.
        ForceRamp::new(200.0, 2e-3, "test").unwrap()
    }

    #[test]
    fn invalid_rates_are_refused_naming_the_key() {
        for (r, d) in [
            (0.0, 1e-3),
            (f64::NAN, 1e-3),
            (1.0, -1.0),
            (1.0, f64::INFINITY),
        ] {
            let e = ForceRamp::new(r, d, "haptics.render.fade_time").unwrap_err();
            assert!(e.to_string().starts_with("haptics.render.fade_time"), "{e}");
        }
    }

    #[test]
    fn engages_from_zero_at_the_rate_and_then_tracks() {
        let mut r = ramp();
        let target = Vec3::new(0.0, 10.0, 0.0);
        assert_eq!(
            r.step(target, 1e-3).0,
            Vec3::zeros(),
            "released until engaged"
        );
        r.engage();
        let mut prev = Vec3::zeros();
        let mut steps = 0;
        while r.phase() == RampPhase::Engaging {
            let (f, _) = r.step(target, 1e-3);
            // 200 N/s × 1 ms = 0.2 N per step, to rounding.
            assert!((f - prev).norm() <= 0.2 + 1e-12);
            assert!(
                f.norm() <= 10.0 + 1e-12,
                "no overshoot of a constant target"
            );
            prev = f;
            steps += 1;
        }
        // 10 N / 0.2 N per step = 50 steps, the last one catching up; the
        // sum of fifty 0.2 N steps may fall short of 10 N by an ulp, which
        // costs one more (tiny) step.
        assert!((50..=51).contains(&steps), "{steps}");
        assert_eq!(r.step(target * 2.0, 1e-3).0, target * 2.0, "tracking");
    }

    #[test]
    fn a_settling_engagement_stays_rate_limited_after_catching_up() {
        // 200 N/s, 1 ms steps: 0.2 N per step; settle 50 ms.
        let mut r = ramp().with_settle(0.05);
        r.engage();
        let target = Vec3::new(0.0, 1.0, 0.0);
        // The first engagement tracks once caught up (5 steps).
        for _ in 0..6 {
            r.step(target, 1e-3);
        }
        assert_eq!(r.phase(), RampPhase::Tracking);
        // Released, then re-engaged: the re-entry settles.
        r.release();
        for _ in 0..6 {
            r.step(target, 1e-3);
        }
        assert!(r.is_released());
        r.engage();
        for _ in 0..10 {
            r.step(target, 1e-3); // caught up after 5 steps, still settling
        }
        assert_eq!(r.phase(), RampPhase::Engaging);
        // A target jump inside the window moves the output by one step.
        let (f, limited) = r.step(target * 3.0, 1e-3);
        assert!(limited && (f.norm() - 1.2).abs() < 1e-12, "{f:?}");
        for _ in 0..60 {
            r.step(target * 3.0, 1e-3);
        }
        // Window over and caught up: tracking, jumps pass through.
        assert_eq!(r.phase(), RampPhase::Tracking);
        assert_eq!(r.step(target * 5.0, 1e-3).0, target * 5.0);
    }

    #[test]
    fn a_stalled_caller_is_credited_one_max_dt() {
        let mut r = ramp();
        r.engage();
        let (f, limited) = r.step(Vec3::new(5.0, 0.0, 0.0), 3.0);
        assert!(limited);
        assert!((f.norm() - 0.4).abs() < 1e-12, "{f:?}");
    }

    #[test]
    fn engage_while_releasing_passes_through_zero() {
        let mut r = ramp();
        r.engage();
        let target = Vec3::new(0.0, 1.0, 0.0);
        for _ in 0..10 {
            r.step(target, 1e-3);
        }
        assert_eq!(r.phase(), RampPhase::Tracking);
        r.release();
        r.step(target, 1e-3); // 1.0 → 0.8
        r.engage(); // a fresh target arrives mid-release
        let mut seen_zero = false;
        let mut prev = r.output().norm();
        for _ in 0..10 {
            let f = r.step(target * 3.0, 1e-3).0.norm();
            if !seen_zero {
                assert!(f <= prev, "still releasing: {f} > {prev}");
                seen_zero = f == 0.0;
            }
            prev = f;
        }
        assert!(seen_zero, "the force passed through zero");
        assert_eq!(r.phase(), RampPhase::Engaging);
        assert!(prev > 0.0, "and came back");
    }
}
