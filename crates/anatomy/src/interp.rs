//! Interpolation of the anatomical tables along the leg.
//!
//! [`Profile`] is a monotone piecewise-cubic Hermite interpolant
//! (Fritsch & Carlson 1980, SIAM J. Numer. Anal. 17:238): C¹, exact at the
//! knots, and without overshoot between them, so a radius or a depth never
//! dips below its neighbouring published values. Hand-written (≈ 40 lines)
//! because the crate's dependencies are limited to nalgebra/serde/toml/
//! thiserror and nalgebra has no 1-D spline.

/// A C¹ monotone cubic `v(s)` through knots `(s_k, v_k)`; constant beyond
/// the first and last knots.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    s: Vec<f64>,
    v: Vec<f64>,
    m: Vec<f64>,
}

impl Profile {
    /// The interpolant through `knots` (s strictly increasing, all finite).
    /// Returns `None` when the knots are empty, unsorted or not finite.
    pub fn new(knots: &[(f64, f64)]) -> Option<Profile> {
        if knots.is_empty()
            || knots.iter().any(|(s, v)| !s.is_finite() || !v.is_finite())
            || knots.windows(2).any(|w| w[1].0 <= w[0].0)
        {
            return None;
        }
        let s: Vec<f64> = knots.iter().map(|k| k.0).collect();
        let v: Vec<f64> = knots.iter().map(|k| k.1).collect();
        let n = s.len();
        let d: Vec<f64> = (0..n.saturating_sub(1))
            .map(|k| (v[k + 1] - v[k]) / (s[k + 1] - s[k]))
            .collect();
        let mut m = vec![0.0; n];
        if n >= 2 {
            m[0] = d[0];
            m[n - 1] = d[n - 2];
            for k in 1..n - 1 {
                m[k] = if d[k - 1] * d[k] <= 0.0 {
                    0.0
                } else {
                    0.5 * (d[k - 1] + d[k])
                };
            }
            // Fritsch–Carlson limiter: (α² + β²) ≤ 9 on every interval.
            for k in 0..n - 1 {
                if d[k] == 0.0 {
                    m[k] = 0.0;
                    m[k + 1] = 0.0;
                    continue;
                }
                let a = m[k] / d[k];
                let b = m[k + 1] / d[k];
                let h = a * a + b * b;
                if h > 9.0 {
                    let t = 3.0 / h.sqrt();
                    m[k] = t * a * d[k];
                    m[k + 1] = t * b * d[k];
                }
            }
        }
        Some(Profile { s, v, m })
    }

    /// A constant profile.
    pub fn constant(v: f64) -> Profile {
        Profile {
            s: vec![0.0],
            v: vec![v],
            m: vec![0.0],
        }
    }

    /// `v(s)`: the cubic Hermite on the interval holding `s`; the end
    /// values beyond the knots.
    pub fn eval(&self, s: f64) -> f64 {
        let n = self.s.len();
        if n == 1 || s <= self.s[0] {
            return self.v[0];
        }
        if s >= self.s[n - 1] {
            return self.v[n - 1];
        }
        let k = self.s.partition_point(|&x| x <= s) - 1;
        let h = self.s[k + 1] - self.s[k];
        let t = (s - self.s[k]) / h;
        let (t2, t3) = (t * t, t * t * t);
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + t;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        h00 * self.v[k] + h10 * h * self.m[k] + h01 * self.v[k + 1] + h11 * h * self.m[k + 1]
    }
}

/// Smooth step `3t² − 2t³` of `t` clamped to [0, 1] (C¹ blend of two
/// courses, used where a branch leaves its parent vessel).
pub fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_at_knots_and_monotone_between() {
        let p = Profile::new(&[(0.0, 1.0), (1.0, 3.0), (2.0, 3.0), (3.0, 0.0)]).unwrap();
        for (s, v) in [(0.0, 1.0), (1.0, 3.0), (2.0, 3.0), (3.0, 0.0)] {
            assert!((p.eval(s) - v).abs() < 1e-12);
        }
        // Monotone data on each interval: no overshoot (flat interval stays flat).
        for i in 0..=100 {
            let s = 1.0 + i as f64 / 100.0;
            assert!((p.eval(s) - 3.0).abs() < 1e-12, "overshoot at {s}");
        }
        let mut last = p.eval(0.0);
        for i in 1..=100 {
            let v = p.eval(i as f64 / 100.0);
            assert!(v >= last - 1e-12);
            last = v;
        }
        assert!(Profile::new(&[(1.0, 0.0), (0.5, 1.0)]).is_none());
    }
}
