//! The probe force a compression should reach under the probe's present
//! position (issue 19: "the target band for the current patient" on the
//! page's force gauge).
//!
//! Trainees are taught to press until a healthy vein's walls meet, and, if
//! they do not, until the companion artery begins to deform (fidelity
//! review §1 "Positive criterion", §4 item 5). The band runs from the
//! probe force at which a **healthy** vein here would meet its walls to
//! the force at which the artery is clearly oval (120 mmHg at its centre,
//! §4 item 5: "ovalise visibly from ~60–80 mmHg … clearly by ~120 mmHg"):
//! below it the press proves nothing, above it the press adds nothing.
//! The band uses the healthy vein's law whatever the case's disease, so
//! it gives nothing of the diagnosis away.
//!
//! Both ends invert the image's own force chain ([`Renderer::lumens`]):
//! the mean face pressure `p = F / A` (face area `A`) reaches a vessel's
//! centre attenuated by Newmark's influence factor `I` ([`crate::pressure`],
//! `σ = p I`), and the lumen laws map `σ` to a lumen ratio. So
//! `F = A σ* / I`, with `σ*` the stress the law needs. `I` is taken at the
//! vessel's centre in the frame's present deformation (the vessel comes
//! closer to the face as the tissue is pressed, so the band settles as the
//! press approaches it and is exact at the force it names).

use crate::anatomy_config::{VeinState, MMHG};
use crate::deformation::column_depth;
use crate::error::ImagingError;
use crate::pressure::stress_under_rectangle;
use crate::render::{FrameInput, Renderer};
use crate::vein_condition::VeinCondition;
use crate::Vessel;

/// Tissue pressure at the artery's centre at which it is clearly oval (Pa):
/// 120 mmHg (fidelity review §4 item 5).
pub const ARTERY_CLEARLY_OVAL: f64 = 120.0 * MMHG;

/// The probe forces (N, tissue force) of the target band at one probe pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetBand {
    /// Force at which a healthy vein here meets its walls (its lumen ratio
    /// falls to the coaptation ratio asked for).
    pub walls_meet: f64,
    /// Force at which the companion artery is clearly oval
    /// ([`ARTERY_CLEARLY_OVAL`] at its centre).
    pub artery_clearly_oval: f64,
}

/// The tissue pressure (Pa) at which `law` first reaches `ratio`, by
/// bisection on the law's monotone collapse (to 1e-3 Pa, far below the
/// 0.13 Pa of 1 mmHg); `None` if the law never falls that low.
fn pressure_for_ratio(law: &VeinCondition, ratio: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0, 1.0e5);
    if law.lumen_ratio(hi) > ratio {
        return None;
    }
    if law.lumen_ratio(lo) <= ratio {
        return Some(0.0);
    }
    while hi - lo > 1e-3 {
        let mid = 0.5 * (lo + hi);
        if law.lumen_ratio(mid) <= ratio {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

impl Renderer {
    /// Newmark's influence factor (σ per unit face pressure) at the centre of
    /// `v` in the frame `input`: the same point [`Renderer::lumens`] reads;
    /// `None` when that centre is outside the image's width (the trainee
    /// does not see the vessel, and a probe beside it would need forces
    /// no one should apply).
    fn influence_at(&self, v: &Vessel, input: &FrameInput) -> Option<f64> {
        let cfg = self.config();
        let def = input.deformation;
        let face = def.face_depth(0.5 * cfg.width);
        let lateral = v.lateral - self.pan(input.lateral_offset).0;
        if lateral.abs() > 0.5 * cfg.width {
            return None;
        }
        let s = def.surface_at(lateral);
        let centre = column_depth(s, def.bone_depth, v.depth) - face;
        Some(stress_under_rectangle(
            1.0,
            cfg.probe_width,
            cfg.probe_elevation,
            lateral,
            0.0,
            centre.max(0.0),
        ))
    }

    /// The target band (module doc) for the frame `input`, with the walls
    /// counted as met below the lumen ratio `coapted` (e.g. 0.1: issue 13's
    /// criterion). `None` for a phantom, when `coapted` is not in (0, 1),
    /// when the vein or its artery is outside the image, or when they lie
    /// outside the stress the probe can reach.
    pub fn target_band(
        &self,
        input: &FrameInput,
        coapted: f64,
    ) -> Result<Option<TargetBand>, ImagingError> {
        // The frame's numbers are checked as `lumens` checks them.
        if self.lumens(input)?.is_none() || !(coapted > 0.0 && coapted < 1.0) {
            return Ok(None);
        }
        let Some(a) = self.anatomy() else {
            return Ok(None);
        };
        let healthy = VeinCondition::of_state(
            VeinState::Healthy,
            a.config().vein(VeinState::Healthy),
            a.config().vein(VeinState::Healthy),
        );
        let Some(p_close) = pressure_for_ratio(&healthy, coapted) else {
            return Ok(None);
        };
        let area = self.config().probe_area();
        let force = |v: &Vessel, stress: f64| {
            let i = self.influence_at(v, input)?;
            (i > 1e-6).then(|| area * stress / i)
        };
        Ok(
            match (
                force(a.vein(), p_close),
                force(a.artery(), ARTERY_CLEARLY_OVAL),
            ) {
                (Some(walls_meet), Some(artery_clearly_oval)) => Some(TargetBand {
                    walls_meet,
                    artery_clearly_oval,
                }),
                _ => None,
            },
        )
    }
}
