//! The haptic loop's force algorithm (paper §4): each tick reads the latest
//! buffer model from the handoff, moves the proxy against the (shaded,
//! textured) constraint surface and renders Hooke's law `f = k (x − p)`, then
//! applies the safety stages. Knows nothing of devices or threads; the caller
//! owns the clock. No allocation, lock or I/O in `tick`.
//!
//! Tick stages: check input → adopt model → shade → proxy → Hooke → clamp →
//! stale ramp → rate limit → finiteness check.
//!
//! Stale handling (issue 20, item 2): when the model is older than
//! `stale_age` the loss is declared and the force is released to zero
//! through a [`ForceRamp`] at `max_force / fade_time` N/s. Models that
//! arrive after that are adopted (the proxy and shading follow them) but
//! not rendered until the force has reached zero; the force then re-enters
//! through the same ramp from zero. The first model, and the first after a
//! fault, enter the same way. Every rate limit credits a tick at most
//! `max_tick_interval`, so a loop resuming after its own stall moves the
//! force by no more than one normal step. [`HapticRenderer::state`] tells
//! the caller where it is; [`RenderState::Released`] means the force
//! displayed is exactly zero.

use crate::buffer::{BufferModel, ModelReceiver};
use crate::config::{ConfigError, RenderConfig};
use crate::proxy::{Friction, Proxy, Surface};
use crate::ramp::{ForceRamp, RampPhase};
use crate::safety::{clamp_magnitude, is_finite, limit_rate};
use crate::shading::Shading;
use crate::Vec3;

/// Bits of `TickOutput::flags`.
pub mod flags {
    /// No model has arrived yet: zero force.
    pub const NO_MODEL: u32 = 1 << 0;
    /// The model is older than `stale_age`: the loss is declared and the
    /// force is released to zero (see [`super::RenderState`]).
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
    /// The force is re-entering through the ramp from zero.
    pub const RAMPING: u32 = 1 << 9;
    /// The force is released: exactly zero until a fresh model ramps it in.
    pub const RELEASED: u32 = 1 << 10;
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
    /// Ratio of the force displayed to the force the model asks for, in
    /// [0, 1] (1 when tracking; 0 when released or the model asks nothing
    /// while ramping).
    pub fade: f64,
    /// Where the stale ramp is.
    pub state: RenderState,
    /// `flags::*` bits.
    pub flags: u32,
}

/// Where the renderer is between a live model and no force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RenderState {
    /// No model has arrived yet: zero force.
    #[default]
    NoModel,
    /// A fresh model is rendered (normal operation).
    Live,
    /// The model went stale: the force is falling to zero at the ramp rate;
    /// models arriving meanwhile are not rendered.
    Releasing,
    /// The force displayed is exactly zero (stale, or after a fault) until
    /// a fresh model arrives.
    Released,
    /// A fresh model is being ramped in from zero.
    Ramping,
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
    ramp: ForceRamp,
    output: TickOutput,
}

impl HapticRenderer {
    /// A renderer reading models from `receiver`.
    pub fn new(config: &RenderConfig, receiver: ModelReceiver) -> Result<Self, ConfigError> {
        config.validate("haptics.render")?;
        let none = BufferModel::none();
        let ramp = ForceRamp::new(
            config.ramp_rate(),
            config.max_tick_interval,
            "haptics.render.fade_time",
        )?
        .with_settle(config.fade_time);
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
            ramp,
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

    /// Where the stale ramp is after the last tick.
    pub fn state(&self) -> RenderState {
        self.output.state
    }

    /// True when the force displayed by the last tick is exactly zero and
    /// stays zero until a fresh model arrives (what a caller may report as
    /// "faded to zero").
    pub fn faded_to_zero(&self) -> bool {
        matches!(
            self.output.state,
            RenderState::Released | RenderState::NoModel
        ) && self.output.force == Vec3::zeros()
    }

    /// Largest change of the force in one tick while it is released or
    /// ramped in, N: `max_force / fade_time · max_tick_interval`.
    pub fn ramp_step_bound(&self) -> f64 {
        self.ramp.max_step()
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
        // A late tick is credited at most `max_tick_interval` by every rate limit.
        let dt = self
            .last_time
            .map_or(0.0, |t| (now - t).clamp(0.0, self.config.max_tick_interval));
        self.last_time = Some(now);
        flags |= self.adopt_latest(now);

        let mut target = Vec3::zeros();
        let (mut k, mut alpha) = (0.0, 1.0);
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
            // Hooke's law f = k (x − p).
            target = (self.proxy.position - p) * k;
            if now - self.arrival > self.config.stale_age {
                // Loss declared: release; a pending engage is cancelled.
                self.ramp.release();
                flags |= flags::STALE;
            } else {
                // Fresh: back through zero if released or releasing.
                self.ramp.engage();
            }
        }
        let (f, clamped) = clamp_magnitude(target, self.config.max_force);
        let wanted = f.norm();
        // The ramp judges its catching up against the model's force itself.
        let (f, _) = self.ramp.step(f, dt);
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
        let state = match (self.model.sequence, self.ramp.phase()) {
            (0, _) => RenderState::NoModel,
            (_, RampPhase::Tracking) => RenderState::Live,
            (_, RampPhase::Releasing) => RenderState::Releasing,
            (_, RampPhase::Released) => RenderState::Released,
            (_, RampPhase::Engaging) => RenderState::Ramping,
        };
        flags |= match state {
            RenderState::Ramping => flags::RAMPING,
            RenderState::Released => flags::RELEASED,
            _ => 0,
        };
        let fade = if state == RenderState::Live {
            1.0
        } else if wanted > 0.0 {
            (f.norm() / wanted).min(1.0)
        } else {
            0.0
        };
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
            fade,
            state,
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

    /// Zero force and a fault flag; the force comes back through the ramp
    /// from zero.
    fn fault(&mut self, bits: u32, p: Vec3, now: f64) -> Vec3 {
        self.last_force = Vec3::zeros();
        self.ramp.zero();
        self.output = TickOutput {
            time: now,
            device: p,
            proxy: self.proxy.position,
            force: Vec3::zeros(),
            model_sequence: self.model.sequence,
            state: if self.model.sequence == 0 {
                RenderState::NoModel
            } else {
                RenderState::Released
            },
            flags: bits | flags::RELEASED,
            ..TickOutput::default()
        };
        Vec3::zeros()
    }
}
