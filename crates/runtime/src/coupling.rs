//! The `[coupling]` section: how physics and haptics are coupled and at what
//! rates (paper §2, Fig. 1; `DESIGN.md` §3).

use crate::live::CouplingMode;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Coupling and rates (`[coupling]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CouplingConfig {
    /// `buffer` (the paper's method), `hold` (no buffer model: the physics'
    /// force held between steps) or `direct` (physics at the haptic rate).
    /// Default `buffer`.
    pub mode: CouplingMode,
    /// Physics rate in `buffer` and `hold` modes (Hz). Default 100 (the paper's).
    pub physics_rate: f64,
    /// Haptic rate (Hz); also the physics rate in `direct` mode. Default 1000.
    pub haptic_rate: f64,
    /// Time the physics takes to deliver a step's sample after it read the
    /// probe pose, as a fraction of its period (dimensionless, 0..=1). A
    /// physics loop running flat out at its rate delivers one period late:
    /// default 1. Used on the deterministic virtual clock; in real time the
    /// measured compute time applies.
    pub compute_delay: f64,
    /// Time without a physics sample after which the haptic side reports its
    /// peer silent and fades the force (s). Default 0.25.
    pub peer_timeout: f64,
}

impl Default for CouplingConfig {
    fn default() -> Self {
        Self {
            mode: CouplingMode::Buffer,
            physics_rate: 100.0,
            haptic_rate: 1000.0,
            compute_delay: 1.0,
            peer_timeout: 0.25,
        }
    }
}

impl CouplingConfig {
    /// Checks every field, naming the key.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let finite_pos = |name: &str, v: f64| -> Result<()> {
            if !v.is_finite() || v <= 0.0 {
                bail!("{prefix}.{name} must be a finite number > 0, got {v}");
            }
            Ok(())
        };
        finite_pos("physics_rate", self.physics_rate)?;
        finite_pos("haptic_rate", self.haptic_rate)?;
        finite_pos("peer_timeout", self.peer_timeout)?;
        if self.physics_rate > self.haptic_rate {
            bail!(
                "{prefix}.physics_rate ({}) must not exceed {prefix}.haptic_rate ({})",
                self.physics_rate,
                self.haptic_rate
            );
        }
        if !(0.0..=1.0).contains(&self.compute_delay) {
            bail!(
                "{prefix}.compute_delay must be in [0, 1], got {}",
                self.compute_delay
            );
        }
        Ok(())
    }

    /// Physics step (s) for the configured mode.
    pub fn physics_period(&self) -> f64 {
        match self.mode {
            CouplingMode::Direct => 1.0 / self.haptic_rate,
            _ => 1.0 / self.physics_rate,
        }
    }

    /// Haptic tick (s).
    pub fn haptic_period(&self) -> f64 {
        1.0 / self.haptic_rate
    }
}
