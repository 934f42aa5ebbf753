//! What the scripted trainee sees under the probe at one site (issue 14):
//! the case's section there (its thrombi included) and, at each sample, the
//! vein's and the artery's lumen ratios under the physics' deformation —
//! the renderer's lumen law ([`Renderer::lumens`]), without forming the
//! image.

use crate::physics_side::probe_pose;
use crate::section::{section_deformation, SectionScratch};
use crate::section_follow::leg_pose;
use crate::section_image::section_anatomy_with;
use anyhow::{Context, Result};
use echothigh_anatomy::{Anatomy, ProbePose, Thrombi};
use echothigh_imaging::{FrameInput, ImagingConfig, Renderer, SectionDeformation, VeinState};
use echothigh_model::{LegSurface, ThighModel};
use echothigh_transport::ProbeMsg;

/// Skin displacement samples across the image (the static press of
/// [`crate::section::press_to_force`] uses the same 81).
const DEFORMATION_SAMPLES: usize = 81;

/// One look at the vein and the artery.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Look {
    /// Vein lumen area over rest.
    pub vein_ratio: f64,
    /// Artery lumen area over rest.
    pub artery_ratio: f64,
    /// Where the image cuts the leg (m below the inguinal ligament), on the
    /// case's leg: the section drawn at the site (the probe's drift under
    /// the press, a few mm, is in `skin`, and the section is not redrawn
    /// for it).
    pub s: f64,
    /// The probe's face centre on the skin: `[s, arc around the leg from
    /// the site]` (m).
    pub skin: [f64; 2],
}

/// The section at one site and the scratch to measure it.
pub struct SiteProbe {
    renderer: Renderer,
    cfg: ImagingConfig,
    site_pose: ProbePose,
    /// `s` of the case's site minus `s` of the physics' press point (m).
    s_shift: f64,
    orientation: [f64; 4],
    bone: f64,
    scratch: SectionScratch,
    deformation: SectionDeformation,
}

impl SiteProbe {
    /// The probe over the case's site at `pose` (on `anatomy`, with
    /// `thrombi`), pressing the physics at `s_phys` with `orientation`.
    pub fn new(
        base: &ImagingConfig,
        anatomy: &Anatomy,
        thrombi: &Thrombi,
        pose: ProbePose,
        s_phys: f64,
        orientation: [f64; 4],
    ) -> Result<Self> {
        let mut cfg = base.clone();
        cfg.anatomy = section_anatomy_with(&cfg.anatomy, anatomy, &pose, Some(thrombi))
            .with_context(|| format!("the section at s = {:.1} mm", pose.s * 1e3))?;
        let renderer =
            Renderer::new(&cfg, VeinState::Healthy).map_err(|e| anyhow::anyhow!("imaging: {e}"))?;
        let bone = renderer
            .anatomy()
            .map(|a| a.femur_top())
            .context("the section has no anatomy")?;
        Ok(SiteProbe {
            renderer,
            site_pose: pose,
            s_shift: pose.s - s_phys,
            orientation,
            bone,
            scratch: SectionScratch::default(),
            deformation: SectionDeformation::rest(bone),
            cfg,
        })
    }

    /// The lumens with the probe's face centre at `position` (m, model
    /// frame) pressing with `force` (N) at time `t` (s), the tissue as
    /// `model` has it now.
    pub fn look(
        &mut self,
        model: &ThighModel,
        leg: &LegSurface,
        position: [f64; 3],
        force: f64,
        t: f64,
    ) -> Result<Look> {
        let pose3 = probe_pose(&ProbeMsg::new(t, position, self.orientation, 0));
        section_deformation(
            model,
            &pose3,
            self.cfg.width,
            DEFORMATION_SAMPLES,
            self.bone,
            &mut self.scratch,
            &mut self.deformation,
        );
        let at = leg_pose(leg, position, self.orientation)?;
        let a = leg.anatomy();
        // The probe's drift from the site around the leg (θ wrapped to
        // (−π, π]: the popliteal site sits at θ ≈ ±π), as an arc on the
        // local skin radius, signed along the image's lateral axis (which
        // flips with cos θ, see `section_follow`'s material coordinates).
        let tau = std::f64::consts::TAU;
        let dtheta = (at.theta - self.site_pose.theta + std::f64::consts::PI).rem_euclid(tau)
            - std::f64::consts::PI;
        let sign = if self.site_pose.theta.cos() >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let offset = sign * dtheta * a.leg().skin_radius(at.s, at.theta);
        let input = FrameInput {
            deformation: &self.deformation,
            probe_pressure: force / self.cfg.probe_area(),
            time: t,
            lateral_offset: offset,
        };
        let l = self
            .renderer
            .lumens(&input)
            .map_err(|e| anyhow::anyhow!("imaging: {e}"))?
            .context("the section has no vessels")?;
        Ok(Look {
            vein_ratio: l.vein.area / l.vein.rest_area,
            artery_ratio: l.artery.area / l.artery.rest_area,
            s: self.site_pose.s,
            skin: [at.s + self.s_shift, offset],
        })
    }
}
