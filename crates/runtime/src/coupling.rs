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
    /// Physics rate in `buffer` and `hold` modes (Hz), in [10, 1000]: below
    /// 10 Hz the buffer model extrapolates a local model for longer than a
    /// probe takes to cross it; above 1 kHz the physics outruns the haptic
    /// loop it serves (the viewer's range too). Default 100 (the paper's).
    pub physics_rate: f64,
    /// Haptic rate (Hz), in [100, 10 000] (haptic loops run 0.5–10 kHz; the
    /// bound also caps a run's trace and, in `direct` mode, the physics
    /// rate); also the physics rate in `direct` mode. Default 1000.
    pub haptic_rate: f64,
    /// Time the physics takes to deliver a step's sample after it read the
    /// probe pose, as a fraction of its period (dimensionless, 0..=1). A
    /// physics loop running flat out at its rate delivers one period late:
    /// default 1. Used on the deterministic virtual clock; in real time the
    /// measured compute time applies.
    pub compute_delay: f64,
    /// Time without a physics sample after which the haptic side reports its
    /// peer silent and fades the force (s), in [0.01, 60] and at least two
    /// physics periods (shorter, every gap between two samples would read as
    /// a silence). Default 0.25.
    pub peer_timeout: f64,
    /// In `direct` mode, integrate only the active window around the probe
    /// (`[integrator.window]`'s radius and margin) even where
    /// `integrator.window.enabled` is false (issue 18): the step then fits
    /// the haptic tick with room to spare. On the built-in whole-leg
    /// scenario (1 296 nodes, 50 mm) the tick's thread-CPU median falls from
    /// ≈ 350 to ≈ 115 µs and its p99 from ≈ 620 to ≈ 230 µs, the force
    /// staying within 7 µN of the full model's over the exam (`echothigh
    /// bench physics --direct-ticks 10000 --direct-window 0.05`); the window
    /// is validated against the full model in
    /// `crates/contact/tests/suite/window.rs`. `false` steps the whole
    /// mesh at the haptic rate (the full reference, which the experiments'
    /// `direct` runs always use: `echothigh_experiments::trace::run_mode`).
    /// Default true.
    pub direct_window: bool,
}

impl Default for CouplingConfig {
    fn default() -> Self {
        Self {
            mode: CouplingMode::Buffer,
            physics_rate: 100.0,
            haptic_rate: 1000.0,
            compute_delay: 1.0,
            peer_timeout: 0.25,
            direct_window: true,
        }
    }
}

impl CouplingConfig {
    /// Checks every field, naming the key.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let range = |name: &str, v: f64, (lo, hi): (f64, f64), why: &str| -> Result<()> {
            if !(v >= lo && v <= hi) {
                bail!("{prefix}.{name} must be in [{lo}, {hi}] {why}, got {v:?}");
            }
            Ok(())
        };
        let physics = "Hz (the buffer model's useful range)";
        range("physics_rate", self.physics_rate, (10.0, 1000.0), physics)?;
        let haptic = "Hz (haptic loops run 0.5-10 kHz)";
        range("haptic_rate", self.haptic_rate, (100.0, 1e4), haptic)?;
        let silent = "s (from a few physics periods to a minute)";
        range("peer_timeout", self.peer_timeout, (0.01, 60.0), silent)?;
        if self.peer_timeout < 2.0 * self.physics_period() {
            bail!(
                "{prefix}.peer_timeout ({} s) must be at least two physics periods ({} s)",
                self.peer_timeout,
                2.0 * self.physics_period()
            );
        }
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
