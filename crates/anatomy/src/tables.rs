//! The control points of the reference anatomy (lean male; see
//! [`crate::vessels`] for how they are used). Knots are `(f, value)` with
//! `f = s / knee_s`; θ in rad ([`crate::frame`]); depths in mm below the
//! muscular fascia along the skin's normal.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// One millimetre (m).
pub const MM: f64 = 1e-3;
/// Wall-to-wall gap between a vein and its artery (m): 1 mm (reference
/// row 15: adjacent in one sheath; the previous 1.3 mm was judged right).
pub const GAP: f64 = 1.0 * MM;
/// Gap between the popliteal artery and the femur's posterior surface (m):
/// 3 mm (estimate: the artery lies on the popliteal surface and the joint
/// capsule, separated by a thin fat pad).
pub const POPLITEAL_GAP: f64 = 3.0 * MM;
/// Sartorius: half-width 20 mm, half-thickness 6 mm (estimates: a strap
/// muscle ≈ 4 cm wide and 12 mm thick over the adductor canal).
pub const SARTORIUS_HALF_WIDTH: f64 = 20.0 * MM;
/// See [`SARTORIUS_HALF_WIDTH`].
pub const SARTORIUS_HALF_THICKNESS: f64 = 6.0 * MM;

/// Artery line: θ (rad) by f. Mid-inguinal point anterior-slightly-medial;
/// anteromedial along the canal; through the hiatus to the posterior line.
pub const ARTERY_THETA: [(f64, f64); 9] = [
    (0.0, 0.30),
    (0.10, 0.36),
    (0.30, 0.65),
    (0.50, 0.95),
    (0.62, 1.30),
    (2.0 / 3.0, 1.60),
    (0.75, 2.20),
    (0.85, 2.80),
    (0.92, PI),
];
/// Artery line: depth below the fascia (mm) by f, down to the hiatus; below
/// it the artery is placed from the femur (blend to 0.8 knee_s). Under the
/// fascia lata at the groin, under sartorius from the apex (estimates;
/// reference row 14: no published mid-thigh depth was found).
pub const ARTERY_DEPTH: [(f64, f64); 6] = [
    (0.0, 8.0),
    (0.10, 9.0),
    (0.30, 16.0),
    (0.50, 22.0),
    (0.62, 28.0),
    (2.0 / 3.0, 32.0),
];
/// Vein side φ (rad) in the artery's local frame by f (reference row 12).
pub const VEIN_PHI: [(f64, f64); 10] = [
    (0.0, 0.0),
    (0.15, 0.2),
    (0.30, FRAC_PI_2),
    (0.50, FRAC_PI_2),
    (0.62, FRAC_PI_4),
    (2.0 / 3.0, FRAC_PI_4),
    (0.80, -FRAC_PI_4),
    (0.90, -FRAC_PI_2),
    (1.0, -FRAC_PI_2),
    (1.125, -FRAC_PI_2 - 0.4),
];
/// GSV θ (rad) by f: anteromedial below the SFJ, medial at mid-thigh,
/// posteromedial at the knee (a hand's breadth behind the patella).
pub const GSV_THETA: [(f64, f64); 6] = [
    (0.05, 0.55),
    (0.125, 0.80),
    (0.50, 1.35),
    (0.80, 1.85),
    (1.0, 2.15),
    (1.125, 2.10),
];
/// Profunda course: (f, θ rad, depth mm) — deep towards the femur's medial side (estimate).
pub const PROFUNDA: [(f64, f64, f64); 4] = [
    (0.10, 0.40, 14.0),
    (0.20, 0.55, 30.0),
    (0.40, 1.10, 50.0),
    (0.60, 1.30, 55.0),
];
/// Sartorius θ (rad) by f: lateral border of the femoral triangle at the
/// groin, over the vessels from the apex (the canal's roof), posteromedial at
/// the knee (estimates from its course ASIS → pes anserinus).
pub const SARTORIUS_THETA: [(f64, f64); 8] = [
    (0.0, -0.55),
    (0.15, -0.05),
    (0.30, 0.62),
    (0.50, 0.95),
    (0.62, 1.30),
    (0.80, 1.90),
    (1.0, 2.30),
    (1.125, 2.35),
];
/// Femur centre y (mm) and radius (mm) by f. Mid-shaft radius 13 mm (the
/// previous echothigh default); wider proximally and at the condyles
/// (estimates). Its x follows the shaft's obliquity (`femur_obliquity_deg`).
pub const FEMUR_Y: [(f64, f64); 3] = [(0.0, -5.0), (0.5, 3.0), (1.0, 8.0)];
/// See [`FEMUR_Y`].
pub const FEMUR_R: [(f64, f64); 5] = [
    (0.0, 16.0),
    (0.15, 14.0),
    (0.5, 13.0),
    (0.8, 15.0),
    (1.0, 21.0),
];
