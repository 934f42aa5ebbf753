//! The exam site (`[site]`, issue 12): where on the patient's leg the
//! scripted exam presses, with the probe held normal to the skin there.
//!
//! Without a site the `[exam]` vectors are in the model's frame and the
//! probe is held face down ([`crate::tick::EXAM_ORIENTATION`]), the paper's
//! setting on its cylinder. With one (`[site] name = "fv-mid"`, which
//! needs `[thigh] patient`), the `[exam]` vectors are read in the **site's
//! frame** instead: origin on the skin at the site, `x` across the image
//! (the probe's width), `y` out of the skin along its normal, `z` along the
//! leg towards the groin (the tool frame of
//! [`echothigh_model::HandTarget`]). So `start = [0, 0.02, -0.01]` is 20 mm
//! above the skin and 10 mm distal to the site, `press_direction = [0, -1,
//! 0]` presses along the inward normal, and a slide `direction = [0, 0, 1]`
//! glides along the vein towards the groin, whatever the site's angle
//! around the leg. The probe keeps the site's orientation (the beam along
//! the inward normal, the image transverse to the leg) for the whole run.

use echothigh_anatomy::Site;
use echothigh_device::{ExamConfig, PhaseConfig};
use echothigh_model::{LegSurface, ThighGeometry, Vec3};
use nalgebra::UnitQuaternion;
use serde::{Deserialize, Serialize};

/// `[site]`: the exam site on the patient's leg.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SiteConfig {
    /// A named exam site of `crates/anatomy` (`cfv`, `sfj`, `fv-proximal`,
    /// `fv-mid`, `fv-distal`, `popliteal`), resolved on `[thigh] patient`'s
    /// leg: the probe sits over the deep vein of that level, normal to the
    /// skin. Default `""`: no site, the `[exam]` vectors are in the model's
    /// frame.
    pub name: String,
}

/// The site's frame in the model's frame: a rigid transform (m, rotation
/// model ← site).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExamFrame {
    /// The site's skin point (m, model frame).
    pub origin: Vec3,
    /// Orientation of the site's frame (model ← site), also the probe's.
    pub rotation: UnitQuaternion<f64>,
}

impl ExamFrame {
    /// A point of the site's frame (m) in the model's frame.
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        (self.origin + self.rotation * Vec3::from(p)).into()
    }

    /// A direction of the site's frame in the model's frame.
    pub fn direction(&self, d: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vec3::from(d)).into()
    }

    /// The probe's orientation as the tick sends it (w, x, y, z).
    pub fn orientation_wxyz(&self) -> [f64; 4] {
        let q = self.rotation.quaternion();
        [q.w, q.i, q.j, q.k]
    }

    /// `exam` with its points and directions taken from the site's frame
    /// to the model's (lengths, speeds and forces unchanged).
    pub fn exam_in_model(&self, exam: &ExamConfig) -> ExamConfig {
        let mut out = exam.clone();
        out.start = self.point(exam.start);
        out.skin_point = self.point(exam.skin_point);
        out.press_direction = self.direction(exam.press_direction);
        for phase in &mut out.phases {
            match phase {
                PhaseConfig::Approach { point, .. } => *point = self.point(*point),
                PhaseConfig::Slide { direction, .. } => *direction = self.direction(*direction),
                PhaseConfig::Press { .. }
                | PhaseConfig::Hold { .. }
                | PhaseConfig::Release { .. } => {}
            }
        }
        out
    }
}

impl SiteConfig {
    /// The site's frame on `thigh`'s leg, `None` without a site. Errors name
    /// `{prefix}.name`: an unknown site, a site without a patient's leg, or
    /// a site outside the mesh's segment of the leg.
    pub fn resolve(
        &self,
        thigh: &ThighGeometry,
        prefix: &str,
    ) -> Result<Option<ExamFrame>, String> {
        if self.name.is_empty() {
            return Ok(None);
        }
        let key = format!("{prefix}.name");
        let site: Site = self
            .name
            .parse()
            .map_err(|e| format!("{key} = {:?}: {e}", self.name))?;
        let leg = LegSurface::new(thigh, "thigh")
            .map_err(|e| e.to_string())?
            .ok_or_else(|| {
                format!(
                    "{key} = {:?} needs a patient's leg: set [thigh] patient (e.g. \"lean-male\")",
                    self.name
                )
            })?;
        let pose = leg.anatomy().site_pose(site);
        // The press and its slide stay a probe's length inside the segment,
        // away from its held end rings.
        let z = thigh.centre_s - pose.s;
        let margin = 0.03;
        if z.abs() > 0.5 * thigh.length - margin {
            return Err(format!(
                "{key} = {:?} lies at s = {:.3} m, outside the mesh's segment s ∈ [{:.3}, {:.3}] m \
                 less {margin} m at each held end: move [thigh] centre_s or lengthen [thigh] length",
                self.name,
                pose.s,
                thigh.centre_s - 0.5 * thigh.length,
                thigh.centre_s + 0.5 * thigh.length
            ));
        }
        let target = leg
            .hand_target(pose.s, pose.theta, 0.0, pose.tilt)
            .map_err(|e| format!("{key} = {:?}: {e}", self.name))?;
        Ok(Some(ExamFrame {
            origin: target.position,
            rotation: target.orientation,
        }))
    }
}
