//! A session of the live system: its physics, link and haptic-loop
//! threads, started with one set of settings and stopped to change them.
//!
//! Stopping a session hands its state to the next ([`Carried`]): the thigh's
//! deformation and velocities, and the device's and hand's positions, so
//! that changing the coupling mode, the physics rate or the latency keeps the
//! probe where it is, pressed as it was, instead of restarting from rest.

use super::hardware_loop::{self, BoxedDevice, DeviceLoop, SkinNormal};
use super::publish::Publisher;
use super::route::{HandRoute, RouteFollower};
use super::shared::{HandTarget, HapticStatus, Shared};
use crate::haptic_side::{haptic_side_for, SampleSink};
use crate::live::CouplingMode;
use crate::live::HapticPriority;
use crate::physics_loop::{physics_loop_with, Clock};
use crate::physics_side::PhysicsSide;
use crate::scenario::Scenario;
use crate::tick::{HapticTick, TickObserver};
use crate::trace::{PhysicsRecord, TickRecord};
use anyhow::{Context, Result};
use echothigh_device::{ExamScript, HapticDevice, SimulatedDevice, SimulatedHand};
use echothigh_haptics::{LoopRunner, Vec3};
use echothigh_transport::{InProcessEndpoint, Link, Message, ProbeMsg};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// The device and the hand gripping it (m, m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DeviceState {
    /// End-effector position (m).
    pub position: Vec3,
    /// End-effector velocity (m/s).
    pub velocity: Vec3,
    /// The hand's setpoint (m).
    pub setpoint: Vec3,
}

/// What a stopped session hands to the next one.
#[derive(Default)]
pub(super) struct Carried {
    /// The physics side: the thigh's positions and velocities, the contact.
    pub physics: Option<PhysicsSide>,
    /// The device and hand (none: start at the hand's target, at rest).
    pub device: Option<DeviceState>,
    /// The real device driving the probe (issue 15), when one is attached.
    pub hardware: Option<BoxedDevice>,
}

/// What drove the probe in a session, handed back when it stops.
pub(super) enum Driver {
    /// The simulated device and hand, following the page or the script.
    Hand(DeviceState),
    /// A real device.
    Hardware(BoxedDevice),
}

/// The running threads of one session.
pub(super) struct Session {
    stop: Arc<AtomicBool>,
    /// The physics thread (none in `direct` mode, where the haptic loop steps it).
    physics: Option<JoinHandle<PhysicsSide>>,
    /// The haptic loop: returns the physics it stepped (`direct`) and the device.
    haptic: JoinHandle<(Option<PhysicsSide>, Driver)>,
    others: Vec<JoinHandle<()>>,
    /// The hand's route to its target, read by the haptic loop.
    pub target: triple_buffer::Input<HandRoute>,
}

impl Session {
    /// Stops every thread and returns their state (what a thread that
    /// panicked held is lost: the next session starts that part from rest).
    pub fn stop(self) -> Carried {
        self.stop.store(true, Ordering::Relaxed);
        let panicked = |name: &str| tracing::error!("the live {name} thread panicked");
        for h in self.others {
            if h.join().is_err() {
                panicked("link");
            }
        }
        let threaded = self
            .physics
            .and_then(|h| h.join().map_err(|_| panicked("physics")).ok());
        let (direct, device, hardware) = match self.haptic.join() {
            Ok((p, Driver::Hand(d))) => (p, Some(d), None),
            Ok((p, Driver::Hardware(h))) => (p, None, Some(h)),
            Err(_) => {
                // A real device unwound with the thread: its drop released it.
                panicked("haptic");
                (None, None, None)
            }
        };
        Carried {
            physics: threaded.or(direct),
            device,
            hardware,
        }
    }
}

/// Starts the threads of a session for `scenario`, continuing from `carried`
/// (the thigh's state, and the device's unless the exam script drives it).
/// With `carried.hardware` the real device drives the probe (its name,
/// `device_name`, for the page); else the simulated hand follows `target`
/// or the exam script.
pub(super) fn start_session(
    shared: &Arc<Shared>,
    scenario: &Scenario,
    exam: bool,
    target: HandTarget,
    carried: Carried,
    device_name: &str,
) -> Result<Session> {
    let c = scenario.coupling.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let (target_in, mut target_out) = triple_buffer::triple_buffer(&HandRoute::to(target));
    let (status_in, status_out) = triple_buffer::triple_buffer(&HapticStatus::default());
    *shared
        .haptic
        .lock()
        .map_err(|_| anyhow::anyhow!("live state poisoned"))? = Some(status_out);
    let mut hardware = carried.hardware;
    let (device_in, device_out) = if hardware.is_some() {
        let (i, o) = triple_buffer::triple_buffer(&Default::default());
        (Some(i), Some(o))
    } else {
        (None, None)
    };
    *shared
        .device
        .lock()
        .map_err(|_| anyhow::anyhow!("live state poisoned"))? = device_out;
    let exam = exam && hardware.is_none();
    // Before any thread starts: an error here loses nothing.
    let skin = hardware
        .as_ref()
        .map(|_| SkinNormal::of(scenario))
        .transpose()?;
    let device = if exam {
        let script = ExamScript::new(scenario.exam_script_config()?).map_err(anyhow::Error::msg)?;
        let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
        SimulatedDevice::with_hand(scenario.device(), hand).map_err(anyhow::Error::msg)?
    } else {
        let at_target = DeviceState {
            position: Vec3::from(target.position),
            velocity: Vec3::zeros(),
            setpoint: Vec3::from(target.position),
        };
        let state = carried.device.unwrap_or(at_target);
        let hand = SimulatedHand::new(scenario.hand, state.setpoint).map_err(anyhow::Error::msg)?;
        let mut d =
            SimulatedDevice::with_hand(scenario.device(), hand).map_err(anyhow::Error::msg)?;
        d.set_state(state.position, state.velocity);
        d
    };
    let start_setpoint = if exam {
        device.position()
    } else {
        carried
            .device
            .map_or(Vec3::from(target.position), |s| s.setpoint)
    };
    let mut carried_physics = carried.physics;
    let mut physics_for = |scenario: &Scenario| match carried_physics.take() {
        Some(p) => Ok(p),
        None => PhysicsSide::new(scenario),
    };
    let (sink, source) = haptic_side_for(c.mode, scenario)?;
    let (haptic_end, physics_end) = scenario.in_process_link();
    let (pos_in, pos_out) = triple_buffer::triple_buffer(&(0.0, ProbeMsg::default(), false));
    let clock = Clock::start();
    let mut others = Vec::new();
    let mut physics_thread = None;
    let mut publisher = Publisher::new(shared.clone(), scenario);
    let direct = c.mode == CouplingMode::Direct;
    let mut direct_physics: Option<PhysicsSide> = if direct {
        Some(physics_for(scenario)?)
    } else {
        None
    };
    if !direct {
        let mut physics = physics_for(scenario)?;
        let (st, rate, sh) = (stop.clone(), c.physics_rate, shared.clone());
        let realtime = scenario.haptics.runner.realtime_priority;
        let mut physics_end: InProcessEndpoint = physics_end;
        physics_thread = Some(
            std::thread::Builder::new()
                .name("physics".into())
                .spawn(move || {
                    crate::physics_loop::request_physics_priority(realtime);
                    let mut records = crate::recorder::RecordSink::Discard;
                    let r = physics_loop_with(
                        &mut physics,
                        &mut physics_end,
                        clock,
                        &st,
                        rate,
                        f64::INFINITY,
                        &mut records,
                        &mut |ph, probe| publisher.publish(ph, probe, clock.now()),
                    );
                    if let Err(e) = r {
                        sh.report_fault("physics", &e);
                    }
                    physics
                })
                .context("starting the physics thread")?,
        );
        let (st, sh) = (stop.clone(), shared.clone());
        others.push(
            std::thread::Builder::new()
                .name("link".into())
                .spawn(move || {
                    if let Err(e) = link_thread(haptic_end, sink, pos_out, clock, &st) {
                        // Without the link the haptic side renders a stale
                        // model: stop the whole session (the loop releases
                        // the device) and tell the page.
                        sh.report_fault("link", &e);
                        st.store(true, Ordering::Relaxed);
                    }
                })
                .context("starting the link thread")?,
        );
        publisher = Publisher::new(shared.clone(), scenario);
    }
    let (st, sh, scale, loop_cfg) = (
        stop.clone(),
        shared.clone(),
        scenario.device().force_scale(),
        scenario.haptics.runner.clone(),
    );
    let mut runner = LoopRunner::new(&loop_cfg).map_err(anyhow::Error::msg)?;
    let rt = loop_cfg.realtime_priority;
    let period = 1.0 / loop_cfg.rate_hz;
    let observer = LiveObserver::new(pos_in, status_in, publisher, period);
    if let (Some(hw), Some(device_in), Some(skin)) = (hardware.take(), device_in, skin) {
        let mut tick = HapticTick::new(hw, source, scale, direct_physics.take(), period);
        // Real time: the `direct` tick renders the force only (its 1 ms).
        tick.set_direct_queries(false);
        let device_loop = DeviceLoop::new(tick, observer, skin, device_in, target.orientation);
        let haptic = hardware_loop::spawn(
            device_loop,
            runner,
            clock,
            stop.clone(),
            shared.clone(),
            device_name.to_string(),
            rt,
        )?;
        return Ok(Session {
            stop,
            physics: physics_thread,
            haptic,
            others,
            target: target_in,
        });
    }
    let mut observer = observer;
    let mut tick = HapticTick::new(device, source, scale, direct_physics.take(), period);
    tick.set_direct_queries(false);
    if exam {
        tick.set_orientation(scenario.probe_orientation()?);
    }
    if let Some(h) = tick.device_mut().hand_mut() {
        h.set_setpoint(start_setpoint, Vec3::zeros());
    }
    let haptic = std::thread::Builder::new()
        .name("haptic-loop".into())
        .spawn(move || {
            raise_priority(&sh, rt);
            let mut follower = RouteFollower::new(HandRoute::to(target));
            runner.run(&st, None, |_, _| {
                let now = clock.now();
                if !exam {
                    if let Some(h) = tick.device_mut().hand_mut() {
                        let at = h.setpoint();
                        let tgt = follower.target(target_out.read(), [at.x, at.y, at.z]);
                        h.slew_towards(Vec3::from(tgt.position), HAND_REACH_SPEED, period);
                        tick.set_orientation(tgt.orientation);
                    }
                }
                if let Err(e) = tick.tick(now, &mut observer) {
                    sh.report_fault("haptic", &e);
                    st.store(true, Ordering::Relaxed);
                }
            });
            tick.release();
            let setpoint = tick
                .device()
                .hand()
                .map_or(tick.device().position(), |h| h.setpoint());
            let state = DeviceState {
                position: tick.device().position(),
                velocity: tick.device().velocity(),
                setpoint,
            };
            let (_, direct) = tick.into_parts();
            (direct, Driver::Hand(state))
        })
        .context("starting the haptic loop")?;
    Ok(Session {
        stop,
        physics: physics_thread,
        haptic,
        others,
        target: target_in,
    })
}

/// Raises the calling (haptic) thread's priority where the OS permits it:
/// the highest priority of its normal time-sharing policy (on Linux, nice
/// −20, which needs CAP_SYS_NICE), so that the physics and the browser on a
/// 2-core machine do not starve it (issue 19: 0 N drop-outs under load).
/// Not a real-time FIFO policy: the loop's sleeper spins its last ~100 µs,
/// and a FIFO thread spinning would starve the physics thread. Failure is
/// logged, not fatal.
pub(super) fn raise_priority(shared: &Shared, realtime: bool) {
    let got = haptic_priority(realtime);
    shared
        .haptic_priority
        .store(got as u8, std::sync::atomic::Ordering::Relaxed);
    match got {
        HapticPriority::Realtime => tracing::info!("haptic loop at real-time priority (FIFO)"),
        HapticPriority::Raised => tracing::info!(
            "haptic loop at the highest time-sharing priority (real-time was refused: without CAP_SYS_NICE or an rtprio limit)"
        ),
        HapticPriority::Normal => {
            tracing::warn!("haptic loop at normal priority (raising it was refused)")
        }
    }
}

/// Puts the calling (haptic) thread where the loop runner will put it, and
/// says which it got (issue 19: "real-time priority ... where permitted";
/// the page shows it): with `realtime` (`[haptics.runner]
/// realtime_priority`, default true) the runner's own request, FIFO where
/// permitted ([`echothigh_haptics::runner::request_realtime_priority`]: the
/// runner makes the same call as it starts, so the report is what the loop
/// runs at), else the highest time-sharing priority. With FIFO the
/// browser's work cannot delay the tick on any core: the thread preempts
/// every time-shared thread.
fn haptic_priority(realtime: bool) -> HapticPriority {
    use thread_priority::{set_current_thread_priority, ThreadPriority};
    if realtime && echothigh_haptics::runner::request_realtime_priority() {
        return HapticPriority::Realtime;
    }
    match set_current_thread_priority(ThreadPriority::Max) {
        Ok(()) => HapticPriority::Raised,
        Err(_) => HapticPriority::Normal,
    }
}

/// How fast the simulated hand reaches for the page's target (m/s): a mouse
/// teleports, a hand placing a probe moves ~0.2 m/s.
const HAND_REACH_SPEED: f64 = 0.2;

/// The live haptic loop's observer: the pose to the link thread, the status
/// to the page (both lock-free single-slot handoffs), and in `direct`
/// coupling the physics state to the publisher every 30 ms.
pub(super) struct LiveObserver {
    pose: triple_buffer::Input<(f64, ProbeMsg, bool)>,
    status: triple_buffer::Input<HapticStatus>,
    publisher: Publisher,
    last_publish: f64,
    late: u64,
    ticks: u64,
    last_tick: Option<f64>,
    period: f64,
}

impl LiveObserver {
    fn new(
        pose: triple_buffer::Input<(f64, ProbeMsg, bool)>,
        status: triple_buffer::Input<HapticStatus>,
        publisher: Publisher,
        period: f64,
    ) -> Self {
        LiveObserver {
            pose,
            status,
            publisher,
            last_publish: -1.0,
            late: 0,
            ticks: 0,
            last_tick: None,
            period,
        }
    }
}

impl TickObserver for LiveObserver {
    fn on_probe(&mut self, probe: &ProbeMsg) -> Result<()> {
        let now = probe.t_device;
        if let Some(l) = self.last_tick {
            self.late += u64::from(now - l > 1.5 * self.period);
        }
        self.last_tick = Some(now);
        self.pose.write((now, *probe, true));
        Ok(())
    }

    fn on_physics_step(&mut self, physics: &PhysicsSide, probe: &ProbeMsg, step: &PhysicsRecord) {
        if step.t - self.last_publish > 0.03 {
            self.publisher.publish(physics, probe, step.t);
            self.last_publish = step.t;
        }
    }

    fn on_tick(&mut self, r: &TickRecord) {
        self.ticks += 1;
        let ticks = self.ticks;
        self.status.write(HapticStatus {
            device: r.device,
            proxy: r.proxy,
            force: r.force,
            model_age: r.model_age,
            ticks,
            late: self.late,
            elapsed: r.t,
        });
    }
}

/// The link thread of the live system: device pose out, samples in, until
/// `stop`; a link error ends it and is returned.
fn link_thread(
    mut link: InProcessEndpoint,
    mut sink: SampleSink,
    mut pos: triple_buffer::Output<(f64, ProbeMsg, bool)>,
    clock: Clock,
    stop: &AtomicBool,
) -> Result<()> {
    let sleeper = spin_sleep::SpinSleeper::default();
    let mut last_sent = -1.0;
    while !stop.load(Ordering::Relaxed) {
        let now = clock.now();
        let (t, probe, valid) = *pos.read();
        if valid && t > last_sent {
            link.send(Message::Probe(probe), now)
                .context("sending the probe pose")?;
            last_sent = t;
        }
        link.poll(now).context("polling the link")?;
        while let Some(m) = link.recv(now).context("receiving a sample")? {
            if let Message::Sample(s) = m {
                sink.on_sample(&s, now);
            }
        }
        sleeper.sleep(Duration::from_micros(500));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 16: a link error ends the link thread with the error (it used
    /// to be logged and dropped, or ignored for `poll`/`recv`), which the
    /// thread's wrapper then reports to the page and turns into a stop.
    #[test]
    fn a_link_error_ends_the_link_thread_with_the_error() {
        let scenario = Scenario::default();
        let (sink, _source) = haptic_side_for(CouplingMode::Buffer, &scenario).unwrap();
        let (mut haptic_end, _physics_end) = scenario.in_process_link();
        haptic_end.close(0.0).unwrap();
        let (mut pos_in, pos_out) =
            triple_buffer::triple_buffer(&(0.0, ProbeMsg::default(), false));
        pos_in.write((1.0, ProbeMsg::default(), true));
        let stop = AtomicBool::new(false);
        let err = link_thread(haptic_end, sink, pos_out, Clock::start(), &stop).unwrap_err();
        assert!(
            format!("{err:#}").contains("sending the probe pose"),
            "{err:#}"
        );
        // Stopped before any error: a clean end.
        let (sink, _source) = haptic_side_for(CouplingMode::Buffer, &scenario).unwrap();
        let (haptic_end, _physics_end) = scenario.in_process_link();
        let (_pos_in, pos_out) = triple_buffer::triple_buffer(&(0.0, ProbeMsg::default(), false));
        stop.store(true, Ordering::Relaxed);
        link_thread(haptic_end, sink, pos_out, Clock::start(), &stop).unwrap();
    }
}
