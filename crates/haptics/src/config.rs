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

/// Checks `lo <= value <= hi` (NaN fails); `unit_why` gives the unit and the
/// reason for the range, e.g. `m (smaller than the thigh's curvature)`.
fn range(
    prefix: &str,
    field: &str,
    value: f64,
    (lo, hi): (f64, f64),
    unit_why: &str,
) -> Result<(), ConfigError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(invalid(
            prefix,
            field,
            format!("must be in [{lo}, {hi}] {unit_why}, got {value:?}"),
        ))
    }
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
    /// Radius given to the sphere before the window identifies it, m, in
    /// [0.001, 100] and within [min_radius, max_radius]. Default 0.08.
    pub initial_radius: f64,
    /// Smallest sphere radius and smallest distance from the newest sample to
    /// the centre, m, in [1e-4, 0.05] (below the thigh's smallest curvature
    /// radius, ~30 mm, and the probe's face). Default 0.002.
    pub min_radius: f64,
    /// Largest sphere radius, m (a flat patch drives the radius up), in
    /// [0.01, 1000] (1 km is flat to 1e-9 m over a 2 mm patch). Default 10.
    pub max_radius: f64,
    /// Number of recent samples in the fitting window, in [1, 256] (the fit
    /// costs `O(window)` per Gauss–Newton iteration on the model manager;
    /// with forgetting ≥ 0.01 the weight of sample 256 is nil anyway).
    /// Default 8.
    pub window: usize,
    /// Forgetting factor in [0.01, 1]: a sample `a` updates old weighs
    /// `forgetting^a` (below 0.01 only the newest sample counts). Default 0.7.
    pub forgetting: f64,
    /// Weight of the gradient rows relative to the distance row, m
    /// (1 m = the paper's unweighted `[Δφ; Δφ']`), in [0, 10]. Default 1.
    pub gradient_weight: f64,
    /// Gauss–Newton iterations per sample, at most, in [1, 100] (converging
    /// fits take a few; bounds the work per sample). Default 10.
    pub max_iterations: usize,
    /// Stop when the correction's norm falls below this, m, in [0, 1e-3].
    /// Default 1e-13.
    pub tolerance: f64,
    /// Singular values below `rcond · σ_max` count as zero in `J⁺`, in
    /// [1e-15, 0.1] (from f64 round-off to a tenth of the largest). Default 1e-9.
    pub rcond: f64,
    /// Largest correction per iteration `|du|`, m, in [1e-4, 1]. Default 0.05.
    pub max_step: f64,
    /// Physics period assumed before samples let us estimate it, s, in
    /// [1e-4, 0.1] (physics rates 10 Hz–10 kHz). Default 0.01.
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
        let p = prefix;
        range(p, "initial_radius", self.initial_radius, (1e-3, 100.0), "m")?;
        let min_r = "m (below the thigh's smallest curvature radius)";
        range(p, "min_radius", self.min_radius, (1e-4, 0.05), min_r)?;
        let max_r = "m (1 km is flat over a 2 mm patch)";
        range(p, "max_radius", self.max_radius, (0.01, 1000.0), max_r)?;
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
        if self.window == 0 || self.window > 256 {
            return Err(invalid(
                prefix,
                "window",
                "must be in 1..=256 (bounds the fit's work)",
            ));
        }
        range(
            p,
            "forgetting",
            self.forgetting,
            (0.01, 1.0),
            "(dimensionless)",
        )?;
        range(p, "gradient_weight", self.gradient_weight, (0.0, 10.0), "m")?;
        if self.max_iterations == 0 || self.max_iterations > 100 {
            return Err(invalid(
                prefix,
                "max_iterations",
                "must be in 1..=100 (bounds the work per sample)",
            ));
        }
        range(p, "tolerance", self.tolerance, (0.0, 1e-3), "m")?;
        range(p, "rcond", self.rcond, (1e-15, 0.1), "(relative to σ_max)")?;
        range(p, "max_step", self.max_step, (1e-4, 1.0), "m")?;
        let period = "s (physics rates 10 Hz to 10 kHz)";
        range(
            p,
            "initial_period",
            self.initial_period,
            (1e-4, 0.1),
            period,
        )
    }
}

/// Haptic rendering settings (`[haptics.render]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderConfig {
    /// Static friction coefficient μ_s (tangential/normal force to break
    /// away), in [0, 2]: gel-coated skin 0.1–0.5, dry skin up to ~1.5.
    /// Default 0.3.
    pub static_friction: f64,
    /// Kinetic friction coefficient μ_k ≤ μ_s while sliding, in [0, 2].
    /// Default 0.2.
    pub kinetic_friction: f64,
    /// Texture amplitude of the constraint height, m (0 = off), in [0,
    /// 0.002] (skin texture is sub-millimetre). Default 0.
    pub texture_amplitude: f64,
    /// Texture wavelength, m, in [1e-4, 0.1]. Default 0.002.
    pub texture_wavelength: f64,
    /// Blend the displayed constraint into each new model over the estimated
    /// physics period (force shading; DESIGN §3 blends the parameters, we blend
    /// the constraint functions, which cannot bulge: see `shading`). Default true.
    pub shading: bool,
    /// Largest force magnitude rendered, N (tissue side; the app scales to
    /// the device), in [0.1, 200] (compression exams use ~5–40 N). Default 20.
    pub max_force: f64,
    /// Largest rate of change of the rendered force, N/s, in [10, 1e12]: from
    /// 0.01 N per 1 ms tick up to "no limit" (1e12 N/s, far past `max_force`
    /// per tick, which tests use to isolate the other stages; a large value
    /// allocates and loops nothing). Default 500: 0.5 N per 1 ms tick, twice
    /// the largest change of the undisturbed scripted exam (0.24 N per tick,
    /// issue 20), so that no model change, friction slip or re-entry after a
    /// stall changes the force by more than that in one tick (2 N per tick
    /// was measured after a 0.35 s physics stall with 2000 N/s,
    /// `crates/app/tests/suite/stall.rs`).
    pub force_rate_limit: f64,
    /// Model age beyond which the loss is declared and the force is
    /// released to zero, s, in [0, 5]. Default 0.1.
    pub stale_age: f64,
    /// Time in which the largest force (`max_force`) is released to zero
    /// once the model is stale, s, in [1e-3, 5]. It sets the ramp rate
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
            force_rate_limit: 500.0,
            stale_age: 0.1,
            fade_time: 0.1,
            max_tick_interval: 0.001,
        }
    }
}

impl RenderConfig {
    /// Checks every field; the error names `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let mu = "(skin on gel 0.1-0.5, dry skin up to ~1.5)";
        range(p, "static_friction", self.static_friction, (0.0, 2.0), mu)?;
        range(p, "kinetic_friction", self.kinetic_friction, (0.0, 2.0), mu)?;
        if self.kinetic_friction > self.static_friction {
            return Err(invalid(
                prefix,
                "kinetic_friction",
                "must not exceed static_friction",
            ));
        }
        let amp = "m (skin texture is sub-millimetre)";
        range(
            p,
            "texture_amplitude",
            self.texture_amplitude,
            (0.0, 2e-3),
            amp,
        )?;
        range(
            p,
            "texture_wavelength",
            self.texture_wavelength,
            (1e-4, 0.1),
            "m",
        )?;
        let force = "N (compression exams use ~5-40 N)";
        range(p, "max_force", self.max_force, (0.1, 200.0), force)?;
        let rate = "N/s (0.01 N per 1 ms tick up to no limit)";
        range(
            p,
            "force_rate_limit",
            self.force_rate_limit,
            (10.0, 1e12),
            rate,
        )?;
        range(p, "stale_age", self.stale_age, (0.0, 5.0), "s")?;
        range(
            p,
            "fade_time",
            self.fade_time,
            (1e-3, 5.0),
            "s (sets the ramp rate)",
        )?;
        range(
            p,
            "max_tick_interval",
            self.max_tick_interval,
            (1e-5, 0.1),
            "s (a haptic tick, 0.1 ms to 100 ms)",
        )
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
    /// Tick rate, Hz, in [100, 10 000] (haptic loops run 0.5–10 kHz).
    /// Default 1000.
    pub rate_hz: f64,
    /// Number of per-tick timing records kept (ring buffer), in [1, 2²²]
    /// (70 min at 1 kHz; bounds the allocation). Default 65536.
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
        let rate = "Hz (haptic loops run 0.5-10 kHz)";
        range(prefix, "rate_hz", self.rate_hz, (100.0, 1e4), rate)?;
        if self.ring_capacity == 0 || self.ring_capacity > 1 << 22 {
            return Err(invalid(
                prefix,
                "ring_capacity",
                "must be in 1..=2^22 (70 min at 1 kHz; bounds the allocation)",
            ));
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
