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
//!
//! A case (issue 13, [`LiveSystem::set_case`]) replaces the patient's leg
//! under the physics and the imaging thread and gives each vein its
//! thrombus segments; the imaging thread publishes, with each frame, a
//! reading of the section under the probe ([`crate::live::SectionReading`]).

mod device_status;
mod doppler;
mod doppler_control;
#[cfg(test)]
mod doppler_tests;
mod hardware_loop;
mod imaging_priority;
mod imaging_source;
mod publish;
mod route;
mod session;
mod shared;

pub use device_status::device_drives_message;
pub use hardware_loop::{DeviceLoop, SkinNormal};
pub use imaging_priority::IMAGING_NICE;

use crate::live::{
    CommandLimits, CouplingMode, ImageInfo, LiveCommand, LiveControl, LiveMesh, LiveSnapshot,
    VeinState,
};
use crate::live_device::{LiveDevice, LiveDeviceInfo};
use crate::physics_side::PhysicsSide;
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_anatomy::Thrombi;
use echothigh_cases::Case;
use echothigh_imaging::SectionDeformation;
use echothigh_model::{LegSurface, ThighGeometry};
use nalgebra::{UnitQuaternion, Vector3};
use publish::ImagingThread;
use route::{HandRoute, Placement};
use session::{start_session, Carried, Session};
use shared::{vein_code, vein_of, HandTarget, ImageInput, ImageSlot, Shared};
use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

struct Inner {
    scenario: Scenario,
    session: Option<Session>,
    exam: bool,
    target: HandTarget,
    /// Where the page last placed the probe: (theta, z, tilt) (rad, m, rad).
    placement: (f64, f64, f64),
    /// The patient's leg the mesh follows (`None` on the cylinder).
    leg: Option<LegSurface>,
    /// The scenario's own thigh, restored when the case is cleared.
    base_thigh: ThighGeometry,
    /// The loaded case's name and its thrombus segments on `leg`.
    case: Option<(String, Arc<Thrombi>)>,
}

/// Height of the lifted probe above the rest skin (m, a negative depth): a
/// reset or a new question starts with the probe off the thigh, so the
/// force starts at zero and rises only as the trainee presses again (issue
/// 19: restarting pressed in gave 13–46 N spikes).
pub const LIFTED_DEPTH: f64 = -0.02;

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

/// The settings a snapshot reports, kept apart from [`Inner`] so that a
/// snapshot never waits for a restart that holds `Inner` (issue 16: a mode
/// change must not stall the pages).
#[derive(Debug, Clone, Copy)]
struct Settings {
    mode: CouplingMode,
    physics_rate: f64,
    latency: f64,
    exam: bool,
    max_force: f64,
    limits: CommandLimits,
}

impl Settings {
    fn of(inner: &Inner) -> Self {
        let s = &inner.scenario;
        Settings {
            mode: s.coupling.mode,
            physics_rate: s.coupling.physics_rate,
            latency: s.link.latency,
            exam: inner.exam,
            max_force: s.device.max_force / s.device().force_scale,
            limits: limits_of(s),
        }
    }
}

/// The live system (see the module docs).
pub struct LiveSystem {
    shared: Arc<Shared>,
    inner: Mutex<Inner>,
    settings: Mutex<Settings>,
    imaging: Mutex<Option<ImagingThread>>,
    /// The real device driving the probe, when one is attached (issue 15).
    device_info: Option<LiveDeviceInfo>,
    /// The live flow's controls, lines and status (issue 17).
    doppler: Arc<doppler::DopplerShared>,
}

/// The hand target for a probe placed at `theta` (rad, 0 = top, positive
/// towards +x, the lateral side) and `z` (m) on the rest surface, pressed
/// `depth` (m) along the inward normal and rocked by `tilt` (rad) about the
/// leg's axis. On a patient's leg the surface is its skin at
/// `s = centre_s − z` and `θ_leg = −theta`
/// ([`echothigh_model::LegSurface::hand_target`]); else the elliptic
/// cylinder's. Errors name the placement the leg cannot take.
fn target_on_surface(
    s: &Scenario,
    leg: Option<&LegSurface>,
    theta: f64,
    z: f64,
    depth: f64,
    tilt: f64,
) -> Result<HandTarget, String> {
    if let Some(leg) = leg {
        let t = leg
            .hand_target(leg.s_of_z(z), -theta, depth, 0.0)
            .map_err(|e| format!("probe placement: {e}"))?;
        let q = t.orientation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), tilt);
        return Ok(HandTarget {
            position: t.position.into(),
            orientation: [q.w, q.i, q.j, q.k],
        });
    }
    let (a, b) = (s.thigh.semi_axis_x, s.thigh.semi_axis_y);
    let tm = std::f64::consts::FRAC_PI_2 - theta;
    let point = Vector3::new(a * tm.cos(), b * tm.sin(), z);
    let normal = Vector3::new(b * tm.cos(), a * tm.sin(), 0.0).normalize();
    let p = point - normal * depth;
    let alpha = (-normal.x).atan2(normal.y) + tilt;
    let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), alpha);
    Ok(HandTarget {
        position: p.into(),
        orientation: [q.w, q.i, q.j, q.k],
    })
}

/// `t` moved `distance` (m) back along the probe's axis (its local `y`,
/// out of the skin).
fn lifted(t: HandTarget, distance: f64) -> HandTarget {
    let [w, i, j, k] = t.orientation;
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, i, j, k));
    let up = q * Vector3::y();
    let p = Vector3::from(t.position) + up * distance;
    HandTarget {
        position: p.into(),
        ..t
    }
}

/// The command ranges of `s` ([`LiveCommand::validate`]).
pub fn limits_of(s: &Scenario) -> CommandLimits {
    CommandLimits {
        half_length: 0.5 * s.thigh.length,
        max_physics_rate: s.coupling.haptic_rate,
    }
}

impl LiveSystem {
    /// Starts the live system for `scenario`, the probe resting above the top of the thigh.
    pub fn start(scenario: Scenario) -> Result<Arc<Self>> {
        Self::start_with_case(scenario, None)
    }

    /// Starts the live system for `scenario` on `case`'s patient with its
    /// thrombus segments ([`LiveSystem::set_case`]), or on the scenario's
    /// own leg for `None`.
    pub fn start_with_case(scenario: Scenario, case: Option<&Case>) -> Result<Arc<Self>> {
        Self::start_with_device(scenario, case, None)
    }

    /// [`LiveSystem::start_with_case`] with `device` (issue 15), when given,
    /// driving the probe instead of the page: the one haptic tick reads it
    /// (calibrated into the thigh frame by its opener), the page's probe
    /// commands are refused while it is attached, and each snapshot carries
    /// its state ([`LiveSnapshot::haptic_device`]).
    pub fn start_with_device(
        scenario: Scenario,
        case: Option<&Case>,
        device: Option<LiveDevice>,
    ) -> Result<Arc<Self>> {
        let (hardware, device_info) = match device {
            Some(d) => (Some(d.device), Some(d.info)),
            None => (None, None),
        };
        let base_thigh = scenario.thigh.clone();
        let mut scenario = scenario;
        if let Some(info) = &device_info {
            scenario.set_device_peak(info.max_force)?;
        }
        if let Some(c) = case {
            scenario.set_patient(c.anatomy.patient())?;
            scenario.patient.vein = echothigh_imaging::VeinState::Healthy;
        }
        let physics = PhysicsSide::new(&scenario)?;
        let live_mesh = live_mesh(&physics);
        let img = scenario.live_imaging_config();
        let shared = Arc::new(Shared {
            snapshot: Mutex::new(LiveSnapshot {
                positions: live_mesh.rest.clone(),
                compression: vec![0.0; live_mesh.rest.len()],
                ..Default::default()
            }),
            mesh: Mutex::new(live_mesh),
            image_input: Mutex::new(ImageInput {
                deformation: SectionDeformation::rest(0.04),
                pressure: 0.0,
                time: 0.0,
                lateral_offset: 0.0,
                probe_position: [0.0; 3],
                probe_orientation: [1.0, 0.0, 0.0, 0.0],
            }),
            image: Mutex::new(ImageSlot {
                pixels: vec![0; img.columns * img.rows],
                overlay: Vec::new(),
                width: img.columns as u32,
                height: img.rows as u32,
                frame: 0,
                time: 0.0,
                field: crate::live::ImageGeometry::of(&img),
            }),
            vein: AtomicU8::new(vein_code(scenario.patient.vein)),
            haptic: Mutex::new(None),
            section: Mutex::new(None),
            watchers: AtomicUsize::new(0),
            haptic_priority: AtomicU8::new(0),
            imaging_rate: std::sync::atomic::AtomicU64::new(0),
            image_frame: std::sync::atomic::AtomicU64::new(0),
            hurry_image: std::sync::atomic::AtomicBool::new(false),
            fault: Mutex::new(None),
            device: Mutex::new(None),
        });
        let leg = physics.model().mesh().leg().cloned();
        let target = target_on_surface(&scenario, leg.as_ref(), 0.0, 0.0, LIFTED_DEPTH, 0.0)
            .map_err(anyhow::Error::msg)?;
        let doppler = Arc::new(doppler::DopplerShared::default());
        doppler.set_case(case);
        let case = case.map(|c| (c.file.name.clone(), Arc::new(c.thrombi.clone())));
        let imaging = ImagingThread::spawn(
            shared.clone(),
            &scenario,
            case.as_ref().map(|c| c.1.clone()),
            doppler.clone(),
        )?;
        let inner = Inner {
            scenario,
            session: None,
            exam: false,
            target,
            placement: (0.0, 0.0, 0.0),
            leg,
            base_thigh,
            case,
        };
        let system = Arc::new(LiveSystem {
            shared,
            settings: Mutex::new(Settings::of(&inner)),
            inner: Mutex::new(inner),
            imaging: Mutex::new(Some(imaging)),
            device_info,
            doppler,
        });
        {
            let mut inner = system
                .inner
                .lock()
                .map_err(|_| anyhow::anyhow!("live state poisoned"))?;
            let carried = Carried {
                hardware,
                ..Carried::default()
            };
            system.start_from(&mut inner, carried, true)?;
        }
        Ok(system)
    }

    /// Publishes the settings of `inner` for snapshots.
    fn publish_settings(&self, inner: &Inner) {
        if let Ok(mut s) = self.settings.lock() {
            *s = Settings::of(inner);
        }
    }

    /// Stops the running threads (if any) and starts new ones with the
    /// current settings, continuing from what `keep` keeps of their state.
    fn restart(&self, inner: &mut Inner, keep: Keep) -> Result<()> {
        let mut carried = inner.session.take().map(Session::stop).unwrap_or_default();
        match keep {
            // A real device stays attached whatever restarts.
            Keep::Nothing => {
                carried = Carried {
                    hardware: carried.hardware.take(),
                    ..Carried::default()
                }
            }
            Keep::Thigh => carried.device = None,
            Keep::ThighAndProbe => {}
        }
        self.start_from(inner, carried, keep == Keep::Nothing)
    }

    /// Starts a session from `carried` (the thigh at rest when `at_rest`).
    fn start_from(&self, inner: &mut Inner, carried: Carried, at_rest: bool) -> Result<()> {
        if let (Some(info), None) = (&self.device_info, &carried.hardware) {
            anyhow::bail!(
                "the haptic device ({}) was released when its haptic thread stopped abnormally: \
                 restart echothigh to drive it again",
                info.name
            );
        }
        if let Ok(mut f) = self.shared.fault.lock() {
            *f = None;
        }
        if at_rest {
            // The thigh restarts from rest: what the page reads until the
            // new physics publishes is the rest state, not the old press
            // (a stale 6 N was read after a reset under load).
            let rest = self.shared.mesh.lock().map(|m| m.rest.clone());
            if let (Ok(mut snap), Ok(rest)) = (self.shared.snapshot.lock(), rest) {
                snap.positions.clone_from(&rest);
                snap.compression.clear();
                snap.compression.resize(rest.len(), 0.0);
                snap.status.physics_force = [0.0; 3];
                snap.status.section = None;
            }
        }
        inner.session = Some(start_session(
            &self.shared,
            &inner.scenario,
            inner.exam,
            inner.target,
            carried,
            self.device_info.as_ref().map_or("", |i| i.name.as_str()),
        )?);
        Ok(())
    }

    /// Stops every thread (the session's, then the imaging thread) and
    /// joins them; returns the imaging thread's error, if it had one (the
    /// session's threads report theirs as they stop). Idempotent.
    pub fn shutdown(&self) -> Result<()> {
        if let Ok(mut inner) = self.inner.lock() {
            if let Some(s) = inner.session.take() {
                s.stop();
            }
        }
        let imaging = match self.imaging.lock() {
            Ok(mut i) => i.take(),
            Err(_) => None,
        };
        match imaging {
            Some(t) => t.stop().context("the imaging thread"),
            None => Ok(()),
        }
    }
}

impl LiveSystem {
    /// Loads `case` (issue 13): the physical leg becomes its patient's
    /// (the scenario's segment kept where it fits that femur, else the whole
    /// femur, [`Scenario::set_patient`]), the imaging thread draws each vein
    /// with the case's segments where the plane cuts it (the global vein
    /// state set healthy, so that only the segments are diseased), and the
    /// thigh and the probe restart from rest, the probe lifted over where
    /// it was. `None` restores the scenario's own leg without thrombus.
    /// The page must fetch the mesh again ([`LiveControl::mesh`]): its rest
    /// positions change with the patient. Errors (a leg the mesh cannot
    /// take) leave the running case in place.
    pub fn set_case(&self, case: Option<&Case>) -> Result<()> {
        let mut inner = self
            .inner
            .lock()
            .map_err(|_| anyhow::anyhow!("live state poisoned"))?;
        let mut scenario = inner.scenario.clone();
        scenario.thigh = inner.base_thigh.clone();
        if let Some(c) = case {
            scenario.set_patient(c.anatomy.patient())?;
        }
        scenario.patient.vein = echothigh_imaging::VeinState::Healthy;
        let physics = PhysicsSide::new(&scenario).context("the case's leg")?;
        let leg = physics.model().mesh().leg().cloned();
        let (theta, z, tilt) = inner.placement;
        let target = target_on_surface(&scenario, leg.as_ref(), theta, z, LIFTED_DEPTH, tilt)
            .map_err(anyhow::Error::msg)?;
        let thrombi = case.map(|c| (c.file.name.clone(), Arc::new(c.thrombi.clone())));
        // The old imaging thread stops before its leg goes.
        let old = self.imaging.lock().ok().and_then(|mut i| i.take());
        if let Some(t) = old {
            if let Err(e) = t.stop() {
                tracing::warn!("the imaging thread of the previous case: {e:#}");
            }
        }
        let hardware = inner.session.take().and_then(|s| s.stop().hardware);
        if let Ok(mut m) = self.shared.mesh.lock() {
            *m = live_mesh(&physics);
        }
        if let Ok(mut slot) = self.shared.image.lock() {
            slot.field = crate::live::ImageGeometry::of(&scenario.live_imaging_config());
        }
        self.shared.vein.store(
            vein_code(echothigh_imaging::VeinState::Healthy),
            Ordering::Relaxed,
        );
        inner.scenario = scenario;
        inner.leg = leg;
        inner.target = target;
        inner.exam = false;
        inner.case = thrombi;
        let carried = Carried {
            physics: Some(physics),
            device: None,
            hardware,
        };
        self.start_from(&mut inner, carried, true)?;
        self.doppler.set_case(case);
        let imaging = ImagingThread::spawn(
            self.shared.clone(),
            &inner.scenario,
            inner.case.as_ref().map(|c| c.1.clone()),
            self.doppler.clone(),
        )?;
        if let Ok(mut slot) = self.imaging.lock() {
            imaging.wake();
            *slot = Some(imaging);
        }
        self.publish_settings(&inner);
        Ok(())
    }

    /// The name of the loaded case, if any.
    pub fn case_name(&self) -> Option<String> {
        self.inner
            .lock()
            .ok()
            .and_then(|i| i.case.as_ref().map(|c| c.0.clone()))
    }
}

/// The live mesh (topology and rest positions) of `physics`' model.
fn live_mesh(physics: &PhysicsSide) -> LiveMesh {
    let mesh = physics.model().mesh();
    LiveMesh {
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
    }
}

impl LiveControl for LiveSystem {
    fn set_case(&self, case: Option<&Case>) -> Result<(), String> {
        LiveSystem::set_case(self, case).map_err(|e| format!("{e:#}"))
    }

    fn mesh(&self) -> LiveMesh {
        match self.shared.mesh.lock() {
            Ok(m) => m.clone(),
            Err(e) => e.into_inner().clone(),
        }
    }

    fn image_frame(&self) -> u64 {
        self.shared.image_frame.load(Ordering::Acquire)
    }

    fn hurry_image(&self) {
        self.shared.hurry_image.store(true, Ordering::Release);
        if let Ok(Some(t)) = self.imaging.lock().as_deref() {
            t.wake();
        }
    }

    fn image_geometry(&self) -> crate::live::ImageGeometry {
        match self.shared.image.lock() {
            Ok(s) => s.field,
            Err(e) => e.into_inner().field,
        }
    }

    fn snapshot(&self, out: &mut LiveSnapshot) {
        if let Ok(s) = self.shared.snapshot.lock() {
            out.clone_from(&s);
        }
        if let Ok(s) = self.settings.lock() {
            out.status.mode = Some(s.mode);
            out.status.physics_rate_setting = s.physics_rate;
            out.status.latency_setting = s.latency;
            out.status.exam_playing = s.exam;
            out.status.max_force = s.max_force;
        }
        if let Ok(f) = self.shared.fault.lock() {
            out.fault.clone_from(&f);
        }
        if let Ok(mut r) = self.shared.section.lock() {
            out.status.section = r.as_mut().and_then(|o| *o.read());
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
        out.status.haptic_priority = crate::live::HapticPriority::from_code(
            self.shared.haptic_priority.load(Ordering::Relaxed),
        );
        out.status.imaging_rate = f64::from_bits(self.shared.imaging_rate.load(Ordering::Relaxed));
        out.haptic_device = self.device_status();
        if out.status.mode == Some(CouplingMode::Direct) {
            // The physics steps in the haptic loop: its achieved rate is the
            // loop's, not the setting (issue 19: "1000 Hz" shown at 652).
            out.status.physics_rate = out.status.haptic_rate;
        }
    }

    fn image(&self, out: &mut Vec<u8>) -> ImageInfo {
        match self.shared.image.lock() {
            Ok(s) => {
                out.clone_from(&s.pixels);
                ImageInfo {
                    width: s.width,
                    height: s.height,
                    frame: s.frame,
                    time: s.time,
                }
            }
            Err(_) => ImageInfo::default(),
        }
    }

    fn vein(&self) -> VeinState {
        vein_of(self.shared.vein.load(Ordering::Relaxed))
    }

    fn doppler(&self, cmd: crate::live_doppler::DopplerCommand) -> Result<(), String> {
        cmd.validate().map_err(|e| e.to_string())?;
        let now = self
            .shared
            .image_input
            .lock()
            .map(|i| i.time)
            .map_err(|_| "the physics' image input is poisoned".to_string())?;
        self.doppler.command(cmd, now)
    }

    fn doppler_status(&self) -> Option<crate::live_doppler::DopplerStatus> {
        Some(self.doppler.status())
    }

    fn flow_image(&self, pixels: &mut Vec<u8>, overlay: &mut Vec<u8>) -> ImageInfo {
        match self.shared.image.lock() {
            Ok(s) => {
                pixels.clone_from(&s.pixels);
                overlay.clone_from(&s.overlay);
                ImageInfo {
                    width: s.width,
                    height: s.height,
                    frame: s.frame,
                    time: s.time,
                }
            }
            Err(_) => ImageInfo::default(),
        }
    }

    fn spectral_lines(&self, from: u64, out: &mut crate::live_doppler::SpectralLines) {
        match self.doppler.lines.lock() {
            Ok(l) => l.copy(from, out),
            Err(_) => {
                out.count = 0;
                out.data.clear();
            }
        }
    }

    fn limits(&self) -> CommandLimits {
        match self.settings.lock() {
            Ok(s) => s.limits,
            Err(_) => limits_of(&Scenario::default()),
        }
    }

    fn driving_device(&self) -> Option<String> {
        self.device_info.as_ref().map(|i| i.name.clone())
    }

    fn page_opened(&self) {
        self.shared.watchers.fetch_add(1, Ordering::AcqRel);
        if let Ok(Some(t)) = self.imaging.lock().as_deref() {
            t.wake();
        }
    }

    fn page_closed(&self) {
        // Saturating: an unpaired close leaves the count at 0.
        let _ = self
            .shared
            .watchers
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| n.checked_sub(1));
    }

    fn command(&self, cmd: LiveCommand) -> Result<(), String> {
        let mut inner = self
            .inner
            .lock()
            .map_err(|_| "live state poisoned".to_string())?;
        cmd.validate(&limits_of(&inner.scenario))
            .map_err(|e| e.to_string())?;
        if let Some(info) = &self.device_info {
            if matches!(
                cmd,
                LiveCommand::Probe { .. } | LiveCommand::Lift | LiveCommand::PlayExam
            ) {
                return Err(device_drives_message(&info.name));
            }
        }
        let applied = self.apply(&mut inner, cmd);
        self.publish_settings(&inner);
        applied
    }
}

impl LiveSystem {
    /// Applies a validated command to `inner` (restarting the threads for a
    /// change of settings).
    fn apply(&self, inner: &mut Inner, cmd: LiveCommand) -> Result<(), String> {
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
                // A far move goes over the skin, not through the leg
                // (`route`): lifted, along the lifted surface, and down.
                let (t0, z0, tilt0) = inner.placement;
                let from = Placement {
                    theta: t0,
                    z: z0,
                    depth: 0.0,
                    tilt: tilt0,
                };
                let to = Placement {
                    theta,
                    z,
                    depth,
                    tilt,
                };
                let (scenario, leg) = (&inner.scenario, inner.leg.as_ref());
                let way = route::route(from, to, LIFTED_DEPTH, |p| {
                    target_on_surface(scenario, leg, p.theta, p.z, p.depth, p.tilt)
                })?;
                inner.target = way.destination();
                inner.placement = (theta, z, tilt);
                if inner.exam {
                    return Err("the scripted exam is playing: stop it to drive the probe".into());
                }
                if let Some(s) = inner.session.as_mut() {
                    s.target.write(way);
                }
                Ok(())
            }
            LiveCommand::Lift => {
                let t = lifted(inner.target, 0.03);
                inner.target = t;
                if let Some(s) = inner.session.as_mut() {
                    s.target.write(HandRoute::to(t));
                }
                Ok(())
            }
            LiveCommand::PlayExam => {
                inner.exam = true;
                restart(self, inner, Keep::Thigh)
            }
            LiveCommand::StopExam => {
                inner.exam = false;
                restart(self, inner, Keep::ThighAndProbe)
            }
            LiveCommand::SetVein { vein } => {
                inner.scenario.patient.vein = vein;
                self.shared.vein.store(vein_code(vein), Ordering::Relaxed);
                Ok(())
            }
            LiveCommand::SetMode { mode } => {
                inner.scenario.coupling.mode = mode;
                restart(self, inner, Keep::ThighAndProbe)
            }
            LiveCommand::SetPhysicsRate { hz } => {
                inner.scenario.coupling.physics_rate = hz;
                restart(self, inner, Keep::ThighAndProbe)
            }
            LiveCommand::SetLatency { seconds } => {
                inner.scenario.link.latency = seconds;
                restart(self, inner, Keep::ThighAndProbe)
            }
            LiveCommand::Reset => {
                inner.exam = false;
                // Lifted above where it was: the new session starts with
                // the device at its target, out of contact.
                let (theta, z, tilt) = inner.placement;
                inner.target = target_on_surface(
                    &inner.scenario,
                    inner.leg.as_ref(),
                    theta,
                    z,
                    LIFTED_DEPTH,
                    tilt,
                )?;
                restart(self, inner, Keep::Nothing)
            }
        }
    }
}

impl Drop for LiveSystem {
    fn drop(&mut self) {
        if let Err(e) = self.shutdown() {
            tracing::error!("stopping the live system: {e:#}");
        }
    }
}
