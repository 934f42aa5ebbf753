//! The live system behind `echothigh view`: the same parts as `run` (physics
//! thread, link thread with the model manager, 1 kHz haptic loop, simulated
//! device and hand) plus an imaging thread, driven by a front end through
//! [`LiveControl`] instead of a script.
//!
//! The haptic loop reads the hand's target through a lock-free single-slot
//! handoff and publishes its status the same way; the physics thread and the
//! imaging thread share their larger state (mesh positions, image) through
//! mutexes that the real-time side only ever `try_lock`s. Changing the mode,
//! rates or latency, resetting, or playing the scripted exam restarts the
//! threads from rest with the new settings.

use super::haptic_side::{haptic_side_for, ForceSource, SampleSink};
use super::physics_loop::{physics_loop_with, Clock};
use super::physics_side::PhysicsSide;
use super::section::{lateral_offset, section_deformation, SectionScratch};
use crate::live::{CouplingMode, LiveCommand, LiveControl, LiveMesh, LiveSnapshot, VeinKind};
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_device::{ExamScript, HapticDevice, SimulatedDevice, SimulatedHand};
use echothigh_haptics::{LoopRunner, Vec3};
use echothigh_imaging::{Anatomy, FrameInput, Renderer, SectionDeformation, VeinState};
use echothigh_model::ThighGeometry;
use echothigh_transport::{in_process_pair, InProcessEndpoint, Link, Message, ProbeMsg};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Where the hand wants the probe.
#[derive(Debug, Clone, Copy, Default)]
struct HandTarget {
    /// Setpoint of the probe face centre (m).
    position: [f64; 3],
    /// Probe orientation (w, x, y, z).
    orientation: [f64; 4],
}

/// What the haptic loop reports every tick.
#[derive(Debug, Clone, Copy, Default)]
struct HapticStatus {
    device: [f64; 3],
    proxy: [f64; 3],
    force: [f64; 3],
    model_age: f64,
    ticks: u64,
    late: u64,
    elapsed: f64,
}

/// The echographic image's input, published by the physics.
struct ImageInput {
    deformation: SectionDeformation,
    pressure: f64,
    time: f64,
    /// Where the probe is relative to the vessels (m, along the skin).
    lateral_offset: f64,
}

struct ImageSlot {
    pixels: Vec<u8>,
    width: u32,
    height: u32,
    frame: u64,
}

struct Shared {
    mesh: LiveMesh,
    snapshot: Mutex<LiveSnapshot>,
    image_input: Mutex<ImageInput>,
    image: Mutex<ImageSlot>,
    vein: AtomicU8,
    haptic: Mutex<Option<triple_buffer::Output<HapticStatus>>>,
}

struct Session {
    stop: Arc<AtomicBool>,
    handles: Vec<JoinHandle<()>>,
    target: triple_buffer::Input<HandTarget>,
}

struct Inner {
    scenario: Scenario,
    session: Option<Session>,
    exam: bool,
    target: HandTarget,
}

/// The live system (see the module docs).
pub struct LiveSystem {
    shared: Arc<Shared>,
    inner: Mutex<Inner>,
}

fn vein_code(v: VeinState) -> u8 {
    match v {
        VeinState::Healthy => 0,
        VeinState::Acute => 1,
        VeinState::Chronic => 2,
    }
}

fn vein_of(code: u8) -> VeinState {
    match code {
        1 => VeinState::Acute,
        2 => VeinState::Chronic,
        _ => VeinState::Healthy,
    }
}

/// The hand target for a probe placed at `theta` (rad, 0 = top, positive
/// towards +x) and `z` (m) on the rest surface of the elliptic thigh, pressed
/// `depth` (m) along the inward normal and tilted by `tilt` (rad) about the
/// thigh axis.
fn target_on_surface(s: &Scenario, theta: f64, z: f64, depth: f64, tilt: f64) -> HandTarget {
    let (a, b) = (s.thigh.semi_axis_x, s.thigh.semi_axis_y);
    let tm = std::f64::consts::FRAC_PI_2 - theta;
    let point = Vector3::new(a * tm.cos(), b * tm.sin(), z);
    let normal = Vector3::new(b * tm.cos(), a * tm.sin(), 0.0).normalize();
    let p = point - normal * depth;
    let alpha = (-normal.x).atan2(normal.y) + tilt;
    let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), alpha);
    HandTarget {
        position: p.into(),
        orientation: [q.w, q.i, q.j, q.k],
    }
}

impl LiveSystem {
    /// Starts the live system for `scenario`, the probe resting above the top of the thigh.
    pub fn start(scenario: Scenario) -> Result<Arc<Self>> {
        let physics = PhysicsSide::new(&scenario)?;
        let mesh = physics.model().mesh();
        let live_mesh = LiveMesh {
            rest: mesh
                .rest_positions()
                .iter()
                .map(|p| [p.x as f32, p.y as f32, p.z as f32])
                .collect(),
            triangles: mesh
                .triangles()
                .iter()
                .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
                .collect(),
        };
        let img = scenario.imaging_config();
        let shared = Arc::new(Shared {
            snapshot: Mutex::new(LiveSnapshot {
                positions: live_mesh.rest.clone(),
                compression: vec![0.0; live_mesh.rest.len()],
                ..Default::default()
            }),
            mesh: live_mesh,
            image_input: Mutex::new(ImageInput {
                deformation: SectionDeformation::rest(0.04),
                pressure: 0.0,
                time: 0.0,
                lateral_offset: 0.0,
            }),
            image: Mutex::new(ImageSlot {
                pixels: vec![0; img.columns * img.rows],
                width: img.columns as u32,
                height: img.rows as u32,
                frame: 0,
            }),
            vein: AtomicU8::new(vein_code(scenario.patient.vein)),
            haptic: Mutex::new(None),
        });
        let target = target_on_surface(&scenario, 0.0, 0.0, -0.02, 0.0);
        let system = Arc::new(LiveSystem {
            shared,
            inner: Mutex::new(Inner {
                scenario,
                session: None,
                exam: false,
                target,
            }),
        });
        {
            let mut inner = system
                .inner
                .lock()
                .map_err(|_| anyhow::anyhow!("live state poisoned"))?;
            system.restart(&mut inner)?;
        }
        spawn_imaging(system.shared.clone(), system.inner_scenario()?)?;
        Ok(system)
    }

    fn inner_scenario(&self) -> Result<Scenario> {
        Ok(self
            .inner
            .lock()
            .map_err(|_| anyhow::anyhow!("live state poisoned"))?
            .scenario
            .clone())
    }

    /// Stops the running threads (if any) and starts new ones from rest.
    fn restart(&self, inner: &mut Inner) -> Result<()> {
        if let Some(s) = inner.session.take() {
            s.stop.store(true, Ordering::Relaxed);
            for h in s.handles {
                let _ = h.join();
            }
        }
        inner.session = Some(start_session(
            &self.shared,
            &inner.scenario,
            inner.exam,
            inner.target,
        )?);
        Ok(())
    }

    /// Stops every thread of the session.
    pub fn shutdown(&self) {
        if let Ok(mut inner) = self.inner.lock() {
            if let Some(s) = inner.session.take() {
                s.stop.store(true, Ordering::Relaxed);
                for h in s.handles {
                    let _ = h.join();
                }
            }
        }
    }
}

fn start_session(
    shared: &Arc<Shared>,
    scenario: &Scenario,
    exam: bool,
    target: HandTarget,
) -> Result<Session> {
    let c = scenario.coupling.clone();
    let stop = Arc::new(AtomicBool::new(false));
    let (target_in, mut target_out) = triple_buffer::triple_buffer(&target);
    let (status_in, status_out) = triple_buffer::triple_buffer(&HapticStatus::default());
    *shared
        .haptic
        .lock()
        .map_err(|_| anyhow::anyhow!("live state poisoned"))? = Some(status_out);
    let device = if exam {
        let script = ExamScript::new(scenario.exam.clone()).map_err(anyhow::Error::msg)?;
        let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
        SimulatedDevice::with_hand(scenario.device, hand).map_err(anyhow::Error::msg)?
    } else {
        let hand = SimulatedHand::new(scenario.hand, Vec3::from(target.position))
            .map_err(anyhow::Error::msg)?;
        let mut d =
            SimulatedDevice::with_hand(scenario.device, hand).map_err(anyhow::Error::msg)?;
        d.set_state(Vec3::from(target.position), Vec3::zeros());
        d
    };
    let (sink, source) = haptic_side_for(c.mode, scenario)?;
    let seed = scenario.run.seed;
    let (haptic_end, physics_end) = in_process_pair(
        seed,
        scenario
            .link
            .with_seed(seed.wrapping_mul(2).wrapping_add(1)),
        scenario
            .link
            .with_seed(seed.wrapping_mul(2).wrapping_add(2)),
    );
    let (pos_in, pos_out) = triple_buffer::triple_buffer(&(0.0, ProbeMsg::default(), false));
    let clock = Clock::start();
    let mut handles = Vec::new();
    let mut publisher = Publisher::new(shared.clone(), scenario);
    let direct = c.mode == CouplingMode::Direct;
    let mut direct_physics = if direct {
        Some(PhysicsSide::new(scenario)?)
    } else {
        None
    };
    if !direct {
        let mut physics = PhysicsSide::new(scenario)?;
        let (st, rate) = (stop.clone(), c.physics_rate);
        let mut physics_end: InProcessEndpoint = physics_end;
        handles.push(
            std::thread::Builder::new()
                .name("physics".into())
                .spawn(move || {
                    let mut records = Vec::new();
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
                        tracing::error!("physics thread stopped: {e:#}");
                    }
                })
                .context("starting the physics thread")?,
        );
        let st = stop.clone();
        handles.push(
            std::thread::Builder::new()
                .name("link".into())
                .spawn(move || link_thread(haptic_end, sink, pos_out, clock, &st))
                .context("starting the link thread")?,
        );
        publisher = Publisher::new(shared.clone(), scenario);
    }
    let (st, scale, loop_cfg) = (
        stop.clone(),
        scenario.device.force_scale(),
        scenario.haptics.runner.clone(),
    );
    let mut runner = LoopRunner::new(&loop_cfg).map_err(anyhow::Error::msg)?;
    let period = 1.0 / loop_cfg.rate_hz;
    let mut source: ForceSource = source;
    let mut status_in = status_in;
    let mut pos_in = pos_in;
    let mut device = device;
    handles.push(
        std::thread::Builder::new()
            .name("haptic-loop".into())
            .spawn(move || {
                let (mut ticks, mut late, mut last) = (0u64, 0u64, None::<f64>);
                let (mut last_pub, mut setpoint) = (-1.0, Vec3::from(target_out.read().position));
                runner.run(&st, None, |_, _| {
                    let now = clock.now();
                    if let Some(l) = last {
                        late += u64::from(now - l > 1.5 * period);
                    }
                    last = Some(now);
                    let tgt = *target_out.read();
                    if !exam {
                        // The mouse teleports; a hand moves at most 0.2 m/s.
                        let goal = Vec3::from(tgt.position);
                        let step = goal - setpoint;
                        let max = 0.2 * period;
                        setpoint += if step.norm() > max {
                            step * (max / step.norm())
                        } else {
                            step
                        };
                        if let Some(h) = device.hand_mut() {
                            h.set_setpoint(setpoint, Vec3::zeros());
                        }
                    }
                    let p = device.position();
                    let orientation = if exam {
                        [1.0, 0.0, 0.0, 0.0]
                    } else {
                        tgt.orientation
                    };
                    let probe = ProbeMsg::new(now, p.into(), orientation, 0);
                    pos_in.write((now, probe, true));
                    let r = match direct_physics.as_mut() {
                        Some(ph) => {
                            let (sample, _) = ph.step(&probe, period, now);
                            if now - last_pub > 0.03 {
                                publisher.publish(ph, &probe, now);
                                last_pub = now;
                            }
                            source.direct(Vec3::from(sample.force), p, 0.0)
                        }
                        None => source.tick(p, now),
                    };
                    device.set_force(scale.tissue_to_device(r.force));
                    device.advance(period);
                    ticks += 1;
                    status_in.write(HapticStatus {
                        device: p.into(),
                        proxy: r.proxy.into(),
                        force: r.force.into(),
                        model_age: r.model_age,
                        ticks,
                        late,
                        elapsed: now,
                    });
                });
            })
            .context("starting the haptic loop")?,
    );
    Ok(Session {
        stop,
        handles,
        target: target_in,
    })
}

/// The link thread of the live system: device pose out, samples in.
fn link_thread(
    mut link: InProcessEndpoint,
    mut sink: SampleSink,
    mut pos: triple_buffer::Output<(f64, ProbeMsg, bool)>,
    clock: Clock,
    stop: &AtomicBool,
) {
    let sleeper = spin_sleep::SpinSleeper::default();
    let mut last_sent = -1.0;
    while !stop.load(Ordering::Relaxed) {
        let now = clock.now();
        let (t, probe, valid) = *pos.read();
        if valid && t > last_sent {
            if let Err(e) = link.send(Message::Probe(probe), now) {
                tracing::error!("live link: {e}");
                return;
            }
            last_sent = t;
        }
        let _ = link.poll(now);
        while let Ok(Some(m)) = link.recv(now) {
            if let Message::Sample(s) = m {
                sink.on_sample(&s, now);
            }
        }
        sleeper.sleep(Duration::from_micros(500));
    }
}

/// Copies the physics state into the shared snapshot and image input,
/// never waiting for a lock.
struct Publisher {
    shared: Arc<Shared>,
    scratch: SectionScratch,
    section: SectionDeformation,
    width: f64,
    samples: usize,
    face_area: f64,
    asymptote: f64,
    bone_depth: f64,
    thigh: ThighGeometry,
    vessel_angle: f64,
    steps: u64,
    first: Option<f64>,
}

impl Publisher {
    fn new(shared: Arc<Shared>, s: &Scenario) -> Self {
        let img = s.imaging_config();
        let bone_depth = Anatomy::new(&img.anatomy, VeinState::Healthy)
            .map(|a| a.femur_top())
            .unwrap_or(0.04);
        Publisher {
            shared,
            scratch: SectionScratch::default(),
            section: SectionDeformation::rest(bone_depth),
            width: img.width,
            samples: 81,
            face_area: 4.0 * s.probe.half_width * s.probe.half_elevation,
            asymptote: s.tissue.asymptote(),
            bone_depth,
            thigh: s.thigh.clone(),
            vessel_angle: s.patient.vessel_angle,
            steps: 0,
            first: None,
        }
    }

    fn publish(&mut self, physics: &PhysicsSide, probe: &ProbeMsg, now: f64) {
        self.steps += 1;
        let first = *self.first.get_or_insert(now);
        let Some(sample) = physics.last_sample() else {
            return;
        };
        let model = physics.model();
        if let Ok(mut snap) = self.shared.snapshot.try_lock() {
            let mesh = model.mesh();
            let (x, anchors, rest) = (model.positions(), mesh.anchors(), mesh.rest_positions());
            snap.positions.clear();
            snap.compression.clear();
            for i in 0..x.len() {
                snap.positions
                    .push([x[i].x as f32, x[i].y as f32, x[i].z as f32]);
                let c =
                    ((rest[i] - anchors[i]).norm() - (x[i] - anchors[i]).norm()) / self.asymptote;
                snap.compression.push(c.clamp(0.0, 1.0) as f32);
            }
            snap.status.time = now;
            snap.status.probe_position = probe.position;
            snap.status.probe_orientation = probe.orientation;
            snap.status.physics_force = sample.force.into();
            snap.status.physics_rate = if now > first {
                (self.steps - 1) as f64 / (now - first)
            } else {
                0.0
            };
        }
        let pose: Isometry3<f64> = super::physics_side::probe_pose(probe);
        section_deformation(
            model,
            &pose,
            self.width,
            self.samples,
            self.bone_depth,
            &mut self.scratch,
            &mut self.section,
        );
        if let Ok(mut input) = self.shared.image_input.try_lock() {
            input.deformation.lateral.clone_from(&self.section.lateral);
            input
                .deformation
                .surface_displacement
                .clone_from(&self.section.surface_displacement);
            input.deformation.bone_depth = self.bone_depth;
            input.pressure = sample.force.norm() / self.face_area;
            input.time = now;
            input.lateral_offset = lateral_offset(&self.thigh, &pose, self.vessel_angle);
        }
    }
}

/// The imaging thread: renders the section under the probe at ~20 frames/s.
fn spawn_imaging(shared: Arc<Shared>, scenario: Scenario) -> Result<()> {
    let cfg = scenario.imaging_config();
    std::thread::Builder::new()
        .name("imaging".into())
        .spawn(move || {
            let mut vein = shared.vein.load(Ordering::Relaxed);
            let mut renderer = match Renderer::new(&cfg, vein_of(vein)) {
                Ok(r) => r,
                Err(e) => {
                    tracing::error!("imaging disabled: {e}");
                    return;
                }
            };
            let mut local = SectionDeformation::rest(0.04);
            let mut pixels = vec![0u8; cfg.columns * cfg.rows];
            loop {
                if Arc::strong_count(&shared) == 1 {
                    return;
                }
                let v = shared.vein.load(Ordering::Relaxed);
                if v != vein {
                    if let Ok(r) = Renderer::new(&cfg, vein_of(v)) {
                        renderer = r;
                        vein = v;
                    }
                }
                let (pressure, time, lateral_offset) = match shared.image_input.lock() {
                    Ok(i) => {
                        local.clone_from(&i.deformation);
                        (i.pressure, i.time, i.lateral_offset)
                    }
                    Err(_) => return,
                };
                let input = FrameInput {
                    deformation: &local,
                    probe_pressure: pressure,
                    time,
                    lateral_offset,
                };
                if renderer.render_into(&input, &mut pixels).is_ok() {
                    if let Ok(mut slot) = shared.image.lock() {
                        slot.pixels.copy_from_slice(&pixels);
                        slot.frame += 1;
                    }
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        })
        .context("starting the imaging thread")?;
    Ok(())
}

impl LiveControl for LiveSystem {
    fn mesh(&self) -> LiveMesh {
        self.shared.mesh.clone()
    }

    fn snapshot(&self, out: &mut LiveSnapshot) {
        if let Ok(s) = self.shared.snapshot.lock() {
            out.clone_from(&s);
        }
        if let Ok(inner) = self.inner.lock() {
            let c = &inner.scenario.coupling;
            out.status.mode = Some(c.mode);
            out.status.physics_rate_setting = c.physics_rate;
            out.status.latency_setting = inner.scenario.link.latency;
            out.status.exam_playing = inner.exam;
            out.status.max_force =
                inner.scenario.device.max_force / inner.scenario.device.force_scale;
            if c.mode == CouplingMode::Direct {
                out.status.physics_rate = c.haptic_rate;
            }
        }
        if let Ok(mut h) = self.shared.haptic.lock() {
            if let Some(o) = h.as_mut() {
                let st = *o.read();
                out.status.device = st.device;
                out.status.proxy = st.proxy;
                out.status.rendered_force = st.force;
                out.status.model_age = if st.model_age.is_finite() {
                    st.model_age
                } else {
                    -1.0
                };
                out.status.missed_deadlines = st.late;
                out.status.haptic_rate = if st.elapsed > 0.0 {
                    st.ticks as f64 / st.elapsed
                } else {
                    0.0
                };
            }
        }
    }

    fn image(&self, out: &mut Vec<u8>) -> (u32, u32, u64) {
        match self.shared.image.lock() {
            Ok(s) => {
                out.clone_from(&s.pixels);
                (s.width, s.height, s.frame)
            }
            Err(_) => (0, 0, 0),
        }
    }

    fn vein(&self) -> VeinKind {
        match vein_of(self.shared.vein.load(Ordering::Relaxed)) {
            VeinState::Healthy => VeinKind::Healthy,
            VeinState::Acute => VeinKind::Acute,
            VeinState::Chronic => VeinKind::Chronic,
        }
    }

    fn command(&self, cmd: LiveCommand) -> Result<(), String> {
        let mut inner = self
            .inner
            .lock()
            .map_err(|_| "live state poisoned".to_string())?;
        let finite = |name: &str, v: f64, lo: f64, hi: f64| -> Result<(), String> {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(format!("{name} must be in [{lo}, {hi}], got {v}"))
            }
        };
        let restart =
            |this: &Self, inner: &mut Inner| this.restart(inner).map_err(|e| format!("{e:#}"));
        match cmd {
            LiveCommand::Probe {
                theta,
                z,
                depth,
                tilt,
            } => {
                finite("theta", theta, -std::f64::consts::PI, std::f64::consts::PI)?;
                let half = 0.5 * inner.scenario.thigh.length;
                finite("z", z, -half, half)?;
                finite("depth", depth, -0.05, 0.04)?;
                finite("tilt", tilt, -0.6, 0.6)?;
                let t = target_on_surface(&inner.scenario, theta, z, depth, tilt);
                inner.target = t;
                if inner.exam {
                    return Err("the scripted exam is playing: stop it to drive the probe".into());
                }
                if let Some(s) = inner.session.as_mut() {
                    s.target.write(t);
                }
                Ok(())
            }
            LiveCommand::Lift => {
                let mut t = inner.target;
                t.position[1] += 0.03;
                inner.target = t;
                if let Some(s) = inner.session.as_mut() {
                    s.target.write(t);
                }
                Ok(())
            }
            LiveCommand::PlayExam => {
                inner.exam = true;
                restart(self, &mut inner)
            }
            LiveCommand::StopExam => {
                inner.exam = false;
                restart(self, &mut inner)
            }
            LiveCommand::SetVein { vein } => {
                let v = match vein {
                    VeinKind::Healthy => VeinState::Healthy,
                    VeinKind::Acute => VeinState::Acute,
                    VeinKind::Chronic => VeinState::Chronic,
                };
                inner.scenario.patient.vein = v;
                self.shared.vein.store(vein_code(v), Ordering::Relaxed);
                Ok(())
            }
            LiveCommand::SetMode { mode } => {
                inner.scenario.coupling.mode = mode;
                restart(self, &mut inner)
            }
            LiveCommand::SetPhysicsRate { hz } => {
                finite("hz", hz, 10.0, inner.scenario.coupling.haptic_rate)?;
                inner.scenario.coupling.physics_rate = hz;
                restart(self, &mut inner)
            }
            LiveCommand::SetLatency { seconds } => {
                finite("seconds", seconds, 0.0, 0.2)?;
                inner.scenario.link.latency = seconds;
                restart(self, &mut inner)
            }
            LiveCommand::Reset => {
                inner.exam = false;
                restart(self, &mut inner)
            }
        }
    }
}

impl Drop for LiveSystem {
    fn drop(&mut self) {
        self.shutdown();
    }
}
