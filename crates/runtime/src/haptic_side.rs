//! The haptic side of Fig. 1, split as the paper splits it (§4): a
//! [`SampleSink`] that receives the physics' samples (the model manager in
//! `buffer` mode; the force holder in `hold` mode) and a [`ForceSource`] that
//! the 1 kHz loop ticks. The two halves talk only through lock-free
//! single-slot handoffs, so the sink may run on another thread (or behind a
//! socket) while the loop never waits.

use crate::live::CouplingMode;
use crate::scenario::Scenario;
use echothigh_haptics::{
    handoff, FitReport, HapticRenderer, HapticsConfig, ModelManager, Sample, Vec3,
};
use echothigh_transport::SampleMsg;

/// The physics' contact force as the `hold` mode displays it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HeldForce {
    /// Contact force on the probe (N, tissue units).
    pub force: Vec3,
    /// Loop-clock time the sample arrived (s).
    pub arrival: f64,
    /// Number of samples received (0 = none yet).
    pub count: u64,
}

/// What the loop displayed on one tick.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rendered {
    /// Force (N, tissue units).
    pub force: Vec3,
    /// Proxy position (m); the device position when there is no proxy.
    pub proxy: Vec3,
    /// Age of the physics information used (s).
    pub model_age: f64,
    /// True if the safety logic caught a fault this tick.
    pub fault: bool,
}

/// Receives physics samples (the model-manager side).
pub struct SampleSink {
    mode: CouplingMode,
    manager: ModelManager,
    held: triple_buffer::Input<HeldForce>,
    count: u64,
    rejected: u64,
}

/// Produces the force on every haptic tick (the haptic-loop side).
pub struct ForceSource {
    mode: CouplingMode,
    renderer: HapticRenderer,
    held: triple_buffer::Output<HeldForce>,
    max_force: f64,
    stale_age: f64,
    fade_time: f64,
}

/// Converts a physics sample message into the haptic crate's sample.
pub fn to_sample(msg: &SampleMsg) -> Sample {
    Sample {
        time: msg.t_sample,
        p: Vec3::from(msg.p),
        distance: msg.distance,
        gradient: Vec3::from(msg.gradient),
        stiffness: msg.stiffness,
    }
}

/// Builds the connected pair for `mode` (allocates; call at setup).
/// `max_stiffness` is the largest stiffness the loop may render, N/m in
/// tissue units (the device's stable stiffness over the force scale:
/// `DeviceConfig::tissue_max_stiffness`).
pub fn haptic_side(
    mode: CouplingMode,
    config: &HapticsConfig,
    max_stiffness: f64,
) -> Result<(SampleSink, ForceSource), echothigh_haptics::ConfigError> {
    let (publisher, receiver) = handoff();
    let manager = ModelManager::new(&config.fit, publisher)?;
    let mut renderer = HapticRenderer::new(&config.render, receiver)?;
    renderer.set_max_stiffness(max_stiffness)?;
    let (held_in, held_out) = triple_buffer::triple_buffer(&HeldForce::default());
    Ok((
        SampleSink {
            mode,
            manager,
            held: held_in,
            count: 0,
            rejected: 0,
        },
        ForceSource {
            mode,
            renderer,
            held: held_out,
            max_force: config.render.max_force,
            stale_age: config.render.stale_age,
            fade_time: config.render.fade_time,
        },
    ))
}

/// Builds the connected pair for `mode` from a scenario's `[haptics]` section,
/// capping the rendered stiffness at the scenario device's stable stiffness in
/// tissue units (N/m, `DeviceConfig::tissue_max_stiffness`). Allocates; call
/// at setup. A haptics configuration the renderer or model manager refuses is
/// an error naming the parameter.
pub fn haptic_side_for(
    mode: CouplingMode,
    scenario: &Scenario,
) -> anyhow::Result<(SampleSink, ForceSource)> {
    haptic_side(
        mode,
        &scenario.haptics,
        scenario.device.tissue_max_stiffness(),
    )
    .map_err(anyhow::Error::msg)
}

impl SampleSink {
    /// Takes one physics sample arriving at loop-clock time `now` (s). In
    /// `buffer` mode the model manager fits the buffer model to it (paper §4)
    /// and publishes it; in `hold` mode the force is handed to the loop as is.
    pub fn on_sample(&mut self, msg: &SampleMsg, now: f64) -> Option<FitReport> {
        self.count += 1;
        match self.mode {
            CouplingMode::Buffer => {
                let report = self.manager.update(&to_sample(msg));
                if report.rejected.is_some() {
                    self.rejected += 1;
                }
                Some(report)
            }
            CouplingMode::Hold | CouplingMode::Direct => {
                self.held.write(HeldForce {
                    force: Vec3::from(msg.force),
                    arrival: now,
                    count: self.count,
                });
                None
            }
        }
    }

    /// Samples received.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Samples the model manager rejected (non-finite, bad gradient...).
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// Forgets the fitted model (after a reset of the physics).
    pub fn reset(&mut self) {
        self.manager.reset();
    }
}

impl ForceSource {
    /// One haptic tick at device position `p` (m), loop time `now` (s).
    /// `buffer`: the god-object proxy on the buffer model (with friction,
    /// shading, texture and safety). `hold`: the physics' last force, held
    /// (zero-order hold) and faded out when older than the stale age, clamped
    /// to the maximum force, never NaN. The rate limit is not applied in
    /// `hold`: it is the paper's baseline "without buffer model".
    pub fn tick(&mut self, p: Vec3, now: f64) -> Rendered {
        match self.mode {
            CouplingMode::Buffer => {
                let force = self.renderer.tick(p, now);
                let out = self.renderer.output();
                Rendered {
                    force,
                    proxy: out.proxy,
                    model_age: out.model_age,
                    fault: out.flags & echothigh_haptics::flags::ANY_FAULT != 0,
                }
            }
            CouplingMode::Hold | CouplingMode::Direct => {
                let held = *self.held.read();
                if held.count == 0 {
                    return Rendered {
                        force: Vec3::zeros(),
                        proxy: p,
                        model_age: f64::INFINITY,
                        fault: false,
                    };
                }
                let age = (now - held.arrival).max(0.0);
                self.direct(held.force, p, age)
            }
        }
    }

    /// Displays a force computed outside the loop (the `direct` mode's
    /// physics force, or a held one) with the same safety: stale fade,
    /// clamp, no NaN.
    pub fn direct(&self, force: Vec3, p: Vec3, age: f64) -> Rendered {
        let finite = force.iter().all(|c| c.is_finite());
        if !finite {
            return Rendered {
                force: Vec3::zeros(),
                proxy: p,
                model_age: age,
                fault: true,
            };
        }
        let gain = if age <= self.stale_age {
            1.0
        } else if self.fade_time > 0.0 {
            (1.0 - (age - self.stale_age) / self.fade_time).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut f = force * gain;
        let n = f.norm();
        if n > self.max_force {
            f *= self.max_force / n;
        }
        Rendered {
            force: f,
            proxy: p,
            model_age: age,
            fault: false,
        }
    }

    /// The buffer-model renderer (telemetry).
    pub fn renderer(&self) -> &HapticRenderer {
        &self.renderer
    }
}
