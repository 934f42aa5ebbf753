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

use super::haptic_side::{haptic_side_for, ForceSource, Rendered, SampleSink};
use super::physics_side::PhysicsSide;
use super::trace::{PhysicsRecord, TickRecord};
use crate::live::CouplingMode;
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_device::{
    ExamPhase, ExamScript, ForceScale, HapticDevice, SimulatedDevice, SimulatedHand,
};
use echothigh_haptics::Vec3;
use echothigh_transport::{InProcessEndpoint, Link, Message, ProbeMsg, SampleMsg};

/// Probe orientation of the exam pose: face down (−y), width along x.
pub const EXAM_ORIENTATION: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// A deterministic run in progress.
pub struct VirtualRun {
    mode: CouplingMode,
    period: f64,
    physics_period: f64,
    compute_delay: f64,
    physics: PhysicsSide,
    sink: SampleSink,
    source: ForceSource,
    device: SimulatedDevice,
    scale: ForceScale,
    haptic_end: InProcessEndpoint,
    physics_end: InProcessEndpoint,
    pending: Option<(f64, SampleMsg)>,
    next_physics: f64,
    latest_probe: Option<ProbeMsg>,
    tick: u64,
    /// Ticks recorded so far.
    pub ticks: Vec<TickRecord>,
    /// Physics steps recorded so far.
    pub steps: Vec<PhysicsRecord>,
    faults: u64,
}

impl VirtualRun {
    /// Builds the run for `scenario` (validated), with the hand following
    /// the scenario's exam script. Allocates the trace buffers for
    /// `scenario.run.duration`.
    pub fn new(scenario: &Scenario) -> Result<Self> {
        let script = ExamScript::new(scenario.exam.clone()).map_err(anyhow::Error::msg)?;
        let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
        let device =
            SimulatedDevice::with_hand(scenario.device, hand).map_err(anyhow::Error::msg)?;
        Self::with_device(scenario, device)
    }

    /// Builds the run with a given simulated device (and its hand).
    pub fn with_device(scenario: &Scenario, device: SimulatedDevice) -> Result<Self> {
        let c = &scenario.coupling;
        let physics = PhysicsSide::new(scenario).context("building the physical model")?;
        let (sink, source) = haptic_side_for(c.mode, scenario)?;
        let (haptic_end, physics_end) = scenario.in_process_link();
        let n_ticks = (scenario.run.duration * c.haptic_rate).ceil() as usize + 1;
        let n_steps = (scenario.run.duration / c.physics_period()).ceil() as usize + 2;
        Ok(VirtualRun {
            mode: c.mode,
            period: c.haptic_period(),
            physics_period: c.physics_period(),
            compute_delay: c.compute_delay * c.physics_period(),
            physics,
            sink,
            source,
            scale: scenario.device.force_scale(),
            device,
            haptic_end,
            physics_end,
            pending: None,
            next_physics: 0.0,
            latest_probe: None,
            tick: 0,
            ticks: Vec::with_capacity(n_ticks),
            steps: Vec::with_capacity(n_steps),
            faults: 0,
        })
    }

    /// Current virtual time (s).
    pub fn time(&self) -> f64 {
        self.tick as f64 * self.period
    }

    /// The simulated device.
    pub fn device(&self) -> &SimulatedDevice {
        &self.device
    }

    /// The physics side.
    pub fn physics(&self) -> &PhysicsSide {
        &self.physics
    }

    /// The physics side, mutable (queries).
    pub fn physics_mut(&mut self) -> &mut PhysicsSide {
        &mut self.physics
    }

    /// Non-finite forces caught before the device.
    pub fn faults(&self) -> u64 {
        self.faults
    }

    /// Link statistics (haptic end, physics end).
    pub fn link_stats(
        &self,
    ) -> (
        echothigh_transport::LinkStats,
        echothigh_transport::LinkStats,
    ) {
        (self.haptic_end.stats(), self.physics_end.stats())
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
        let p = self.device.position();
        let probe = ProbeMsg::new(t, p.into(), EXAM_ORIENTATION, 0);
        let rendered = if self.mode == CouplingMode::Direct {
            let (sample, mut rec) = self.physics.step(&probe, self.physics_period, t);
            self.physics.check()?;
            rec.t = t;
            self.steps.push(rec);
            self.source.direct(Vec3::from(sample.force), p, 0.0)
        } else {
            self.haptic_end
                .send(Message::Probe(probe), t)
                .context("haptic → physics link")?;
            self.physics_tick(t)?;
            self.haptic_receive(t)?;
            self.source.tick(p, t)
        };
        self.render(t, p, rendered);
        self.tick += 1;
        Ok(())
    }

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
            if let Some(probe) = self.latest_probe {
                let (mut sample, mut rec) = self.physics.step(&probe, self.physics_period, t);
                self.physics.check()?;
                sample.probe_seq = probe.header.seq;
                rec.t = t;
                self.steps.push(rec);
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

    fn render(&mut self, t: f64, p: Vec3, r: Rendered) {
        if r.fault {
            self.faults += 1;
        }
        let device_force = self.scale.tissue_to_device(r.force);
        self.device.set_force(device_force);
        let status = self.device.exam_status();
        self.ticks.push(TickRecord {
            t,
            device: p.into(),
            proxy: r.proxy.into(),
            force: r.force.into(),
            device_force: self.device.force().into(),
            model_age: if r.model_age.is_finite() {
                r.model_age
            } else {
                -1.0
            },
            phase: status.map_or(255, |s| phase_code(s.phase)),
            holding: status.is_some_and(|s| s.phase == ExamPhase::Hold),
        });
        self.device.advance(self.period);
    }
}

/// A stable numeric code of an exam phase for the traces.
pub fn phase_code(p: ExamPhase) -> u8 {
    match p {
        ExamPhase::Approach => 0,
        ExamPhase::Press => 1,
        ExamPhase::Hold => 2,
        ExamPhase::Slide => 3,
        ExamPhase::Release => 4,
        ExamPhase::Done => 5,
    }
}
