//! Force safety stages applied to the rendered force, in order: stale-model
//! fade, magnitude clamp, rate limit, and a final finiteness check. Stages are
//! pure functions of their inputs so that each can be tested alone.

use crate::Vec3;

/// Gain in [0, 1] for a model of age `age` (s): 1 up to `stale_age`, then a
/// linear fade to 0 over `fade_time` (immediately 0 if `fade_time = 0`).
pub fn fade_gain(age: f64, stale_age: f64, fade_time: f64) -> f64 {
    if age <= stale_age {
        1.0
    } else if fade_time <= 0.0 {
        0.0
    } else {
        (1.0 - (age - stale_age) / fade_time).clamp(0.0, 1.0)
    }
}

/// `f` scaled down to magnitude `max` (N) if longer; returns whether it clamped.
pub fn clamp_magnitude(f: Vec3, max: f64) -> (Vec3, bool) {
    let m = f.norm();
    if m > max {
        (f * (max / m), true)
    } else {
        (f, false)
    }
}

/// Moves from `previous` towards `target` by at most `rate · dt` (N/s · s);
/// returns whether it limited. Convex: if both ends are within a ball, so is
/// the result.
pub fn limit_rate(previous: Vec3, target: Vec3, rate: f64, dt: f64) -> (Vec3, bool) {
    let step = target - previous;
    let max = rate * dt.max(0.0);
    let m = step.norm();
    if m > max {
        (previous + step * (max / m), true)
    } else {
        (target, false)
    }
}

/// True when every component is finite.
pub fn is_finite(v: &Vec3) -> bool {
    v.iter().all(|c| c.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fade_is_linear_between_ages() {
        assert_eq!(fade_gain(0.05, 0.1, 0.1), 1.0);
        assert!((fade_gain(0.15, 0.1, 0.1) - 0.5).abs() < 1e-12);
        assert_eq!(fade_gain(0.25, 0.1, 0.1), 0.0);
        assert_eq!(fade_gain(0.1001, 0.1, 0.0), 0.0);
    }

    #[test]
    fn clamp_and_rate_limit_bound_the_output() {
        let (f, c) = clamp_magnitude(Vec3::new(30.0, 40.0, 0.0), 20.0);
        assert!(c && (f.norm() - 20.0).abs() < 1e-12);
        let (g, l) = limit_rate(Vec3::zeros(), Vec3::new(0.0, 10.0, 0.0), 2000.0, 1e-3);
        assert!(l && (g.y - 2.0).abs() < 1e-12);
        let (h, l) = limit_rate(g, Vec3::new(0.0, 3.0, 0.0), 2000.0, 1e-3);
        assert!(!l && h.y == 3.0);
    }
}
