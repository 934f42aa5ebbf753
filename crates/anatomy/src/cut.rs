//! The cut of a plane through a quadric solid, as an ellipse in the plane's
//! coordinates.
//!
//! Both shapes reduce to one form. A point of the plane is
//! `q(v) = o + α u + β w`, `v = (α, β)`. An ellipsoid `|L (q − c)|² ≤ 1`
//! (`L = diag(1/aᵢ) Aᵀ`) and a tube linearised at the centreline point `C₀`
//! where the plane crosses it (`|L P (q − C₀)|² ≤ 1`, with `P` the 2×3 map
//! to the transverse offset, see `section.rs`) are both `|M v + d₀|² ≤ 1`
//! with `M = L[u w]` (3×2) and `d₀ = L(o − c)`. With `Q = MᵀM` and
//! `g = Mᵀd₀`, the centre is `v₀ = −Q⁻¹g`, the value there
//! `k = |d₀|² + g·v₀`, and the semi-axes are `√((1 − k)/λᵢ)` along the
//! eigenvectors of `Q`. No cut when `k ≥ 1`; no finite ellipse when `Q` is
//! singular (the plane contains the tube's axis).

use nalgebra::{Matrix2, Matrix3x2, SymmetricEigen, Vector2, Vector3};

/// An ellipse in the image plane (m): centre `(lateral, depth)`, semi-axes
/// `radii = [a, b]` with `a` along the axis nearer the image's lateral
/// direction, and `angle` (rad, in (−π/2, π/2]) of the `a` axis from the
/// lateral direction towards depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Lateral position of the centre (m, positive towards the image's right).
    pub lateral: f64,
    /// Depth of the centre (m, along the beam from the probe's face).
    pub depth: f64,
    /// Semi-axes `[a, b]` (m).
    pub radii: [f64; 2],
    /// Angle of the `a` axis from the lateral direction (rad).
    pub angle: f64,
}

/// Smallest eigenvalue of `Q` accepted (1/m²): an ellipse axis up to
/// 1/√(1e-2) = 10 m long; beyond it the plane is taken to contain the axis.
const MIN_EIGEN: f64 = 1e-2;

/// The ellipse `{v : |M v + d₀|² ≤ 1}`, or `None` when empty or unbounded.
pub fn cut(m: &Matrix3x2<f64>, d0: &Vector3<f64>) -> Option<Ellipse> {
    let q: Matrix2<f64> = m.transpose() * m;
    let g: Vector2<f64> = m.transpose() * d0;
    let eig = SymmetricEigen::new(q);
    if eig.eigenvalues.min() < MIN_EIGEN {
        return None;
    }
    let v0 = -(q.try_inverse()? * g);
    let k = d0.dot(d0) + g.dot(&v0);
    if k >= 1.0 {
        return None;
    }
    let (e0, e1) = (eig.eigenvectors.column(0), eig.eigenvectors.column(1));
    let r0 = ((1.0 - k) / eig.eigenvalues[0]).sqrt();
    let r1 = ((1.0 - k) / eig.eigenvalues[1]).sqrt();
    let (ea, ra, rb) = if e0[0].abs() >= e1[0].abs() {
        (e0, r0, r1)
    } else {
        (e1, r1, r0)
    };
    let mut angle = ea[1].atan2(ea[0]);
    if angle > std::f64::consts::FRAC_PI_2 {
        angle -= std::f64::consts::PI;
    } else if angle <= -std::f64::consts::FRAC_PI_2 {
        angle += std::f64::consts::PI;
    }
    Some(Ellipse {
        lateral: v0[0],
        depth: v0[1],
        radii: [ra, rb],
        angle,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_cut_off_centre_has_the_chord_radius() {
        // Unit-radius (1 m) sphere at (0, 0, 0.6) cut by the plane z = 0
        // (u = x, w = y, o = origin): a circle of radius √(1 − 0.36) = 0.8
        // centred at (0, 0).
        let m = Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0);
        let d0 = Vector3::new(0.0, 0.0, -0.6);
        let e = cut(&m, &d0).unwrap();
        assert!(e.lateral.abs() < 1e-12 && e.depth.abs() < 1e-12);
        assert!((e.radii[0] - 0.8).abs() < 1e-12 && (e.radii[1] - 0.8).abs() < 1e-12);
        assert!(cut(&m, &Vector3::new(0.0, 0.0, -1.2)).is_none());
    }

    #[test]
    fn cylinder_cut_at_angle_gives_r_over_cos() {
        // Circular cylinder of radius 1 around z, cut by a plane through the
        // origin tilted by 30° about x: the section is an ellipse with
        // semi-axes 1 (along x) and 1/cos 30° (in the plane, along the tilt).
        let t = 30f64.to_radians();
        let u = Vector3::new(1.0, 0.0, 0.0);
        let w = Vector3::new(0.0, t.cos(), t.sin());
        // Cylinder: |(q)_xy| ≤ 1, i.e. L = [[1,0,0],[0,1,0],[0,0,0]].
        let m = Matrix3x2::new(u.x, w.x, u.y, w.y, 0.0, 0.0);
        let e = cut(&m, &Vector3::zeros()).unwrap();
        assert!((e.radii[0] - 1.0).abs() < 1e-12);
        assert!((e.radii[1] - 1.0 / t.cos()).abs() < 1e-12);
        assert!(e.angle.abs() < 1e-12);
    }
}
