//! The leg frame (DESIGN.md §7, docs/ARCHITECTURE.md "anatomy").
//!
//! A **right leg**, patient supine. Origin on the leg's axis at the level of
//! the inguinal ligament. `x` lateral (the patient's right), `y` anterior
//! (towards the ceiling), `z = x × y` proximal (towards the head), so the
//! frame is right-handed; the leg's axis (hip centre to knee centre, the
//! mechanical axis) is the z axis. Positions along the leg are named by
//! `s = −z` (m below the inguinal ligament, growing towards the knee), and
//! around it by the angle `θ` from the anterior line (θ = 0) towards the
//! medial side (θ = π/2 medial, θ = π posterior, the popliteal fossa;
//! θ = −π/2 lateral). A point at distance `r` from the axis is
//! `(−r sin θ, r cos θ, −s)`.

use nalgebra::Vector3;
use std::f64::consts::{PI, TAU};

/// A point or vector in the leg frame (m).
pub type Vec3 = Vector3<f64>;

/// The point at `s` (m below the ligament), angle `θ` (rad) and distance
/// `r` (m) from the leg's axis.
pub fn point(s: f64, theta: f64, r: f64) -> Vec3 {
    Vec3::new(-r * theta.sin(), r * theta.cos(), -s)
}

/// `s` of a point (m below the inguinal ligament): `−z`.
pub fn s_of(p: &Vec3) -> f64 {
    -p.z
}

/// `θ` of a point (rad, in (−π, π]): `atan2(−x, y)`.
pub fn theta_of(p: &Vec3) -> f64 {
    (-p.x).atan2(p.y)
}

/// The angle wrapped into (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

/// Unit vector in the transverse plane pointing outward at angle θ:
/// `(−sin θ, cos θ, 0)`.
pub fn outward(theta: f64) -> Vec3 {
    Vec3::new(-theta.sin(), theta.cos(), 0.0)
}

/// Unit vector in the transverse plane in the direction of increasing θ:
/// `(−cos θ, −sin θ, 0)` (medial on the front of the leg, lateral behind).
pub fn along_theta(theta: f64) -> Vec3 {
    Vec3::new(-theta.cos(), -theta.sin(), 0.0)
}
