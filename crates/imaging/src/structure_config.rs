//! The structures of a section beyond the studied vein–artery pair
//! (`[[imaging.anatomy.structures]]`): the other vessels, muscle outlines
//! and lymph nodes a plane through the 3D leg cuts (`echothigh-anatomy`'s
//! section), each an ellipse in tissue coordinates.

use crate::error::ImagingError;
use crate::vein_condition::VeinCondition;
use serde::{Deserialize, Serialize};

/// Largest number of extra structures in a section.
pub const MAX_STRUCTURES: usize = 12;

/// What an extra structure is, which sets how it is drawn and deforms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StructureKind {
    /// A patent vein (healthy lumen law and echoes, whatever the studied
    /// vein's state): collapses under the tissue pressure at its centre.
    Vein,
    /// An artery: the artery lumen law (deformation cue and pulse) of
    /// `[imaging.anatomy]` at its own tissue pressure.
    Artery,
    /// A muscle belly: drawn as its outline (an echogenic epimysium line of
    /// the fascia's thickness), muscle inside.
    Muscle,
    /// A lymph node: hypoechoic cortex around an echogenic fatty hilum.
    LymphNode,
}

/// One extra structure: an ellipse in tissue coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Name (the anatomy id, e.g. `gsv`, `dfa`, `sartorius`), for messages.
    pub name: String,
    /// What it is.
    pub kind: StructureKind,
    /// Lateral position of the centre (m, from the probe's centre, positive
    /// towards the image's right). Accepted: within ±0.2 m.
    pub lateral: f64,
    /// Depth of the centre below the undeformed skin (m). Accepted: 0 to 0.25 m.
    pub depth: f64,
    /// Semi-axes `[a, b]` of the lumen (vessels) or outline (m); `a` at
    /// `angle` from the lateral axis. Accepted: each 0.2 to 100 mm.
    pub radii: [f64; 2],
    /// Angle of the `a` axis from the lateral direction towards depth (rad).
    /// Accepted: in [−π/2, π/2].
    pub angle: f64,
    /// Wall thickness of a vessel (m); ignored otherwise. Accepted: 0 to 3 mm.
    pub wall: f64,
    /// A vein's own condition (issue 13: its thrombus segment state at the
    /// section); default none, a healthy vein (its `radii` and `wall` as
    /// given). When set, the radii are scaled by its `diameter_factor` and
    /// the wall is its `wall_thickness`. Only for `kind = "vein"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition: Option<VeinCondition>,
}

impl StructureConfig {
    /// Checks every field, naming the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "lateral",
            self.lateral,
            -0.2,
            0.2,
            "must be between -200 and 200 mm of the probe centre",
        )?;
        ImagingError::in_range(
            prefix,
            "depth",
            self.depth,
            0.0,
            0.25,
            "must be between 0 and 250 mm below the skin",
        )?;
        for r in self.radii {
            ImagingError::in_range(
                prefix,
                "radii",
                r,
                2e-4,
                0.1,
                "each must be between 0.2 and 100 mm",
            )?;
        }
        ImagingError::in_range(
            prefix,
            "angle",
            self.angle,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
            "must be in [-pi/2, pi/2] rad",
        )?;
        ImagingError::in_range(
            prefix,
            "wall",
            self.wall,
            0.0,
            3e-3,
            "must be between 0 and 3 mm",
        )?;
        if let Some(c) = &self.condition {
            if self.kind != StructureKind::Vein {
                return Err(ImagingError::invalid(
                    prefix,
                    "condition",
                    self.name.as_str(),
                    "only a vein has a condition",
                ));
            }
            c.validate(&format!("{prefix}.condition"))?;
        }
        Ok(())
    }
}
