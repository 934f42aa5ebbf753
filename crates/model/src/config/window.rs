//! `[integrator.window]`: the active window (issue 18), off by default.

use super::{key, range, ConfigError};
use serde::{Deserialize, Serialize};

/// The active window: only the nodes near the probe are integrated
/// implicitly, the others are held (see [`crate::window`]).
///
/// Distances are arc lengths on the rest surface (m), measured on the
/// `n_θ × n_z` grid with the mesh's mean spacings around and along: the
/// window is the grid rectangle of half-widths `radius + margin` around
/// its centre node (a square in surface length, not a disc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindowParams {
    /// Integrate only the window (true) or the whole mesh (false, the
    /// default: the full model is the reference the window is checked
    /// against, `crates/contact/tests/suite/window.rs`).
    pub enabled: bool,
    /// Radius `r` (m): every node within `r` of the probe's nearest node
    /// (along and around, on the rest surface) is always integrated. In
    /// [0.02, 1] m: below 20 mm the window would barely hold a 40 × 10 mm
    /// probe face and the held boundary would press on the contact; above
    /// 1 m it holds any mesh this model builds. Default 0.05: validated
    /// against the full model on the 10 112-node leg (force within 0.05 %,
    /// displacement within 0.06 % of its peak over a Fig. 4 exam and a
    /// 100 mm slide, `crates/contact/tests/suite/window.rs`).
    pub radius: f64,
    /// Hysteresis `m` (m): the window re-centres on the probe only when the
    /// probe's nearest node is more than `m` from the window's centre, so a
    /// node enters within `r` and leaves beyond `r + m`. In [0, radius].
    /// Default 0.01.
    pub margin: f64,
}

impl Default for WindowParams {
    fn default() -> Self {
        WindowParams {
            enabled: false,
            radius: 0.05,
            margin: 0.01,
        }
    }
}

impl WindowParams {
    /// Validates the fields; errors name `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        range(
            prefix,
            "radius",
            self.radius,
            (0.02, 1.0),
            "m",
            "the window must hold the probe's face and fit the model",
        )?;
        if !(self.margin >= 0.0 && self.margin <= self.radius) {
            return Err(ConfigError::invalid(
                key(prefix, "margin"),
                format!(
                    "must be in [0, radius = {}] m (the re-centring hysteresis), got {:?}",
                    self.radius, self.margin
                ),
            ));
        }
        Ok(())
    }
}
