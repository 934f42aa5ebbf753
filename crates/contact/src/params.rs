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
    /// Contact rigidity `λ_c`, N/m³ (default 5e7: under the default probe,
    /// 20 N/mm of face stiffness, ~40× the tissue's initial stiffness, so a
    /// 15 N press penetrates ~0.75 mm).
    pub stiffness: f64,
    /// Contact damping `μ_c`, N·s/m³ (default 2e4, about half the critical
    /// damping of the contact spring against the default areal mass).
    pub damping: f64,
    /// Spacing of the face samples that measure the penetrated volume, m
    /// (default 0.002: 20 × 5 samples on the default face).
    pub sample_spacing: f64,
    /// Extra margin of the broad-phase box around the probe body, m (default
    /// 0.003): candidates are gathered once per step, before the Newton
    /// iterations move the nodes.
    pub margin: f64,
    /// Out of contact, the stiffness sent to the haptic side is that of the
    /// surface the face would meet first: the face samples whose surface
    /// lies within this band of the highest one, m (default 0.002).
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
        ConfigError::positive(prefix, "stiffness", self.stiffness)?;
        ConfigError::non_negative(prefix, "damping", self.damping)?;
        ConfigError::positive(prefix, "sample_spacing", self.sample_spacing)?;
        ConfigError::non_negative(prefix, "margin", self.margin)?;
        ConfigError::non_negative(prefix, "first_contact_band", self.first_contact_band)?;
        Ok(())
    }
}
