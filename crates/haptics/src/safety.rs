//! Force safety stages applied to the rendered force, in order: magnitude
//! clamp, rate limit, and a final finiteness check (the stale release and
//! re-entry are [`crate::ForceRamp`]'s). Stages are pure functions of their
//! inputs so that each can be tested alone.

use crate::Vec3;

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
    fn clamp_and_rate_limit_bound_the_output() {
        let (f, c) = clamp_magnitude(Vec3::new(30.0, 40.0, 0.0), 20.0);
        assert!(c && (f.norm() - 20.0).abs() < 1e-12);
        let (g, l) = limit_rate(Vec3::zeros(), Vec3::new(0.0, 10.0, 0.0), 2000.0, 1e-3);
        assert!(l && (g.y - 2.0).abs() < 1e-12);
        let (h, l) = limit_rate(g, Vec3::new(0.0, 3.0, 0.0), 2000.0, 1e-3);
        assert!(!l && h.y == 3.0);
    }
}
