//! The leg's skin: a tapered generalized cylinder around the leg frame's
//! z axis, with an elliptic cross-section whose circumference follows the
//! patient's profile, and the popliteal fossa as a shallow posterior
//! hollow behind the knee.
//!
//! Cross-section at `s`: the ellipse `(x/a)² + (y/b)² = 1` with `b = k a`
//! (`k` = `ap_ratio`) and `a` from the circumference `C(s)` by Ramanujan's
//! approximation `C ≈ π [3(a + b) − √((3a + b)(a + 3b))]` (relative error
//! < 1e-4 for k ≥ 0.5). In polar form around the axis at the angle θ of
//! [`crate::frame`], `r(θ) = 1 / √((sin θ / a)² + (cos θ / b)²)`, minus the
//! fossa's hollow `δ w_s(s) w_θ(θ)`.

use crate::frame::{self, Vec3};
use crate::interp::{smoothstep, Profile};
use crate::patient::Patient;
use std::f64::consts::PI;

/// Depth of the popliteal fossa's hollow (m), 5 mm (estimate: no published
/// surface depth was retrieved; the hollow is shallow in a supine leg with
/// the knee slightly flexed).
pub const FOSSA_DEPTH: f64 = 5e-3;
/// Half-width (rad) of the fossa around the posterior line θ = π: 0.5 rad
/// (≈ 28 mm of arc on a 57 mm radius; estimate, the fossa is a diamond
/// between the hamstrings and the gastrocnemius heads).
pub const FOSSA_HALF_ANGLE: f64 = 0.5;

/// The leg's outer surface (skin).
#[derive(Debug, Clone, PartialEq)]
pub struct LegShape {
    length: f64,
    knee_s: f64,
    circumference: Profile,
    ap_ratio: f64,
}

impl LegShape {
    /// The skin of `p`'s leg (assumes `p` validated). Circumference knots at
    /// s = 0, knee/2, 0.82 knee, knee (see [`Patient`]); constant beyond.
    pub fn new(p: &Patient) -> LegShape {
        let k = p.knee_s;
        let circumference = Profile::new(&[
            (0.0, p.circumference_groin),
            (0.5 * k, p.circumference_mid),
            (0.82 * k, p.circumference_distal),
            (k, p.circumference_knee),
        ])
        .expect("validated patient: increasing knots");
        LegShape {
            length: p.length,
            knee_s: k,
            circumference,
            ap_ratio: p.ap_ratio,
        }
    }

    /// Modelled length (m): `s ∈ [0, length]`.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The ellipse's semi-axes `(a, b)` (m; a medio-lateral, b antero-posterior) at `s`.
    pub fn semi_axes(&self, s: f64) -> (f64, f64) {
        let c = self.circumference.eval(s);
        let k = self.ap_ratio;
        let a = c / (PI * (3.0 * (1.0 + k) - ((3.0 + k) * (1.0 + 3.0 * k)).sqrt()));
        (a, k * a)
    }

    /// Weight of the fossa's hollow along the leg: rises from 0.75 knee_s,
    /// full from 0.85 knee_s to the knee line + 2 cm, fades over 3 cm.
    fn fossa_weight_s(&self, s: f64) -> f64 {
        let k = self.knee_s;
        smoothstep((s - 0.75 * k) / (0.1 * k)) * (1.0 - smoothstep((s - k - 0.02) / 0.03))
    }

    /// Distance (m) from the leg's axis to the skin at `(s, θ)`.
    pub fn skin_radius(&self, s: f64, theta: f64) -> f64 {
        let (a, b) = self.semi_axes(s);
        let (sn, cs) = theta.sin_cos();
        let r = 1.0 / ((sn / a).powi(2) + (cs / b).powi(2)).sqrt();
        let dth = frame::wrap_angle(theta - PI);
        let w_theta = if dth.abs() < FOSSA_HALF_ANGLE {
            (0.5 * PI * dth / FOSSA_HALF_ANGLE).cos().powi(2)
        } else {
            0.0
        };
        r - FOSSA_DEPTH * w_theta * self.fossa_weight_s(s)
    }

    /// Skin point at `(s, θ)` in the leg frame (m).
    pub fn skin_point(&self, s: f64, theta: f64) -> Vec3 {
        frame::point(s, theta, self.skin_radius(s, theta))
    }

    /// Outward unit normal of the skin at `(s, θ)`: `∂p/∂s × ∂p/∂θ`
    /// normalised, by central differences (steps 1e-5 m and 1e-5 rad: the
    /// truncation error is O(h²) ≈ 1e-10 relative, below any use).
    pub fn skin_normal(&self, s: f64, theta: f64) -> Vec3 {
        let (ts, tt) = self.tangents(s, theta);
        ts.cross(&tt).normalize()
    }

    /// Unit tangent of the skin in the transverse direction of increasing θ
    /// (towards medial on the front of the right leg).
    pub fn transverse_tangent(&self, s: f64, theta: f64) -> Vec3 {
        self.tangents(s, theta).1.normalize()
    }

    fn tangents(&self, s: f64, theta: f64) -> (Vec3, Vec3) {
        const H: f64 = 1e-5;
        let ts = (self.skin_point(s + H, theta) - self.skin_point(s - H, theta)) / (2.0 * H);
        let tt = (self.skin_point(s, theta + H) - self.skin_point(s, theta - H)) / (2.0 * H);
        (ts, tt)
    }

    /// Whether the point `p` (leg frame, m) lies inside the leg: `s` within
    /// `[0, length]` and no farther from the axis than the skin at its angle.
    pub fn contains(&self, p: &Vec3) -> bool {
        let s = frame::s_of(p);
        if !(0.0..=self.length).contains(&s) {
            return false;
        }
        p.xy().norm() <= self.skin_radius(s, frame::theta_of(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circumference_matches_the_profile_and_normal_is_outward_unit() {
        let p = Patient::preset("lean-male").unwrap();
        let leg = LegShape::new(&p);
        // Perimeter of the cross-section at mid-thigh by summing 20 000
        // chords; the fossa is absent there, so it must equal the patient's
        // mid-thigh circumference to Ramanujan's accuracy (< 1e-4 relative)
        // plus the chord sum's O(1/n²) error (≈ 1e-8).
        let s = 0.5 * p.knee_s;
        let n = 20_000;
        let per: f64 = (0..n)
            .map(|i| {
                let t0 = std::f64::consts::TAU * i as f64 / n as f64;
                let t1 = std::f64::consts::TAU * (i + 1) as f64 / n as f64;
                (leg.skin_point(s, t1) - leg.skin_point(s, t0)).norm()
            })
            .sum();
        assert!(
            (per / p.circumference_mid - 1.0).abs() < 1e-4,
            "perimeter {per}"
        );
        for &(s, th) in &[(0.01, 0.3), (0.2, 1.0), (0.37, PI), (0.3, -2.0)] {
            let n = leg.skin_normal(s, th);
            assert!((n.norm() - 1.0).abs() < 1e-12);
            let radial = leg.skin_point(s, th).xy().normalize();
            assert!(n.xy().dot(&radial) > 0.9, "normal not outward at {s}, {th}");
            let inside = leg.skin_point(s, th) - 1e-4 * n;
            let outside = leg.skin_point(s, th) + 1e-4 * n;
            assert!(leg.contains(&inside) && !leg.contains(&outside));
        }
    }
}
