//! The one haptic tick, as CHAI3D writes its loop: read the device, compute
//! the force, apply it, count. Every deployment runs this tick and nothing
//! else at the haptic rate: the virtual clock ([`crate::virtual_clock`]), the
//! threads of `run` and the `haptic-client` process ([`crate::client`]) and
//! the live system behind the viewer ([`crate::live_system`]).
//!
//! What differs between deployments is outside the tick, in its
//! [`TickObserver`]: where the probe pose goes (a lock-free handoff to a link
//! thread, or the virtual clock's own link and physics), where the record
//! goes (a preallocated buffer, or a lock-free ring to a writer thread), what
//! the page sees. The tick allocates nothing, takes no lock and does no I/O;
//! its observers must keep that promise too (`tests/no_alloc_tick.rs` runs it
//! as the binary does).

use crate::haptic_side::{ForceSource, Rendered};
use crate::physics_side::PhysicsSide;
use crate::recorder::RecordSink;
use crate::trace::{PhysicsRecord, TickRecord};
use echothigh_device::{ExamPhase, ForceScale, HapticDevice, SimulatedDevice};
use echothigh_haptics::Vec3;
use echothigh_transport::ProbeMsg;

/// Probe orientation of the exam pose: face down (−y), width along x
/// (unit quaternion w, x, y, z).
pub const EXAM_ORIENTATION: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// What the tick counts (monotonic since the tick was built).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TickCounters {
    /// Ticks run.
    pub ticks: u64,
    /// Ticks on which the force computation caught a fault (non-finite
    /// input or output, replaced by a safe force).
    pub faults: u64,
}

/// A device the tick can drive: any [`HapticDevice`], plus what the trace
/// records of a scripted hand (the exam phase), when there is one.
pub trait TickDevice: HapticDevice {
    /// The exam phase of a scripted hand, if the device has one.
    fn exam_phase(&self) -> Option<ExamPhase> {
        None
    }
}

impl TickDevice for SimulatedDevice {
    fn exam_phase(&self) -> Option<ExamPhase> {
        self.exam_status().map(|s| s.phase)
    }
}

/// A device chosen at run time (`--device NAME`): a real one has no script.
impl TickDevice for Box<dyn HapticDevice + Send> {}

/// Sees each tick. Every method runs inside the real-time tick: it must not
/// allocate, lock a contended mutex, do I/O or wait.
pub trait TickObserver {
    /// The probe pose read this tick (loop time `probe.t_sent`), before the
    /// force is computed: the threaded deployments hand it to their link
    /// thread; the virtual clock runs its link and physics here. An error
    /// stops the deployment.
    fn on_probe(&mut self, _probe: &ProbeMsg) -> anyhow::Result<()> {
        Ok(())
    }
    /// In `direct` coupling, the physics stepped inside the tick.
    fn on_physics_step(
        &mut self,
        _physics: &PhysicsSide,
        _probe: &ProbeMsg,
        _step: &PhysicsRecord,
    ) {
    }
    /// The tick's record, after the force was applied.
    fn on_tick(&mut self, _record: &TickRecord) {}
}

/// An observer that sees nothing.
impl TickObserver for () {}

/// Two observers, called in order.
impl<A: TickObserver, B: TickObserver> TickObserver for (A, B) {
    fn on_probe(&mut self, probe: &ProbeMsg) -> anyhow::Result<()> {
        self.0.on_probe(probe)?;
        self.1.on_probe(probe)
    }
    fn on_physics_step(&mut self, physics: &PhysicsSide, probe: &ProbeMsg, step: &PhysicsRecord) {
        self.0.on_physics_step(physics, probe, step);
        self.1.on_physics_step(physics, probe, step);
    }
    fn on_tick(&mut self, record: &TickRecord) {
        self.0.on_tick(record);
        self.1.on_tick(record);
    }
}

/// The haptic loop's observer in the threaded deployments (`run`,
/// `haptic-client`): the probe pose goes to the link thread through a
/// lock-free single-slot handoff, the record to a [`RecordSink`] (the
/// recorder's ring, or memory).
pub struct HandoffObserver {
    pose: triple_buffer::Input<Option<ProbeMsg>>,
    ticks: RecordSink<TickRecord>,
}

impl HandoffObserver {
    /// The observer writing poses into `pose` and records into `ticks`.
    pub fn new(
        pose: triple_buffer::Input<Option<ProbeMsg>>,
        ticks: RecordSink<TickRecord>,
    ) -> Self {
        HandoffObserver { pose, ticks }
    }

    /// The record sink, after the loop.
    pub fn into_records(self) -> RecordSink<TickRecord> {
        self.ticks
    }
}

impl TickObserver for HandoffObserver {
    fn on_probe(&mut self, probe: &ProbeMsg) -> anyhow::Result<()> {
        self.pose.write(Some(*probe));
        Ok(())
    }

    fn on_tick(&mut self, record: &TickRecord) {
        self.ticks.push(*record);
    }
}

/// The haptic side's per-tick state: the device, the force source of the
/// coupling mode, the force scale and, in `direct` coupling, the physics.
pub struct HapticTick<D> {
    device: D,
    source: ForceSource,
    scale: ForceScale,
    direct: Option<PhysicsSide>,
    direct_queries: bool,
    period: f64,
    orientation: [f64; 4],
    counters: TickCounters,
}

impl<D: TickDevice> HapticTick<D> {
    /// The tick of a loop of period `period` (s). `direct`: the physics
    /// stepped inside the tick at the device position (`direct` coupling),
    /// `None` otherwise (the force comes from `source`).
    pub fn new(
        device: D,
        source: ForceSource,
        scale: ForceScale,
        direct: Option<PhysicsSide>,
        period: f64,
    ) -> Self {
        HapticTick {
            device,
            source,
            scale,
            direct,
            direct_queries: true,
            period,
            orientation: EXAM_ORIENTATION,
            counters: TickCounters::default(),
        }
    }

    /// One tick at loop time `now` (s): read the device, compute the force,
    /// apply it (scaled to the device, which then advances by one period),
    /// count. Returns what was rendered (tissue units).
    pub fn tick(&mut self, now: f64, observer: &mut impl TickObserver) -> anyhow::Result<Rendered> {
        // 1. Read the device.
        let p = self.device.position();
        // A device that senses the tool's orientation sets the probe's
        // (its rotation about the leg and its tilt); else the front end's.
        let orientation = self
            .device
            .orientation()
            .map_or(self.orientation, |q| [q.w, q.i, q.j, q.k]);
        let probe = ProbeMsg::new(now, p.into(), orientation, 0);
        observer.on_probe(&probe)?;
        // 2. Compute the force.
        let rendered = match self.direct.as_mut() {
            Some(physics) => {
                let (force, mut step) = if self.direct_queries {
                    let (sample, step) = physics.step(&probe, self.period, now);
                    (Vec3::from(sample.force), step)
                } else {
                    physics.step_force(&probe, self.period, now)
                };
                // A diverged model ends the run with an error naming the node.
                physics.check()?;
                step.t = now;
                observer.on_physics_step(physics, &probe, &step);
                self.source.direct(force, p, now)
            }
            None => self.source.tick(p, now),
        };
        // 3. Apply it.
        self.device
            .set_force(self.scale.tissue_to_device(rendered.force));
        let phase = self.device.exam_phase();
        let record = TickRecord {
            t: now,
            device: p.into(),
            proxy: rendered.proxy.into(),
            force: rendered.force.into(),
            device_force: self.device.force().into(),
            model_age: if rendered.model_age.is_finite() {
                rendered.model_age
            } else {
                -1.0
            },
            phase: phase.map_or(255, phase_code),
            holding: phase == Some(ExamPhase::Hold),
        };
        self.device.advance(self.period);
        // 4. Count.
        self.counters.ticks += 1;
        self.counters.faults += u64::from(rendered.fault);
        observer.on_tick(&record);
        Ok(rendered)
    }

    /// Whether the `direct` physics also answers the haptic queries (`D`,
    /// `∇D`, `k`) every tick: true by default (the virtual clock records
    /// them: the stability analysis reads `k` off the `direct` trace). The
    /// real-time deployments turn them off: the tick renders only the force,
    /// and on the whole-leg mesh the stiffness query's solve costs more than
    /// the step itself (issue 18), so with it the tick overran its 1 ms. The
    /// force is the same either way ([`PhysicsSide::step_force`]).
    pub fn set_direct_queries(&mut self, on: bool) {
        self.direct_queries = on;
    }

    /// Commands zero force: every loop calls it on its way out, whatever
    /// ended it.
    pub fn release(&mut self) {
        self.device.set_force(Vec3::zeros());
    }

    /// Sets the probe orientation sent with the position (unit quaternion
    /// w, x, y, z): the front end's or the device's pose; the exam pose by
    /// default.
    pub fn set_orientation(&mut self, orientation: [f64; 4]) {
        self.orientation = orientation;
    }

    /// The device.
    pub fn device(&self) -> &D {
        &self.device
    }

    /// The device, mutable (the live system moves its hand's target).
    pub fn device_mut(&mut self) -> &mut D {
        &mut self.device
    }

    /// The physics stepped inside the tick (`direct` coupling).
    pub fn direct_physics(&self) -> Option<&PhysicsSide> {
        self.direct.as_ref()
    }

    /// The physics stepped inside the tick, mutable (queries).
    pub fn direct_physics_mut(&mut self) -> Option<&mut PhysicsSide> {
        self.direct.as_mut()
    }

    /// The force source (telemetry).
    pub fn source(&self) -> &ForceSource {
        &self.source
    }

    /// The force source, mutable (ramps on transitions).
    pub fn source_mut(&mut self) -> &mut ForceSource {
        &mut self.source
    }

    /// Loop period (s).
    pub fn period(&self) -> f64 {
        self.period
    }

    /// What the tick counted.
    pub fn counters(&self) -> TickCounters {
        self.counters
    }

    /// Takes the tick apart: the device and the `direct` physics (handed to
    /// the next session of the live system).
    pub fn into_parts(self) -> (D, Option<PhysicsSide>) {
        (self.device, self.direct)
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
