//! Tissue pressure under the probe: vertical stress below a uniformly loaded
//! rectangle on an elastic half-space (Boussinesq 1885, integrated over a
//! rectangle by Newmark 1935, "Simplified computation of vertical pressures in
//! elastic foundations", Univ. Illinois Eng. Exp. Stn. Circ. 24).
//!
//! The vein does not feel the probe's mean face pressure but the stress that
//! reaches its depth: ≈ 100 % just under the face, ≈ 25 % at 20 mm under a
//! 40 × 10 mm face. This is the "attenuation with depth" of the pressure that
//! drives the vessels' lumen laws.

use std::f64::consts::PI;

/// Newmark's influence factor for the vertical stress at depth `z` (m) under
/// a corner of a uniformly loaded `b × l` rectangle (m), extended oddly to
/// signed sides: `I(−b, l) = −I(b, l)`, so rectangles that do not contain the
/// point are handled by superposition.
fn corner_factor(b: f64, l: f64, z: f64) -> f64 {
    let m = b / z;
    let n = l / z;
    let s2 = m * m + n * n + 1.0;
    let s = s2.sqrt();
    let mn = m * n;
    let t1 = 2.0 * mn * s / (s2 + mn * mn) * (s2 + 1.0) / s2;
    let t2 = (2.0 * mn * s).atan2(s2 - mn * mn);
    (t1 + t2) / (4.0 * PI)
}

/// Vertical stress (Pa) at the point `(x, y)` (m, in the plane of the face,
/// relative to its centre) and depth `z` (m, ≥ 0) under a `width × elevation`
/// rectangle (m) carrying the uniform pressure `pressure` (Pa).
///
/// `σ_z = p Σ ± I(x_i − x, y_j − y, z)` over the four corners (Newmark).
/// At `z → 0` under the face it tends to `p`; far away it tends to the point
/// load solution `3 P z³ / (2π R⁵)` with `P = p · width · elevation`.
pub fn stress_under_rectangle(
    pressure: f64,
    width: f64,
    elevation: f64,
    x: f64,
    y: f64,
    z: f64,
) -> f64 {
    let z = z.max(1e-6);
    let (x1, x2) = (-0.5 * width - x, 0.5 * width - x);
    let (y1, y2) = (-0.5 * elevation - y, 0.5 * elevation - y);
    let f = corner_factor(x2, y2, z) - corner_factor(x1, y2, z) - corner_factor(x2, y1, z)
        + corner_factor(x1, y1, z);
    pressure * f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_pressure_just_under_the_face() {
        let s = stress_under_rectangle(1000.0, 0.04, 0.01, 0.0, 0.0, 1e-6);
        assert!((s - 1000.0).abs() < 1.0, "{s}");
    }

    #[test]
    fn far_field_is_the_point_load() {
        let (p, w, e) = (1000.0, 0.04, 0.01);
        let z = 1.0;
        let s = stress_under_rectangle(p, w, e, 0.0, 0.0, z);
        let point = 3.0 * p * w * e / (2.0 * PI * z * z);
        assert!((s / point - 1.0).abs() < 1e-3, "{s} vs {point}");
        // Off axis at (x, 0, z): 3 P z³ / (2π R⁵).
        let x = 0.5;
        let r = (x * x + z * z).sqrt();
        let point = 3.0 * p * w * e * z.powi(3) / (2.0 * PI * r.powi(5));
        let s = stress_under_rectangle(p, w, e, x, 0.0, z);
        assert!((s / point - 1.0).abs() < 1e-3, "{s} vs {point}");
    }

    #[test]
    fn outside_the_face_and_decreasing_with_depth() {
        // Just below the surface, outside the loaded area: ~0.
        let s = stress_under_rectangle(1000.0, 0.04, 0.01, 0.05, 0.0, 1e-5);
        assert!(s.abs() < 1e-3, "{s}");
        let mut last = f64::INFINITY;
        for i in 1..40 {
            let s = stress_under_rectangle(1000.0, 0.04, 0.01, 0.0, 0.0, i as f64 * 1e-3);
            assert!(s < last && s > 0.0);
            last = s;
        }
    }
}
