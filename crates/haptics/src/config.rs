//! Configuration of the haptic side: the `[haptics]` section of a scenario
//! file, split into `[haptics.fit]` (model manager), `[haptics.render]`
//! (proxy, friction, shading, texture, safety) and `[haptics.loop]` (loop
//! runner). Every field states its unit and default; `validate` names the
//! offending key as `"{prefix}.{field}"`.

use serde::{Deserialize, Serialize};

/// A configuration value that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// The key `key` holds an invalid value.
    #[error("{key}: {reason}")]
    Invalid {
        /// Full key, e.g. `haptics.fit.forgetting`.
        key: String,
        /// What is wrong with it.
        reason: String,
    },
}

fn invalid(prefix: &str, field: &str, reason: impl Into<String>) -> ConfigError {
    ConfigError::Invalid {
        key: format!("{prefix}.{field}"),
        reason: reason.into(),
    }
}

/// Checks that `value` is finite and `> 0` (or `>= 0` when `allow_zero`).
fn positive(prefix: &str, field: &str, value: f64, allow_zero: bool) -> Result<(), ConfigError> {
    if !value.is_finite() {
        return Err(invalid(
            prefix,
            field,
            format!("must be finite, got {value}"),
        ));
    }
    if value < 0.0 || (!allow_zero && value == 0.0) {
        let bound = if allow_zero { ">= 0" } else { "> 0" };
        return Err(invalid(
            prefix,
            field,
            format!("must be {bound}, got {value}"),
        ));
    }
    Ok(())
}

/// Which local model `φ(u, x)` the model manager fits (paper §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// The paper's sphere `φ = |x − c| − r`, `u = (c, r)`.
    #[default]
    Sphere,
    /// A plane `φ = n·x − d`, `u = (n, d)`, a baseline.
    Plane,
}

/// Model manager settings (`[haptics.fit]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitConfig {
    /// Local model kind. Default `sphere`.
    pub model: ModelKind,
    /// Radius given to the sphere before the window identifies it, m. Default 0.08.
    pub initial_radius: f64,
    /// Smallest sphere radius and smallest distance from the newest sample to
    /// the centre, m. Default 0.002.
    pub min_radius: f64,
    /// Largest sphere radius, m (a flat patch drives the radius up). Default 10.
    pub max_radius: f64,
    /// Number of recent samples in the fitting window (≥ 1). Default 8.
    pub window: usize,
    /// Forgetting factor in (0, 1]: a sample `a` updates old weighs `forgetting^a`. Default 0.7.
    pub forgetting: f64,
    /// Weight of the gradient rows relative to the distance row, m
    /// (1 m = the paper's unweighted `[Δφ; Δφ']`). Default 1.
    pub gradient_weight: f64,
    /// Gauss–Newton iterations per sample, at most. Default 10.
    pub max_iterations: usize,
    /// Stop when the correction's norm falls below this, m. Default 1e-13.
    pub tolerance: f64,
    /// Singular values below `rcond · σ_max` count as zero in `J⁺`. Default 1e-9.
    pub rcond: f64,
    /// Largest correction per iteration `|du|`, m. Default 0.05.
    pub max_step: f64,
    /// Physics period assumed before samples let us estimate it, s. Default 0.01.
    pub initial_period: f64,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            model: ModelKind::Sphere,
            initial_radius: 0.08,
            min_radius: 0.002,
            max_radius: 10.0,
            window: 8,
            forgetting: 0.7,
            gradient_weight: 1.0,
            max_iterations: 10,
            tolerance: 1e-13,
            rcond: 1e-9,
            max_step: 0.05,
            initial_period: 0.01,
        }
    }
}

impl FitConfig {
    /// Checks every field; the error names `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        positive(prefix, "initial_radius", self.initial_radius, false)?;
        positive(prefix, "min_radius", self.min_radius, false)?;
        positive(prefix, "max_radius", self.max_radius, false)?;
        if self.max_radius <= self.min_radius {
            return Err(invalid(prefix, "max_radius", "must exceed min_radius"));
        }
        if self.initial_radius < self.min_radius || self.initial_radius > self.max_radius {
            return Err(invalid(
                prefix,
                "initial_radius",
                "must lie within [min_radius, max_radius]",
            ));
        }
        if self.window == 0 || self.window > 1024 {
            return Err(invalid(prefix, "window", "must be in 1..=1024"));
        }
        if !(self.forgetting > 0.0 && self.forgetting <= 1.0) {
            return Err(invalid(
                prefix,
                "forgetting",
                format!("must be in (0, 1], got {}", self.forgetting),
            ));
        }
        positive(prefix, "gradient_weight", self.gradient_weight, true)?;
        if self.max_iterations == 0 {
            return Err(invalid(prefix, "max_iterations", "must be ≥ 1"));
        }
        positive(prefix, "tolerance", self.tolerance, true)?;
        positive(prefix, "rcond", self.rcond, false)?;
        if self.rcond >= 1.0 {
            return Err(invalid(prefix, "rcond", "must be < 1"));
        }
        positive(prefix, "max_step", self.max_step, false)?;
        positive(prefix, "initial_period", self.initial_period, false)
    }
}

/// Haptic rendering settings (`[haptics.render]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    /// Static friction coefficient μ_s (tangential/normal force to break away). Default 0.3.
    pub static_friction: f64,
    /// Kinetic friction coefficient μ_k ≤ μ_s while sliding. Default 0.2.
    pub kinetic_friction: f64,
    /// Texture amplitude of the constraint height, m (0 = off). Default 0.
    pub texture_amplitude: f64,
    /// Texture wavelength, m. Default 0.002.
    pub texture_wavelength: f64,
    /// Blend the displayed constraint into each new model over the estimated
    /// physics period (force shading; DESIGN §3 blends the parameters, we blend
    /// the constraint functions, which cannot bulge: see `shading`). Default true.
    pub shading: bool,
    /// Largest force magnitude rendered, N (tissue side; the app scales to the device). Default 20.
    pub max_force: f64,
    /// Largest rate of change of the rendered force, N/s. Default 2000.
    pub force_rate_limit: f64,
    /// Model age beyond which the loss is declared and the force is
    /// released to zero, s. Default 0.1.
    pub stale_age: f64,
    /// Time in which the largest force (`max_force`) is released to zero
    /// once the model is stale, s (positive). It sets the ramp rate
    /// `max_force / fade_time` (N/s) of the release and of the re-entry
    /// from zero after it ([`crate::ForceRamp`]). Default 0.1 (200 N/s,
    /// 0.2 N per 1 ms tick: below the 0.24 N per tick of normal pressing
    /// reported in issue 20).
    pub fade_time: f64,
    /// Longest interval between two ticks that the rate limits credit, s
    /// (positive): a tick that comes later (the loop itself stalled) changes the
    /// force by at most what this interval allows. Set it to the loop
    /// period. Default 0.001 (the 1 kHz loop).
    pub max_tick_interval: f64,
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            static_friction: 0.3,
            kinetic_friction: 0.2,
            texture_amplitude: 0.0,
            texture_wavelength: 0.002,
            shading: true,
            max_force: 20.0,
            force_rate_limit: 2000.0,
            stale_age: 0.1,
            fade_time: 0.1,
            max_tick_interval: 0.001,
        }
    }
}

impl RenderConfig {
    /// Checks every field; the error names `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        positive(prefix, "static_friction", self.static_friction, true)?;
        positive(prefix, "kinetic_friction", self.kinetic_friction, true)?;
        if self.kinetic_friction > self.static_friction {
            return Err(invalid(
                prefix,
                "kinetic_friction",
                "must not exceed static_friction",
            ));
        }
        positive(prefix, "texture_amplitude", self.texture_amplitude, true)?;
        positive(prefix, "texture_wavelength", self.texture_wavelength, false)?;
        positive(prefix, "max_force", self.max_force, false)?;
        positive(prefix, "force_rate_limit", self.force_rate_limit, false)?;
        positive(prefix, "stale_age", self.stale_age, true)?;
        positive(prefix, "fade_time", self.fade_time, false)?;
        positive(prefix, "max_tick_interval", self.max_tick_interval, false)
    }

    /// Rate of the stale release and of the re-entry from zero, N/s:
    /// `max_force / fade_time`.
    pub fn ramp_rate(&self) -> f64 {
        self.max_force / self.fade_time
    }
}

/// Loop runner settings (`[haptics.loop]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoopConfig {
    /// Tick rate, Hz. Default 1000.
    pub rate_hz: f64,
    /// Number of per-tick timing records kept (ring buffer). Default 65536.
    pub ring_capacity: usize,
    /// Ask the OS for real-time priority (best effort; failure is logged once). Default true.
    pub realtime_priority: bool,
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            ring_capacity: 65536,
            realtime_priority: true,
        }
    }
}

impl LoopConfig {
    /// Checks every field; the error names `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        positive(prefix, "rate_hz", self.rate_hz, false)?;
        if self.rate_hz > 100_000.0 {
            return Err(invalid(prefix, "rate_hz", "must be ≤ 100000"));
        }
        if self.ring_capacity == 0 || self.ring_capacity > 1 << 26 {
            return Err(invalid(prefix, "ring_capacity", "must be in 1..=2^26"));
        }
        Ok(())
    }
}

/// The whole `[haptics]` section.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HapticsConfig {
    /// Model manager (`[haptics.fit]`).
    pub fit: FitConfig,
    /// Rendering (`[haptics.render]`).
    pub render: RenderConfig,
    /// Loop runner (`[haptics.loop]`).
    #[serde(rename = "loop")]
    pub runner: LoopConfig,
}

impl HapticsConfig {
    /// Checks every sub-section; `prefix` is usually `"haptics"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        self.fit.validate(&format!("{prefix}.fit"))?;
        self.render.validate(&format!("{prefix}.render"))?;
        self.runner.validate(&format!("{prefix}.loop"))
    }
}
