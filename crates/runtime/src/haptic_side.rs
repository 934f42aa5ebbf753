//! The haptic side of Fig. 1, split as the paper splits it (§4): a
//! [`SampleSink`] that receives the physics' samples (the model manager in
//! `buffer` mode; the force holder in `hold` mode) and a [`ForceSource`] that
//! the 1 kHz loop ticks. The two halves talk only through lock-free
//! single-slot handoffs, so the sink may run on another thread (or behind a
//! socket) while the loop never waits.

use crate::live::CouplingMode;
use crate::scenario::Scenario;
use echothigh_haptics::{
    handoff, FitReport, ForceRamp, HapticRenderer, HapticsConfig, ModelManager, Sample, Vec3,
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
    /// The path of the `hold` and `direct` forces through zero: released
    /// when the held force goes stale (or a fault zeroes it), engaged from
    /// zero when a fresh one arrives, so no stall or fault kicks the device
    /// (issue 20, item 2). The renderer has its own for `buffer`.
    ramp: ForceRamp,
    /// Loop time of the previous tick (s); none before the first.
    last_time: Option<f64>,
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
            ramp: ForceRamp::new(
                config.render.ramp_rate(),
                config.render.max_tick_interval,
                "haptics.render.fade_time",
            )?
            .with_settle(config.render.fade_time),
            last_time: None,
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
        scenario.device().tissue_max_stiffness(),
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
    /// (zero-order hold), clamped to the maximum force, never NaN; when it is
    /// older than the stale age it is released to zero and a fresh one
    /// re-enters from zero, both at the ramp rate `max_force / fade_time`
    /// (N/s). Between those, no rate limit: `hold` is the paper's baseline
    /// "without buffer model".
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
                    let dt = self.advance_clock(now);
                    let (force, _) = self.ramp.step(Vec3::zeros(), dt);
                    return Rendered {
                        force,
                        proxy: p,
                        model_age: f64::INFINITY,
                        fault: false,
                    };
                }
                let age = (now - held.arrival).max(0.0);
                self.held_force(held.force, p, age, now)
            }
        }
    }

    /// Displays the `direct` mode's physics force, computed inside the tick
    /// at loop time `now` (s): clamped, never NaN, through the ramp.
    pub fn direct(&mut self, force: Vec3, p: Vec3, now: f64) -> Rendered {
        self.held_force(force, p, 0.0, now)
    }

    /// A force computed outside the renderer, `age` s old, displayed with
    /// the safety of every path: a non-finite force is a fault (zero, the
    /// ramp released); older than the stale age it is released to zero at
    /// the ramp rate; fresh, it re-enters from zero at that rate and is then
    /// tracked; clamped to the maximum force.
    fn held_force(&mut self, force: Vec3, p: Vec3, age: f64, now: f64) -> Rendered {
        let dt = self.advance_clock(now);
        if !force.iter().all(|c| c.is_finite()) || !age.is_finite() {
            self.ramp.zero();
            return Rendered {
                force: Vec3::zeros(),
                proxy: p,
                model_age: age,
                fault: true,
            };
        }
        if age > self.stale_age {
            self.ramp.release();
        } else {
            self.ramp.engage();
        }
        let mut target = force;
        let n = target.norm();
        if n > self.max_force {
            target *= self.max_force / n;
        }
        let (f, _) = self.ramp.step(target, dt);
        Rendered {
            force: f,
            proxy: p,
            model_age: age,
            fault: false,
        }
    }

    /// The loop period since the previous tick (s; 0 on the first, the ramp
    /// credits at most `max_tick_interval`).
    fn advance_clock(&mut self, now: f64) -> f64 {
        let dt = self.last_time.map_or(0.0, |t| now - t);
        self.last_time = Some(now);
        dt
    }

    /// True when the force of the last tick is exactly zero and stays zero
    /// until fresh physics arrive (what a caller may report as "faded to
    /// zero").
    pub fn faded_to_zero(&self) -> bool {
        match self.mode {
            CouplingMode::Buffer => self.renderer.faded_to_zero(),
            CouplingMode::Hold | CouplingMode::Direct => self.ramp.is_released(),
        }
    }

    /// Largest change of the force in one tick while it is released or
    /// ramped in, N: `max_force / fade_time · max_tick_interval`.
    pub fn ramp_step_bound(&self) -> f64 {
        self.ramp.max_step()
    }

    /// The buffer-model renderer (telemetry).
    pub fn renderer(&self) -> &HapticRenderer {
        &self.renderer
    }
}
