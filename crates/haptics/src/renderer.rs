//! The haptic loop's force algorithm (paper §4): each tick reads the latest
//! buffer model from the handoff, moves the proxy against the (shaded,
//! textured) constraint surface and renders Hooke's law `f = k (x − p)`, then
//! applies the safety stages. Knows nothing of devices or threads; the caller
//! owns the clock. No allocation, lock or I/O in `tick`.
//!
//! Tick stages: check input → adopt model → shade → proxy → Hooke → fade →
//! clamp → rate limit → finiteness check.

use crate::buffer::{BufferModel, ModelReceiver};
use crate::config::{ConfigError, RenderConfig};
use crate::proxy::{Friction, Proxy, Surface};
use crate::safety::{clamp_magnitude, fade_gain, is_finite, limit_rate};
use crate::shading::Shading;
use crate::Vec3;

/// Bits of `TickOutput::flags`.
pub mod flags {
    /// No model has arrived yet: zero force.
    pub const NO_MODEL: u32 = 1 << 0;
    /// The model is older than `stale_age`: the force is fading.
    pub const STALE: u32 = 1 << 1;
    /// The force was clamped to `max_force`.
    pub const CLAMPED: u32 = 1 << 2;
    /// The force's change was limited by `force_rate_limit`.
    pub const RATE_LIMITED: u32 = 1 << 3;
    /// Non-finite device position or time: zero force this tick.
    pub const FAULT_INPUT: u32 = 1 << 4;
    /// A published model was not usable (non-finite or invalid): ignored.
    pub const FAULT_MODEL: u32 = 1 << 5;
    /// The computed force was not finite: zero force this tick.
    pub const FAULT_NUMERIC: u32 = 1 << 6;
    /// A force-shading blend is in progress.
    pub const SHADING: u32 = 1 << 7;
    /// The model's stiffness exceeded the device's stable limit: rendered
    /// at the limit.
    pub const STIFFNESS_LIMITED: u32 = 1 << 8;
    /// Any fault bit.
    pub const ANY_FAULT: u32 = FAULT_INPUT | FAULT_MODEL | FAULT_NUMERIC;
}

/// Telemetry of the last tick (Copy; read it after `tick`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TickOutput {
    /// Tick time (caller's clock), s.
    pub time: f64,
    /// Device position `p`, m.
    pub device: Vec3,
    /// Proxy position `x`, m.
    pub proxy: Vec3,
    /// Force displayed, N (tissue units, thigh frame).
    pub force: Vec3,
    /// Stiffness rendered `k`, N/m (shaded, then limited).
    pub stiffness: f64,
    /// Time since the current model arrived, s (loop clock).
    pub model_age: f64,
    /// Physics time of the current model's sample, s.
    pub sample_time: f64,
    /// Sequence number of the current model (0 = none).
    pub model_sequence: u64,
    /// The device is inside the constraint.
    pub in_contact: bool,
    /// Friction state is sliding.
    pub sliding: bool,
    /// Shading blend fraction α ∈ [0, 1].
    pub shading: f64,
    /// Stale-fade gain ∈ [0, 1].
    pub fade: f64,
    /// `flags::*` bits.
    pub flags: u32,
}

/// Buffer-model haptic renderer (god-object proxy + effects + safety).
pub struct HapticRenderer {
    config: RenderConfig,
    friction: Friction,
    receiver: ModelReceiver,
    model: BufferModel,
    arrival: f64,
    shading: Shading,
    proxy: Proxy,
    max_stiffness: f64,
    last_force: Vec3,
    last_time: Option<f64>,
    output: TickOutput,
}

impl HapticRenderer {
    /// A renderer reading models from `receiver`.
    pub fn new(config: &RenderConfig, receiver: ModelReceiver) -> Result<Self, ConfigError> {
        config.validate("haptics.render")?;
        let none = BufferModel::none();
        Ok(HapticRenderer {
            config: config.clone(),
            friction: Friction {
                static_coefficient: config.static_friction,
                kinetic_coefficient: config.kinetic_friction,
            },
            receiver,
            model: none,
            arrival: 0.0,
            shading: Shading::settled(none.params, 0.0),
            proxy: Proxy::new(Vec3::zeros()),
            max_stiffness: f64::INFINITY,
            last_force: Vec3::zeros(),
            last_time: None,
            output: TickOutput::default(),
        })
    }

    /// Sets the largest stiffness rendered, N/m (tissue units; default
    /// unlimited): the device's stable stiffness over the force scale. A
    /// stiffer buffer model is rendered at this stiffness (the probe sinks
    /// deeper than in the tissue instead of making the device unstable), and
    /// the tick is flagged [`flags::STIFFNESS_LIMITED`].
    pub fn set_max_stiffness(&mut self, k: f64) -> Result<(), ConfigError> {
        if k.is_nan() || k <= 0.0 {
            return Err(ConfigError::Invalid {
                key: "device.max_stiffness / device.force_scale".into(),
                reason: format!("the rendered stiffness limit must be > 0 N/m, got {k}"),
            });
        }
        self.max_stiffness = k;
        Ok(())
    }

    /// Telemetry of the last tick.
    pub fn output(&self) -> &TickOutput {
        &self.output
    }

    /// The model currently adopted (the shading target).
    pub fn model(&self) -> &BufferModel {
        &self.model
    }

    /// One haptic tick at device position `p` (m) and time `now` (s, caller's
    /// clock): returns the force to display, N (tissue units). Never NaN.
    pub fn tick(&mut self, p: Vec3, now: f64) -> Vec3 {
        let mut flags = 0;
        if !is_finite(&p) || !now.is_finite() {
            return self.fault(flags::FAULT_INPUT, p, now);
        }
        let dt = self.last_time.map_or(0.0, |t| (now - t).max(0.0));
        self.last_time = Some(now);
        flags |= self.adopt_latest(now);

        let mut target = Vec3::zeros();
        let (mut k, mut alpha, mut gain) = (0.0, 1.0, 1.0);
        if self.model.sequence == 0 {
            flags |= flags::NO_MODEL;
            self.proxy = Proxy::new(p);
        } else {
            let (u, k_shaded, a) = self.shading.at(now);
            (k, alpha) = (k_shaded.min(self.max_stiffness), a);
            if k < k_shaded {
                flags |= flags::STIFFNESS_LIMITED;
            }
            if alpha < 1.0 {
                flags |= flags::SHADING;
            }
            let surface = Surface {
                model: u,
                amplitude: self.config.texture_amplitude,
                wavelength: self.config.texture_wavelength,
            };
            self.proxy.update(&surface, &p, &self.friction);
            gain = fade_gain(
                now - self.arrival,
                self.config.stale_age,
                self.config.fade_time,
            );
            if gain < 1.0 {
                flags |= flags::STALE;
            }
            // Hooke's law f = k (x − p), faded when stale.
            target = (self.proxy.position - p) * (k * gain);
        }
        let (f, clamped) = clamp_magnitude(target, self.config.max_force);
        let (f, limited) = limit_rate(self.last_force, f, self.config.force_rate_limit, dt);
        if clamped {
            flags |= flags::CLAMPED;
        }
        if limited {
            flags |= flags::RATE_LIMITED;
        }
        if !is_finite(&f) {
            self.proxy = Proxy::new(p);
            return self.fault(flags | flags::FAULT_NUMERIC, p, now);
        }
        self.last_force = f;
        self.output = TickOutput {
            time: now,
            device: p,
            proxy: self.proxy.position,
            force: f,
            stiffness: k,
            model_age: now - self.arrival,
            sample_time: self.model.sample_time,
            model_sequence: self.model.sequence,
            in_contact: self.proxy.in_contact,
            sliding: self.proxy.sliding,
            shading: alpha,
            fade: gain,
            flags,
        };
        f
    }

    /// Reads the handoff; adopts a new usable model (starting a shading
    /// blend) and returns fault flags for an unusable one.
    fn adopt_latest(&mut self, now: f64) -> u32 {
        let m = self.receiver.latest();
        if m.sequence == self.model.sequence {
            return 0;
        }
        if !m.is_usable() {
            return if m.sequence == 0 {
                0
            } else {
                flags::FAULT_MODEL
            };
        }
        if self.model.sequence == 0 || !self.config.shading {
            self.shading = Shading::settled(m.params, m.stiffness);
        } else {
            self.shading.retarget(m.params, m.stiffness, now, m.period);
        }
        self.model = m;
        self.arrival = now;
        0
    }

    /// Zero force and a fault flag (the rate limiter restarts from zero).
    fn fault(&mut self, bits: u32, p: Vec3, now: f64) -> Vec3 {
        self.last_force = Vec3::zeros();
        self.output = TickOutput {
            time: now,
            device: p,
            proxy: self.proxy.position,
            force: Vec3::zeros(),
            model_sequence: self.model.sequence,
            flags: bits,
            ..TickOutput::default()
        };
        Vec3::zeros()
    }
}
