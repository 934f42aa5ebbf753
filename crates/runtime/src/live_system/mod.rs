//! The live system behind `echothigh view`: the same parts as `run` (physics
//! thread, link thread with the model manager, 1 kHz haptic loop, simulated
//! device and hand) plus an imaging thread, driven by a front end through
//! [`LiveControl`] instead of a script.
//!
//! The haptic loop reads the hand's target through a lock-free single-slot
//! handoff and publishes its status the same way; the physics thread and the
//! imaging thread share their larger state (mesh positions, image) through
//! mutexes that the real-time side only ever `try_lock`s. Changing the mode,
//! rate or latency, or stopping the scripted exam, restarts the threads with
//! the new settings from where the thigh and the probe were ([`session`]);
//! playing the exam keeps the thigh and hands the probe to the script;
//! resetting starts from rest.

mod publish;
mod session;
mod shared;

use crate::live::{CouplingMode, LiveCommand, LiveControl, LiveMesh, LiveSnapshot, VeinKind};
use crate::physics_side::PhysicsSide;
use crate::scenario::Scenario;
use anyhow::Result;
use echothigh_imaging::{SectionDeformation, VeinState};
use nalgebra::{UnitQuaternion, Vector3};
use publish::spawn_imaging;
use session::{start_session, Carried, Session};
use shared::{vein_code, vein_of, HandTarget, ImageInput, ImageSlot, Shared};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex};

struct Inner {
    scenario: Scenario,
    session: Option<Session>,
    exam: bool,
    target: HandTarget,
}

/// What a restart keeps of the stopped session's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keep {
    /// Start from rest (reset).
    Nothing,
    /// Keep the thigh's state; the device starts afresh (the exam script
    /// takes the probe).
    Thigh,
    /// Keep the thigh and the device with the hand (a change of settings).
    ThighAndProbe,
}

/// The live system (see the module docs).
pub struct LiveSystem {
    shared: Arc<Shared>,
    inner: Mutex<Inner>,
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
            system.restart(&mut inner, Keep::Nothing)?;
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

    /// Stops the running threads (if any) and starts new ones with the
    /// current settings, continuing from what `keep` keeps of their state.
    fn restart(&self, inner: &mut Inner, keep: Keep) -> Result<()> {
        let mut carried = inner.session.take().map(Session::stop).unwrap_or_default();
        match keep {
            Keep::Nothing => carried = Carried::default(),
            Keep::Thigh => carried.device = None,
            Keep::ThighAndProbe => {}
        }
        inner.session = Some(start_session(
            &self.shared,
            &inner.scenario,
            inner.exam,
            inner.target,
            carried,
        )?);
        Ok(())
    }

    /// Stops every thread of the session.
    pub fn shutdown(&self) {
        if let Ok(mut inner) = self.inner.lock() {
            if let Some(s) = inner.session.take() {
                s.stop();
            }
        }
    }
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
        let restart = |this: &Self, inner: &mut Inner, keep| {
            this.restart(inner, keep).map_err(|e| format!("{e:#}"))
        };
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
                restart(self, &mut inner, Keep::Thigh)
            }
            LiveCommand::StopExam => {
                inner.exam = false;
                restart(self, &mut inner, Keep::ThighAndProbe)
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
                restart(self, &mut inner, Keep::ThighAndProbe)
            }
            LiveCommand::SetPhysicsRate { hz } => {
                finite("hz", hz, 10.0, inner.scenario.coupling.haptic_rate)?;
                inner.scenario.coupling.physics_rate = hz;
                restart(self, &mut inner, Keep::ThighAndProbe)
            }
            LiveCommand::SetLatency { seconds } => {
                finite("seconds", seconds, 0.0, 0.2)?;
                inner.scenario.link.latency = seconds;
                restart(self, &mut inner, Keep::ThighAndProbe)
            }
            LiveCommand::Reset => {
                inner.exam = false;
                restart(self, &mut inner, Keep::Nothing)
            }
        }
    }
}

impl Drop for LiveSystem {
    fn drop(&mut self) {
        self.shutdown();
    }
}
