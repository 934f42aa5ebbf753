//! `[contact]`: the penalty contact's parameters (paper Eq. 2).

use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// Penalty contact parameters, the `[contact]` section of a scenario.
///
/// Eq. 2 gives each penetrating node the force `(−λ_c v − μ_c v̇) k̂` with
/// `v = −depth × area` the (negative) penetrated volume, so `λ_c` is a force
/// per volume (N/m³) and `μ_c` a force per volume rate (N·s/m³). Per unit
/// face area, `λ_c` is a stiffness (Pa/m) comparable with the tissue's
/// initial stiffness per unit area, `1/tissue.normal_b`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactParams {
    /// Contact rigidity `λ_c`, N/m³, in [1e5, 1e10]: from about the softest
    /// tissue's stiffness per area (`1/tissue.normal_b` ≥ 1e3 Pa/m, so the
    /// probe still dominates) to 200× the default (beyond, a node's contact
    /// stiffness over its mass, `(λ_c/ρ_A) h²`, exceeds 1e7 at 100 Hz and
    /// the Newton system loses most of its digits). Default 5e7: under the
    /// default probe, 20 N/mm of face stiffness, ~40× the tissue's initial
    /// stiffness, so a 15 N press penetrates ~0.75 mm.
    pub stiffness: f64,
    /// Contact damping `μ_c`, N·s/m³, in [0, 1e7] (none to ~30× critical
    /// at the stiffest `λ_c` against 10 kg/m²: `2 √(λ_c ρ_A)` ≈ 6e5). Default
    /// 2e4, about half the critical damping of the contact spring against
    /// the default areal mass.
    pub damping: f64,
    /// Spacing of the face samples that measure the penetrated volume, m, in
    /// [2e-4, 0.01]: from 0.2 mm (finer than the mesh or the image can
    /// resolve; bounds the largest face, 100 × 40 mm, to 1e5 samples) to
    /// 10 mm (a few samples across the face). Default 0.002: 20 × 5 samples
    /// on the default face.
    pub sample_spacing: f64,
    /// Extra margin of the broad-phase box around the probe body, m, in [0,
    /// 0.05] (a node moves a few mm per step at most; 50 mm already gathers
    /// a large part of the segment). Default 0.003: candidates are gathered
    /// once per step, before the Newton iterations move the nodes.
    pub margin: f64,
    /// Out of contact, the stiffness sent to the haptic side is that of the
    /// surface the face would meet first: the face samples whose surface
    /// lies within this band of the highest one, m, in [0, 0.02] (up to the
    /// probe's half-elevation scale). Default 0.002.
    pub first_contact_band: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            stiffness: 5.0e7,
            damping: 2.0e4,
            sample_spacing: 0.002,
            margin: 0.003,
            first_contact_band: 0.002,
        }
    }
}

impl ContactParams {
    /// Checks every field; errors name the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let stiff = "must be in [1e5, 1e10] N/m³ (softest tissue to 200x the default)";
        ConfigError::in_range(p, "stiffness", self.stiffness, (1e5, 1e10), stiff)?;
        let damp = "must be in [0, 1e7] N·s/m³ (none to far past critical damping)";
        ConfigError::in_range(p, "damping", self.damping, (0.0, 1e7), damp)?;
        let spacing = "must be in [2e-4, 0.01] m (0.2 mm bounds the face to 1e5 samples)";
        ConfigError::in_range(
            p,
            "sample_spacing",
            self.sample_spacing,
            (2e-4, 0.01),
            spacing,
        )?;
        let margin = "must be in [0, 0.05] m (a few mm of node motion per step)";
        ConfigError::in_range(p, "margin", self.margin, (0.0, 0.05), margin)?;
        let band = "must be in [0, 0.02] m (the probe's elevation scale)";
        ConfigError::in_range(
            p,
            "first_contact_band",
            self.first_contact_band,
            (0.0, 0.02),
            band,
        )?;
        Ok(())
    }
}
