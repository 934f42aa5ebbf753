//! The deterministic deployment: physics, link, haptic side and simulated
//! device stepped in one thread on a virtual clock, so that a run gives the
//! same numbers on any machine and under any load, faster or slower than
//! real time (tests, experiments).
//!
//! Per haptic tick of period `T` at time `t`, in order (paper Fig. 1):
//! 1. read the device position `p`; send it to the physics (link, with faults);
//! 2. physics: a sample whose computation started one compute delay ago is
//!    sent to the haptic side; if a step is due, read the latest probe pose
//!    and step (`buffer`, `hold`); in `direct` the physics steps every tick
//!    at `p` itself;
//! 3. haptic side: take the delivered samples (latest wins; the model manager
//!    fits each), tick the loop: force `f`;
//! 4. write `f` (times the force scale) to the device and advance it by `T`.
//!
//! Steps 1 and 4 and the loop's force are the one haptic tick
//! ([`HapticTick`]); steps 1's link and 2–3's physics and model manager are
//! its observer here ([`VirtualWorld`]), run synchronously inside the tick,
//! where the threaded deployments hand the pose to other threads instead.

use crate::haptic_side::{haptic_side_for, SampleSink};
use crate::physics_side::PhysicsSide;
use crate::scenario::Scenario;
use crate::tick::{HapticTick, TickObserver};
use crate::trace::{PhysicsRecord, TickRecord};
use anyhow::{Context, Result};
use echothigh_device::{ExamScript, SimulatedDevice, SimulatedHand};
use echothigh_transport::{InProcessEndpoint, Link, LinkStats, Message, ProbeMsg, SampleMsg};

pub use crate::tick::{phase_code, EXAM_ORIENTATION};

/// Everything but the haptic tick: the link's two ends, the physics (except
/// in `direct` coupling, where the tick owns it), the model-manager side and
/// the trace, advanced synchronously from the tick's observer.
struct VirtualWorld {
    physics_period: f64,
    compute_delay: f64,
    /// The physics (`buffer`, `hold`); `None` in `direct`.
    physics: Option<PhysicsSide>,
    sink: SampleSink,
    haptic_end: InProcessEndpoint,
    physics_end: InProcessEndpoint,
    pending: Option<(f64, SampleMsg)>,
    next_physics: f64,
    latest_probe: Option<ProbeMsg>,
    ticks: Vec<TickRecord>,
    steps: Vec<PhysicsRecord>,
}

/// A deterministic run in progress.
pub struct VirtualRun {
    period: f64,
    tick: HapticTick<SimulatedDevice>,
    world: VirtualWorld,
    n: u64,
}

impl VirtualRun {
    /// Builds the run for `scenario` (validated), with the hand following
    /// the scenario's exam script. Allocates the trace buffers for
    /// `scenario.run.duration`.
    pub fn new(scenario: &Scenario) -> Result<Self> {
        let script = ExamScript::new(scenario.exam_script_config()?).map_err(anyhow::Error::msg)?;
        let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
        let device =
            SimulatedDevice::with_hand(scenario.device(), hand).map_err(anyhow::Error::msg)?;
        Self::with_device(scenario, device)
    }

    /// Builds the run with a given simulated device (and its hand).
    pub fn with_device(scenario: &Scenario, device: SimulatedDevice) -> Result<Self> {
        let c = &scenario.coupling;
        let physics = PhysicsSide::new(scenario).context("building the physical model")?;
        let (sink, source) = haptic_side_for(c.mode, scenario)?;
        let (haptic_end, physics_end) = scenario.in_process_link();
        let n_ticks = (scenario.run.duration * c.haptic_rate).ceil() as usize + 1;
        let n_steps = match c.mode {
            crate::live::CouplingMode::Direct => n_ticks,
            _ => (scenario.run.duration / c.physics_period()).ceil() as usize + 2,
        };
        let (tick_physics, world_physics) = match c.mode {
            crate::live::CouplingMode::Direct => (Some(physics), None),
            _ => (None, Some(physics)),
        };
        let mut tick = HapticTick::new(
            device,
            source,
            scenario.device().force_scale(),
            tick_physics,
            c.haptic_period(),
        );
        tick.set_orientation(scenario.probe_orientation()?);
        Ok(VirtualRun {
            period: c.haptic_period(),
            tick,
            world: VirtualWorld {
                physics_period: c.physics_period(),
                compute_delay: c.compute_delay * c.physics_period(),
                physics: world_physics,
                sink,
                haptic_end,
                physics_end,
                pending: None,
                next_physics: 0.0,
                latest_probe: None,
                ticks: Vec::with_capacity(n_ticks),
                steps: Vec::with_capacity(n_steps),
            },
            n: 0,
        })
    }

    /// Current virtual time (s).
    pub fn time(&self) -> f64 {
        self.n as f64 * self.period
    }

    /// The simulated device.
    pub fn device(&self) -> &SimulatedDevice {
        self.tick.device()
    }

    /// The simulated device, mutable (a runner that drives the hand's
    /// setpoint itself, as the scripted trainee of [`crate::exam_run`]).
    pub fn device_mut(&mut self) -> &mut SimulatedDevice {
        self.tick.device_mut()
    }

    /// Sets the probe orientation the tick sends with the position (unit
    /// quaternion w, x, y, z; see [`HapticTick::set_orientation`]).
    pub fn set_probe_orientation(&mut self, orientation: [f64; 4]) {
        self.tick.set_orientation(orientation);
    }

    /// The physics side.
    pub fn physics(&self) -> &PhysicsSide {
        match self.tick.direct_physics() {
            Some(p) => p,
            None => self
                .world
                .physics
                .as_ref()
                .expect("physics outside the tick unless direct"),
        }
    }

    /// The physics side, mutable (queries).
    pub fn physics_mut(&mut self) -> &mut PhysicsSide {
        match self.tick.direct_physics_mut() {
            Some(p) => p,
            None => self
                .world
                .physics
                .as_mut()
                .expect("physics outside the tick unless direct"),
        }
    }

    /// Non-finite forces caught before the device.
    pub fn faults(&self) -> u64 {
        self.tick.counters().faults
    }

    /// Ticks recorded so far.
    pub fn ticks(&self) -> &[TickRecord] {
        &self.world.ticks
    }

    /// Physics steps recorded so far.
    pub fn steps(&self) -> &[PhysicsRecord] {
        &self.world.steps
    }

    /// Hands over the recorded trace (ticks, steps), leaving it empty.
    pub fn take_trace(&mut self) -> (Vec<TickRecord>, Vec<PhysicsRecord>) {
        (
            std::mem::take(&mut self.world.ticks),
            std::mem::take(&mut self.world.steps),
        )
    }

    /// Passes the records made since the last call to `f` (ticks, steps),
    /// then forgets them, keeping the buffers' room: how a streamed run
    /// hands its trace to the recorder chunk by chunk.
    pub fn drain_trace(&mut self, mut f: impl FnMut(&[TickRecord], &[PhysicsRecord])) {
        f(&self.world.ticks, &self.world.steps);
        self.world.ticks.clear();
        self.world.steps.clear();
    }

    /// Link statistics (haptic end, physics end).
    pub fn link_stats(&self) -> (LinkStats, LinkStats) {
        (
            self.world.haptic_end.stats(),
            self.world.physics_end.stats(),
        )
    }

    /// Runs ticks until `duration` (s) of virtual time.
    pub fn run_for(&mut self, duration: f64) -> Result<()> {
        let n = (duration / self.period).round() as u64;
        for _ in 0..n {
            self.step_tick()?;
        }
        Ok(())
    }

    /// One haptic tick (see the module docs).
    pub fn step_tick(&mut self) -> Result<()> {
        let t = self.time();
        self.tick.tick(t, &mut self.world)?;
        self.n += 1;
        Ok(())
    }
}

impl TickObserver for VirtualWorld {
    fn on_probe(&mut self, probe: &ProbeMsg) -> Result<()> {
        let t = probe.t_device;
        if self.physics.is_none() {
            return Ok(());
        }
        self.haptic_end
            .send(Message::Probe(*probe), t)
            .context("haptic → physics link")?;
        self.physics_tick(t)?;
        self.haptic_receive(t)
    }

    fn on_physics_step(&mut self, _: &PhysicsSide, _: &ProbeMsg, step: &PhysicsRecord) {
        if self.steps.len() < self.steps.capacity() {
            self.steps.push(*step);
        }
    }

    fn on_tick(&mut self, record: &TickRecord) {
        if self.ticks.len() < self.ticks.capacity() {
            self.ticks.push(*record);
        }
    }
}

impl VirtualWorld {
    fn physics_tick(&mut self, t: f64) -> Result<()> {
        let eps = 1e-9;
        if let Some((due, msg)) = self.pending {
            if due <= t + eps {
                self.physics_end
                    .send(Message::Sample(msg), t)
                    .context("physics → haptic link")?;
                self.pending = None;
            }
        }
        self.physics_end.poll(t).context("physics link")?;
        while let Some(m) = self.physics_end.recv(t).context("physics link")? {
            if let Message::Probe(pm) = m {
                self.latest_probe = Some(pm);
            }
        }
        if t + eps >= self.next_physics {
            if let (Some(probe), Some(physics)) = (self.latest_probe, self.physics.as_mut()) {
                let (mut sample, mut rec) = physics.step(&probe, self.physics_period, t);
                physics.check()?;
                sample.probe_seq = probe.header.seq;
                rec.t = t;
                if self.steps.len() < self.steps.capacity() {
                    self.steps.push(rec);
                }
                if self.compute_delay <= eps {
                    self.physics_end
                        .send(Message::Sample(sample), t)
                        .context("physics → haptic link")?;
                } else {
                    self.pending = Some((t + self.compute_delay, sample));
                }
            }
            self.next_physics += self.physics_period;
        }
        Ok(())
    }

    fn haptic_receive(&mut self, t: f64) -> Result<()> {
        self.haptic_end.poll(t).context("haptic link")?;
        while let Some(m) = self.haptic_end.recv(t).context("haptic link")? {
            if let Message::Sample(s) = m {
                self.sink.on_sample(&s, t);
            }
        }
        Ok(())
    }
}
