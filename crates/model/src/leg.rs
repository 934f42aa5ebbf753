//! The anatomical leg the mesh follows (issue 12): the skin of a patient's
//! tapered leg ([`echothigh_anatomy::LegShape`]), the anchors of the normal
//! springs on the oblique femur, and the regional stiffness of the tissue.
//!
//! **Frames.** The model's frame and the anatomy's leg frame share their
//! axes (x lateral, y anterior, z proximal); the model's origin is on the
//! leg's axis at `s = centre_s` ([`ThighGeometry::centre_s`]), so a model
//! point `(x, y, z)` is the leg point `(x, y, z − centre_s)` and
//! `s = centre_s − z`. The model's ring angle θ (`x = r cos θ`, `y = r sin θ`,
//! θ = π/2 anterior) is the anatomy's `θ_leg = θ − π/2` (θ_leg = 0 anterior,
//! π/2 medial): see [`leg_theta`].
//!
//! **Anchors.** A node's normal spring spans the soft tissue between the
//! skin and the femur: its rest length is the distance from the node to
//! the femur's nearest surface point in the node's transverse plane,
//! `|p − c| − r_f` (`c` the femur's centre, `r_f` its radius at the node's
//! `s`), and its anchor lies that far along the inward normal, so that the
//! spring acts normal to the skin as in the paper's Fig. 2 (a spring aimed
//! at the bone's centre instead would be oblique to a normal load, and its
//! compressed geometric stiffness, which the tangent omits, would then
//! matter). The rest length thus varies along the leg (the femur is
//! oblique: lateral under the greater trochanter, central at the knee) and
//! around it (the femur is off the leg's axis).
//!
//! **Regional stiffness.** Each node carries a factor on its normal
//! spring's stiffness: the patient's muscle factor
//! ([`echothigh_anatomy::Patient::muscle_stiffness_factor`]: `stiffness_scale`,
//! ×2 for a tense leg, reference row 19) times `1 + (canal_stiffness − 1)
//! w_s w_θ` over the adductor canal, where `w_s` rises from the apex of the
//! femoral triangle and falls to 0 at the adductor hiatus (smooth steps
//! over 2 cm, so the band is C¹ and gone where the femoral vein ends) and `w_θ = cos²(π Δθ / (2 · 0.6))` within 0.6 rad (≈ 50 mm of arc
//! on a 83 mm radius: the sartorius' width plus the canal's walls,
//! estimate) of the femoral vein's angle at that level.

use crate::config::{ConfigError, ThighGeometry};
use crate::Vec3;
use echothigh_anatomy::interp::smoothstep;
use echothigh_anatomy::{frame, Anatomy, Patient, StructureId};
use std::f64::consts::{FRAC_PI_2, PI};

/// Half-width (rad) of the adductor canal's stiffer band around the femoral
/// vein's angle (see the module docs; estimate).
pub const CANAL_HALF_ANGLE: f64 = 0.6;
/// Length (m) of the smooth steps that open and close the canal's band
/// along the leg (estimate: the sartorius crosses the vessels over ~2 cm).
pub const CANAL_RAMP: f64 = 0.02;

/// The anatomy's angle θ_leg (rad, 0 anterior, π/2 medial) of the model's
/// ring angle θ (rad, π/2 anterior, π medial): `θ − π/2`.
pub fn leg_theta(theta: f64) -> f64 {
    theta - FRAC_PI_2
}

/// The model's ring angle θ of the anatomy's θ_leg: `θ_leg + π/2`.
pub fn model_theta(theta_leg: f64) -> f64 {
    theta_leg + FRAC_PI_2
}

/// A node's rest geometry on the leg: skin point and outward normal (model
/// frame, m), anchor on the femur (m) and stiffness factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegNode {
    /// Skin point (m, model frame).
    pub position: Vec3,
    /// Outward unit normal of the skin.
    pub normal: Vec3,
    /// Anchor of the normal spring (m): on the inward normal, at the
    /// distance from the node to the femur's nearest surface point.
    pub anchor: Vec3,
    /// Factor on the normal spring's stiffness (regional and patient).
    pub stiffness: f64,
}

/// Where a hand holds the probe (model frame): the probe face's centre (m)
/// and the tool's orientation (model ← tool), the tool's local `y` along
/// the skin's outward normal (the face looks down its `−y`), local `z` the
/// leg's proximal direction projected on the skin's tangent plane, local
/// `x = y × z` (the image's lateral axis). At the anterior line of a
/// straight leg this is the identity, the runtime's `EXAM_ORIENTATION`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandTarget {
    /// Face centre (m, model frame).
    pub position: Vec3,
    /// Orientation, model ← tool.
    pub orientation: nalgebra::UnitQuaternion<f64>,
}

/// The leg of one patient, placed in the model's frame.
#[derive(Debug, Clone)]
pub struct LegSurface {
    anatomy: Anatomy,
    centre_s: f64,
    canal_stiffness: f64,
}

impl LegSurface {
    /// The leg of `geometry.patient` (a preset name; its full description
    /// `geometry.patient_spec` when a case set one), or `None` for the
    /// elliptic cylinder (`patient = ""`). Errors name `{prefix}.patient`
    /// (unknown preset) or `{prefix}.centre_s` (segment outside the femur).
    pub fn new(geometry: &ThighGeometry, prefix: &str) -> Result<Option<Self>, ConfigError> {
        if geometry.patient.is_empty() {
            return Ok(None);
        }
        let key = |f: &str| crate::config::key(prefix, f);
        let patient = match &geometry.patient_spec {
            Some(p) => p.clone(),
            None => Patient::preset(&geometry.patient).map_err(|e| {
                ConfigError::invalid(key("patient"), format!("= {:?}: {e}", geometry.patient))
            })?,
        };
        let anatomy = Anatomy::new(patient)
            .map_err(|e| ConfigError::invalid(key("patient"), e.to_string()))?;
        let knee = anatomy.levels().knee;
        let (s0, s1) = (
            geometry.centre_s - 0.5 * geometry.length,
            geometry.centre_s + 0.5 * geometry.length,
        );
        // The anchors need the femur, which spans s ∈ [0, knee].
        if !(s0 >= 0.0 && s1 <= knee) {
            return Err(ConfigError::invalid(
                key("centre_s"),
                format!(
                    "= {} m with length {} m spans s ∈ [{s0:.3}, {s1:.3}] m, which must lie \
                     within the femur of patient {:?}, s ∈ [0, {knee:.3}] m",
                    geometry.centre_s, geometry.length, geometry.patient
                ),
            ));
        }
        Ok(Some(LegSurface {
            anatomy,
            centre_s: geometry.centre_s,
            canal_stiffness: geometry.canal_stiffness,
        }))
    }

    /// The patient's anatomy (leg frame).
    pub fn anatomy(&self) -> &Anatomy {
        &self.anatomy
    }

    /// `s` (m below the inguinal ligament) of the model's height `z` (m).
    pub fn s_of_z(&self, z: f64) -> f64 {
        self.centre_s - z
    }

    /// A leg-frame point (m) in the model's frame.
    pub fn to_model(&self, p: &Vec3) -> Vec3 {
        Vec3::new(p.x, p.y, p.z + self.centre_s)
    }

    /// A model-frame point (m) in the leg frame.
    pub fn to_leg(&self, p: &Vec3) -> Vec3 {
        Vec3::new(p.x, p.y, p.z - self.centre_s)
    }

    /// The rest geometry of the node at ring angle θ (rad, model's
    /// convention) and height z (m); z must lie in the segment.
    pub fn node(&self, theta: f64, z: f64) -> LegNode {
        let s = self.s_of_z(z);
        let th = leg_theta(theta);
        let leg = self.anatomy.leg();
        let p = leg.skin_point(s, th);
        let normal = leg.skin_normal(s, th);
        let femur = self
            .anatomy
            .tube(StructureId::Femur)
            .expect("every anatomy has a femur");
        let c = femur.cross_section(s);
        let rest = (p.x - c.x).hypot(p.y - c.y) - c.r1.min(c.r2);
        let anchor = p - normal * rest;
        LegNode {
            position: self.to_model(&p),
            normal,
            anchor: self.to_model(&anchor),
            stiffness: self.stiffness_factor(s, th),
        }
    }

    /// The hand target of a probe on the skin at `s` (m below the inguinal
    /// ligament) and `θ_leg` (rad, 0 anterior, π/2 medial, π the popliteal
    /// fossa), its face `depth` (m) inside the rest skin along the inward
    /// normal (negative: above the skin), tilted by `tilt` (rad) about its
    /// lateral axis (a positive tilt aims the beam distally). Errors name
    /// the argument (`s` outside the leg, non-finite angles or depth).
    pub fn hand_target(
        &self,
        s: f64,
        theta_leg: f64,
        depth: f64,
        tilt: f64,
    ) -> Result<HandTarget, echothigh_anatomy::AnatomyError> {
        use echothigh_anatomy::AnatomyError::BadQuery;
        for (what, v) in [("angle", theta_leg), ("depth", depth), ("tilt", tilt)] {
            if !v.is_finite() {
                let reason = "must be finite";
                return Err(BadQuery {
                    what,
                    value: v,
                    reason,
                });
            }
        }
        let p = self.anatomy.skin_point(s, theta_leg)?;
        let n = self.anatomy.skin_normal(s, theta_leg)?;
        let z = (Vec3::z() - n * n.z).normalize();
        let x = n.cross(&z);
        let frame =
            nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[x, n, z]));
        let tilted = frame * nalgebra::Rotation3::from_axis_angle(&Vec3::x_axis(), tilt);
        Ok(HandTarget {
            position: self.to_model(&(p - n * depth)),
            orientation: nalgebra::UnitQuaternion::from_rotation_matrix(&tilted),
        })
    }

    /// The factor on the normal springs' stiffness at `(s, θ_leg)` (see the
    /// module docs): patient × adductor canal.
    pub fn stiffness_factor(&self, s: f64, theta_leg: f64) -> f64 {
        let lv = self.anatomy.levels();
        let w_s = smoothstep((s - lv.apex) / CANAL_RAMP)
            * (1.0 - smoothstep((s - lv.hiatus + CANAL_RAMP) / CANAL_RAMP));
        let w_theta = match self.anatomy.tube(StructureId::Fv) {
            Some(fv) if w_s > 0.0 => {
                let d = frame::wrap_angle(theta_leg - frame::theta_of(&fv.centre(s)));
                if d.abs() < CANAL_HALF_ANGLE {
                    (0.5 * PI * d / CANAL_HALF_ANGLE).cos().powi(2)
                } else {
                    0.0
                }
            }
            _ => 0.0,
        };
        self.anatomy.patient().muscle_stiffness_factor()
            * (1.0 + (self.canal_stiffness - 1.0) * w_s * w_theta)
    }
}
