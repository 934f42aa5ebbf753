//! The condition of one vein of the section (issue 13): each vein drawn —
//! the studied one and every vein of `structures` — carries its own lumen
//! law and echoes instead of the one global [`VeinState`].
//!
//! A vein's lumen holds blood and, over a fraction `fill` of its rest area,
//! thrombus or fibrous content. The two parts yield differently: the lumen
//! area relative to rest is
//! `c(p) = fill · c_content(p) + (1 − fill) · c_open(p)`, each `c_x` the
//! smooth collapsible-tube law of [`crate::anatomy`] with its own onset,
//! full pressure and smallest ratio. With `fill = 1` (occlusive) this is
//! the content's law alone; with `fill = 0` the healthy law. Where the
//! content sits in the cross-section is its [`ContentLayout`]: in each
//! column through the lumen, the deepest `fill` of the chord (mural: a
//! thrombus on the dependent wall, chronic synechiae) or its central `fill`
//! (a free-floating tail with blood all round); either way the content's
//! area is `fill` of the lumen's.

use crate::anatomy_config::{VeinState, VeinStateParams};
use crate::error::ImagingError;
use crate::post_thrombotic::PostThrombotic;
use serde::{Deserialize, Serialize};

/// Where the content sits in the lumen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ContentLayout {
    /// Against the deep wall.
    #[default]
    Mural,
    /// In the middle of the lumen.
    Central,
}

/// One collapsible-tube law: the area ratio falls smoothly from 1 at
/// `onset` to `min_ratio` at `full` (tissue pressure at the vessel, Pa).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollapseLaw {
    /// Pressure where flattening starts (Pa), in [0, 1e5].
    pub onset: f64,
    /// Pressure of the smallest area (Pa), above `onset`, at most 1e5.
    pub full: f64,
    /// Smallest area relative to rest, in [0, 1].
    pub min_ratio: f64,
}

impl CollapseLaw {
    /// The law of a vein state's parameters.
    pub fn of(p: &VeinStateParams) -> CollapseLaw {
        CollapseLaw {
            onset: p.collapse_onset,
            full: p.collapse_full,
            min_ratio: p.min_lumen_ratio,
        }
    }

    /// Area ratio under the tissue pressure `p` (Pa): `1 − (1 − c_min) S(t)`,
    /// `S(t) = 3t² − 2t³`, `t = (p − onset)/(full − onset)` clamped to [0, 1].
    pub fn ratio(&self, p: f64) -> f64 {
        let t = ((p - self.onset) / (self.full - self.onset)).clamp(0.0, 1.0);
        1.0 - (1.0 - self.min_ratio) * t * t * (3.0 - 2.0 * t)
    }

    fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "onset",
            self.onset,
            0.0,
            1e5,
            "must be between 0 and 1e5 Pa",
        )?;
        if !(self.full > self.onset && self.full <= 1e5) {
            return Err(ImagingError::invalid(
                prefix,
                "full",
                self.full,
                "must exceed onset and be at most 1e5 Pa",
            ));
        }
        ImagingError::in_range(
            prefix,
            "min_ratio",
            self.min_ratio,
            0.0,
            1.0,
            "must be in [0, 1]",
        )
    }
}

/// The condition of one vein (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VeinCondition {
    /// Diameter relative to the healthy vein, in [0.2, 2].
    pub diameter_factor: f64,
    /// Wall thickness (m), in [0.1, 5] mm.
    pub wall_thickness: f64,
    /// Wall backscatter relative to muscle (dB), in [−80, 30].
    pub wall_echo: f64,
    /// Fraction of the rest lumen's area that is content, in [0, 1].
    pub fill: f64,
    /// Where the content sits.
    #[serde(default)]
    pub layout: ContentLayout,
    /// Content backscatter relative to muscle (dB), in [−80, 30].
    pub content_echo: f64,
    /// Content attenuation (dB/(cm·MHz)), in [0, 5].
    pub content_attenuation: f64,
    /// Law of the content.
    pub content_law: CollapseLaw,
    /// Law of the open (blood) part.
    pub open_law: CollapseLaw,
    /// Chronic post-thrombotic change as drawn: irregular wall, webs and
    /// recanalized channels ([`PostThrombotic`]); `None` draws the content
    /// by `layout`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub post_thrombotic: Option<PostThrombotic>,
    /// Relative sway of a free-floating tail here, in [0, 1] (0: none, 1:
    /// at its free tip): with breathing, the central content moves across
    /// the lumen ([`VeinCondition::tail_shift`]).
    #[serde(default)]
    pub sway: f64,
}

/// Breathing rate (Hz): 0.25, 15 breaths per minute, the middle of the
/// adult resting range of 12–20 per minute (e.g. StatPearls, "Physiology,
/// Respiratory Rate").
pub const BREATHING_RATE: f64 = 0.25;

/// Fraction of the free gap between a floating tail and the wall over
/// which its free tip swings with breathing: 0.5. Derivation: free-floating
/// thrombi are seen to move with respiration inside the lumen without
/// striking the wall (abcvascular.com, "free-floating distal thrombus
/// tongue", the reference's row 25); no measured amplitude was found, so
/// the tip swings half-way to the wall on each side (≈ 2 mm in a 12 mm
/// distended CFV with a tail filling 35 % of each chord).
pub const TAIL_SWING: f64 = 0.5;

impl VeinCondition {
    /// The condition of a vein in a global [`VeinState`] (the simple case: one
    /// segment along the whole vein): healthy is all blood with the
    /// healthy law; acute and chronic fill the lumen with their content.
    pub fn of_state(
        state: VeinState,
        params: &VeinStateParams,
        healthy: &VeinStateParams,
    ) -> VeinCondition {
        VeinCondition {
            diameter_factor: params.diameter_factor,
            wall_thickness: params.wall_thickness,
            wall_echo: params.wall_echo,
            fill: if state == VeinState::Healthy {
                0.0
            } else {
                1.0
            },
            layout: ContentLayout::Mural,
            content_echo: params.content_echo,
            content_attenuation: params.content_attenuation,
            content_law: CollapseLaw::of(params),
            open_law: CollapseLaw::of(healthy),
            post_thrombotic: None,
            sway: 0.0,
        }
    }

    /// Shift of a free-floating tail at time `time` (s), as a fraction of
    /// the lumen's half-height in each column (positive deeper):
    /// `sway · TAIL_SWING · (1 − fill) · sin(2π f_b t)`, `f_b` the
    /// [`BREATHING_RATE`]; `(1 − fill) h` is the free gap between a central
    /// content of `fill` of the chord and the wall. 0 unless the content
    /// is central (a floating tail).
    pub fn tail_shift(&self, time: f64) -> f64 {
        if self.layout != ContentLayout::Central || self.fill <= 0.0 || !time.is_finite() {
            return 0.0;
        }
        let phase = (time * BREATHING_RATE).rem_euclid(1.0);
        self.sway * TAIL_SWING * (1.0 - self.fill) * (std::f64::consts::TAU * phase).sin()
    }

    /// A healthy vein (the healthy defaults of [`VeinStateParams::healthy`]).
    pub fn healthy() -> VeinCondition {
        let h = VeinStateParams::healthy();
        VeinCondition::of_state(VeinState::Healthy, &h, &h)
    }

    /// Lumen area relative to rest under the tissue pressure `p` (Pa) at the vein.
    pub fn lumen_ratio(&self, p: f64) -> f64 {
        self.fill * self.content_law.ratio(p) + (1.0 - self.fill) * self.open_law.ratio(p)
    }

    /// Smallest lumen area relative to rest (under any pressure).
    pub fn min_lumen_ratio(&self) -> f64 {
        self.fill * self.content_law.min_ratio + (1.0 - self.fill) * self.open_law.min_ratio
    }

    /// Whether the point at normalised chord position `eta` (−1 at the
    /// lumen's top in its column, +1 at its bottom) is content.
    pub fn is_content(&self, eta: f64) -> bool {
        match self.layout {
            ContentLayout::Mural => eta > 1.0 - 2.0 * self.fill,
            ContentLayout::Central => eta.abs() < self.fill,
        }
    }

    /// Checks every field, naming the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "diameter_factor",
            self.diameter_factor,
            0.2,
            2.0,
            "must be between 0.2 and 2",
        )?;
        ImagingError::in_range(
            prefix,
            "wall_thickness",
            self.wall_thickness,
            1e-4,
            5e-3,
            "must be between 0.1 and 5 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "wall_echo",
            self.wall_echo,
            -80.0,
            30.0,
            "must be between -80 and 30 dB",
        )?;
        ImagingError::in_range(prefix, "fill", self.fill, 0.0, 1.0, "must be in [0, 1]")?;
        ImagingError::in_range(
            prefix,
            "content_echo",
            self.content_echo,
            -80.0,
            30.0,
            "must be between -80 and 30 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "content_attenuation",
            self.content_attenuation,
            0.0,
            5.0,
            "must be between 0 and 5 dB/(cm MHz)",
        )?;
        ImagingError::in_range(prefix, "sway", self.sway, 0.0, 1.0, "must be in [0, 1]")?;
        if let Some(pt) = &self.post_thrombotic {
            pt.validate(&format!("{prefix}.post_thrombotic"))?;
        }
        self.content_law
            .validate(&format!("{prefix}.content_law"))?;
        self.open_law.validate(&format!("{prefix}.open_law"))
    }
}
