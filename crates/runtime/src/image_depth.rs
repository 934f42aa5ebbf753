//! The image depth a sonographer would set for a patient (issue 21, issue
//! 13's follow-up: "the obese vein lies below the fixed 60 mm image depth
//! in 13 of 21 sections").
//!
//! The depth knob's rule: the deepest edge of the region of interest sits
//! about three quarters of the way down the image, which shows all of it
//! and some tissue below it for context (its shadow, its enhancement)
//! without wasting the screen (searcyem.com, "Ultrasound image depth",
//! 2025; the same ¾ rule in the knobology course notes of S. Batool; "align
//! the target to the centre of the monitor and show the entire target",
//! usabcd.org basic physics). The region of interest of a compression exam
//! is the deep vein of the level, which lies 22 mm deep at a lean man's
//! groin and 71 mm in an obese popliteal fossa (`every_preset_vein_fits_its_
//! image` prints the figures), so the depth follows the level as the
//! sonographer's hand on the knob does: each section the live imaging
//! thread builds sets its own ([`section_depth`], in whole centimetres as a
//! scanner's depth steps), and the frame's reading carries it to the page's
//! depth scale. [`patient_image_depth`] is the one depth that shows the
//! deepest vein of a patient's whole exam (for a fixed-depth image).

use crate::section_image::section_anatomy;
use anyhow::{Context, Result};
use echothigh_anatomy::Anatomy;
use echothigh_imaging::{AnatomyConfig, VeinState};

/// Fraction of the image depth at which the deepest vein wall lies at most.
pub const DEEPEST_WALL_FRACTION: f64 = 0.75;
/// The scanner's depth step (m): whole centimetres.
pub const DEPTH_STEP: f64 = 0.01;
/// The shallowest depth the rule sets (m). Our choice, not sourced: the
/// rule alone would give 3 cm at a lean groin (far wall 22 mm), which cuts
/// off the femur under the vessels, the landmark a trainee orients by.
pub const MIN_DEPTH: f64 = 0.04;
/// The deepest (m): the upper end of the 4–10 cm over which a thigh is
/// imaged (`ImagingConfig::depth`'s documented range; not a measured
/// penetration of the 7.5 MHz probe). The obese popliteal fossa reaches it.
pub const MAX_DEPTH: f64 = 0.10;
/// Spacing of the levels sampled along the leg (m): finer than any vessel's
/// change of depth that matters at a 1 cm depth step.
const LEVEL_STEP: f64 = 0.005;

/// The far wall of `section`'s studied vein (m below the skin).
pub fn vein_far_wall(section: &AnatomyConfig) -> Result<f64> {
    let a = echothigh_imaging::Anatomy::new(section, VeinState::Healthy)
        .map_err(|e| anyhow::anyhow!("the section's imaging anatomy: {e}"))?;
    let v = a.vein();
    Ok(v.depth + v.half_height() + v.wall)
}

/// The image depth (m) of one section: [`depth_for_wall`] of its studied
/// vein's far wall.
pub fn section_depth(section: &AnatomyConfig) -> Result<f64> {
    Ok(depth_for_wall(vein_far_wall(section)?))
}

/// Deepest far wall of the deep vein (m below the skin) over the levels
/// from the inguinal ligament to the knee, each section taken over the
/// vein as the exam's probe would be (`Anatomy::pose_over`).
pub fn deepest_vein_wall(anatomy: &Anatomy, base: &AnatomyConfig) -> Result<f64> {
    let knee = anatomy.levels().knee;
    let n = (knee / LEVEL_STEP).ceil() as usize;
    let mut deepest: f64 = 0.0;
    for k in 0..=n {
        let s = (k as f64 * LEVEL_STEP).min(knee);
        let pose = anatomy
            .pose_over(s, anatomy.deep_vein_at(s))
            .with_context(|| format!("the section over the deep vein at {:.0} mm", s * 1e3))?;
        let cfg = section_anatomy(base, anatomy, &pose)?;
        let wall =
            vein_far_wall(&cfg).with_context(|| format!("the section at {:.0} mm", s * 1e3))?;
        deepest = deepest.max(wall);
    }
    Ok(deepest)
}

/// The image depth (m) for a deepest vein wall at `wall` (m): the wall at
/// no more than [`DEEPEST_WALL_FRACTION`] of the image, rounded up to the
/// next [`DEPTH_STEP`], within [`MIN_DEPTH`, `MAX_DEPTH`].
pub fn depth_for_wall(wall: f64) -> f64 {
    let steps = (wall / DEEPEST_WALL_FRACTION / DEPTH_STEP - 1e-9).ceil();
    (steps * DEPTH_STEP).clamp(MIN_DEPTH, MAX_DEPTH)
}

/// The image depth (m) for `anatomy`'s patient ([`deepest_vein_wall`],
/// [`depth_for_wall`]).
pub fn patient_image_depth(anatomy: &Anatomy, base: &AnatomyConfig) -> Result<f64> {
    Ok(depth_for_wall(deepest_vein_wall(anatomy, base)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use echothigh_anatomy::{Patient, PRESETS};
    use echothigh_imaging::ImagingConfig;

    /// The rule's arithmetic: 44 mm / 0.75 = 58.7 mm → 6 cm; exactly 45 mm
    /// → 60 mm (not 7 cm from rounding noise); the clamps.
    #[test]
    fn depth_steps_and_clamps() {
        assert!((depth_for_wall(0.044) - 0.06).abs() < 1e-12);
        assert!((depth_for_wall(0.045) - 0.06).abs() < 1e-12);
        assert!((depth_for_wall(0.0451) - 0.07).abs() < 1e-12);
        assert!((depth_for_wall(0.01) - MIN_DEPTH).abs() < 1e-12);
        assert!((depth_for_wall(0.2) - MAX_DEPTH).abs() < 1e-12);
    }

    /// Every preset patient's deep vein lies inside its image at every
    /// level, with its deepest wall at ¾ of the depth or less, and the depth
    /// is no deeper than one step more than that needs (the screen is not
    /// wasted); the depth grows with build (fat thickens from lean to
    /// obese: issue 12's presets).
    #[test]
    fn every_preset_vein_fits_its_image() {
        let base = ImagingConfig::default().anatomy;
        let mut last = 0.0;
        for preset in PRESETS {
            let a = Anatomy::new(Patient::preset(preset).unwrap()).unwrap();
            let wall = deepest_vein_wall(&a, &base).unwrap();
            let depth = patient_image_depth(&a, &base).unwrap();
            eprintln!(
                "{preset}: deepest vein wall {:.1} mm, image depth {:.0} mm",
                wall * 1e3,
                depth * 1e3
            );
            assert!(wall <= DEEPEST_WALL_FRACTION * depth + 1e-12, "{preset}");
            assert!(
                wall > DEEPEST_WALL_FRACTION * (depth - DEPTH_STEP) || depth == MIN_DEPTH,
                "{preset}: {depth} m is a step deeper than needed"
            );
            assert!(depth >= last, "{preset}: {depth} m after {last} m");
            last = depth;
        }
    }
}
