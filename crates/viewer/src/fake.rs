//! A test double of the live runtime: an elliptic-cylinder surface indented
//! analytically under the probe, with a stiffening force
//! `F = k₀ d / (1 − d/d_max)` (the shape of the paper's normal spring
//! `x/(ax + b)`), so the server's tests see forces that rise with the press.

use echothigh_cases::Case;
use echothigh_runtime::live::{
    CommandLimits, CouplingMode, ImageInfo, LiveCommand, LiveControl, LiveMesh, LiveSnapshot,
    LiveStatus, VeinState,
};
use echothigh_runtime::live::{SectionReading, COAPTED_RATIO};
use echothigh_runtime::live_device::LiveDeviceStatus;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

const N_THETA: usize = 24;
const N_Z: usize = 10;
const SEMI_X: f64 = 0.085;
const SEMI_Y: f64 = 0.07;
const LENGTH: f64 = 0.3;
const K0: f64 = 500.0;
const D_MAX: f64 = 0.04;
const IMAGE: (u32, u32) = (32, 24);

/// The double's mutable state.
#[derive(Debug, Default)]
struct Inner {
    probe: Option<(f64, f64, f64, f64)>,
    vein: Option<VeinState>,
    mode: Option<CouplingMode>,
    rate: f64,
    latency: f64,
    playing: bool,
    frame: u64,
    commands: Vec<LiveCommand>,
    /// The loaded case ([`LiveControl::set_case`]).
    case: Option<Case>,
    /// A real device driving the probe (issue 15), as the live system reports it.
    device: Option<LiveDeviceStatus>,
}

/// A [`LiveControl`] for tests.
#[derive(Debug, Default)]
pub struct FakeLive {
    inner: Mutex<Inner>,
    watchers: AtomicUsize,
    /// When set, the next mode change waits (without holding `inner`, as the
    /// live system's snapshot never waits for a restart) until released.
    gate: Mutex<Option<mpsc::Receiver<()>>>,
    gate_timed_out: AtomicBool,
    /// The double's flow (issue 17).
    pub doppler: crate::fake_doppler::FakeDoppler,
    /// When set, frames of this size `(width, height)` of fresh noise
    /// ([`FakeLive::speckled_images`]).
    speckle: Mutex<Option<(u32, u32)>>,
    /// When set, every frame shows the physics state of this simulated time
    /// (s) ([`FakeLive::image_time`]).
    image_time: Mutex<Option<f64>>,
}

/// How long a held mode change waits for its release before giving up.
pub const GATE_WAIT: Duration = Duration::from_secs(10);

impl FakeLive {
    /// A thigh at rest, healthy vein, buffer mode.
    pub fn new() -> Self {
        let f = Self::default();
        {
            let mut i = f.inner.lock().unwrap();
            i.vein = Some(VeinState::Healthy);
            i.mode = Some(CouplingMode::Buffer);
            i.rate = 100.0;
        }
        f
    }

    /// Makes every later frame `width × height` of fresh uniform noise, which
    /// JPEG cannot compress much (like speckle): the images then spend the
    /// connection's byte budget, as the live system's do.
    pub fn speckled_images(&self, width: u32, height: u32) {
        *self.speckle.lock().unwrap() = Some((width, height));
    }

    /// Makes every later frame show the physics state of time `time` (s):
    /// older than the states sent once they pass it, or newer than any
    /// (`f64::MAX`). Without it a frame's time counts the frames read, a
    /// clock unrelated to the states' (which count each connection's
    /// snapshots).
    pub fn image_time(&self, time: f64) {
        *self.image_time.lock().unwrap() = Some(time);
    }

    /// Attaches a device that drives the probe (the page's probe commands
    /// are then refused by the server), reported with every snapshot.
    pub fn attach_device(&self, status: LiveDeviceStatus) {
        self.inner.lock().unwrap().device = Some(status);
    }

    /// The loaded case's name.
    pub fn case_name(&self) -> Option<String> {
        self.inner
            .lock()
            .unwrap()
            .case
            .as_ref()
            .map(|c| c.file.name.clone())
    }

    /// Commands received so far.
    pub fn commands(&self) -> Vec<LiveCommand> {
        self.inner.lock().unwrap().commands.clone()
    }

    /// Pages looking now ([`LiveControl::page_opened`] minus closed).
    pub fn watchers(&self) -> usize {
        self.watchers.load(Ordering::SeqCst)
    }

    /// Makes the next `set_mode` block, like a restart of the threads, until
    /// the returned sender sends (or [`GATE_WAIT`] passes, which
    /// [`Self::gate_timed_out`] then reports).
    pub fn hold_next_mode_change(&self) -> mpsc::Sender<()> {
        let (tx, rx) = mpsc::channel();
        *self.gate.lock().unwrap() = Some(rx);
        tx
    }

    /// Whether the held mode change has arrived (taken the gate).
    pub fn gate_taken(&self) -> bool {
        self.gate.lock().unwrap().is_none()
    }

    /// Whether a held mode change gave up waiting for its release.
    pub fn gate_timed_out(&self) -> bool {
        self.gate_timed_out.load(Ordering::SeqCst)
    }

    fn rest(i_t: usize, i_z: usize) -> [f64; 3] {
        let t = i_t as f64 / N_THETA as f64 * std::f64::consts::TAU;
        let z = i_z as f64 / (N_Z - 1) as f64 * LENGTH - LENGTH / 2.0;
        [SEMI_X * t.sin(), SEMI_Y * t.cos(), z]
    }
}

impl LiveControl for FakeLive {
    fn mesh(&self) -> LiveMesh {
        let mut rest = Vec::new();
        for i_z in 0..N_Z {
            for i_t in 0..N_THETA {
                rest.push(Self::rest(i_t, i_z).map(|c| c as f32));
            }
        }
        let mut triangles = Vec::new();
        for i_z in 0..N_Z - 1 {
            for i_t in 0..N_THETA {
                let a = (i_z * N_THETA + i_t) as u32;
                let b = (i_z * N_THETA + (i_t + 1) % N_THETA) as u32;
                let (c, d) = (a + N_THETA as u32, b + N_THETA as u32);
                triangles.push([a, b, c]);
                triangles.push([b, d, c]);
            }
        }
        LiveMesh { rest, triangles }
    }

    fn snapshot(&self, out: &mut LiveSnapshot) {
        let i = self.inner.lock().unwrap();
        let (theta, z0, depth, _tilt) = i.probe.unwrap_or((0.0, 0.0, 0.0, 0.0));
        let pressing = i.probe.is_some();
        out.positions.clear();
        out.compression.clear();
        for i_z in 0..N_Z {
            for i_t in 0..N_THETA {
                let p = Self::rest(i_t, i_z);
                let t = i_t as f64 / N_THETA as f64 * std::f64::consts::TAU;
                let near = (angle_diff(t, theta).abs() < 0.3) && (p[2] - z0).abs() < 0.03;
                let d = if pressing && near { depth } else { 0.0 };
                let s = 1.0 - d / SEMI_Y;
                out.positions
                    .push([(p[0] * s) as f32, (p[1] * s) as f32, p[2] as f32]);
                out.compression.push((d / D_MAX) as f32);
            }
        }
        let f = if pressing {
            K0 * depth / (1.0 - depth / D_MAX)
        } else {
            0.0
        };
        let n = [theta.sin(), theta.cos(), 0.0];
        let probe = [SEMI_X * theta.sin(), SEMI_Y * theta.cos(), z0];
        out.status = LiveStatus {
            time: out.status.time + 0.01,
            probe_position: probe,
            probe_orientation: [1.0, 0.0, 0.0, 0.0],
            device: probe,
            proxy: probe,
            rendered_force: n.map(|c| c * f),
            physics_force: n.map(|c| c * f),
            max_force: 30.0,
            physics_rate: i.rate,
            haptic_rate: 1000.0,
            missed_deadlines: 0,
            imaging_rate: echothigh_runtime::live::IMAGING_RATE_SETTING,
            haptic_priority: echothigh_runtime::live::HapticPriority::Raised,
            model_age: 0.0,
            mode: i.mode,
            physics_rate_setting: i.rate,
            latency_setting: i.latency,
            exam_playing: i.playing,
            // The fake's thigh is the cylinder: no level along a leg.
            level_s: 0.0,
            level: None,
            section: i.case.as_ref().map(|c| reading(c, z0, f, out.status.time)),
        };
        out.haptic_device.clone_from(&i.device);
    }

    fn driving_device(&self) -> Option<String> {
        self.inner
            .lock()
            .unwrap()
            .device
            .as_ref()
            .map(|d| d.name.clone())
    }

    /// Frame `f` is a uniform image at [`fake_image_level`]`(f)`: flat 8 × 8
    /// blocks go through the JPEG wire within one grey level, so a test
    /// tells the frames apart.
    fn image(&self, out: &mut Vec<u8>) -> ImageInfo {
        let mut i = self.inner.lock().unwrap();
        i.frame += 1;
        let f = i.frame as u32;
        out.clear();
        let size = match *self.speckle.lock().unwrap() {
            Some((w, h)) => {
                // SplitMix64 per frame: a different noise in every frame.
                let mut z = i.frame;
                out.extend((0..w * h).map(|_| {
                    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
                    let mut x = z;
                    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                    (x >> 56) as u8
                }));
                (w, h)
            }
            None => {
                out.resize((IMAGE.0 * IMAGE.1) as usize, fake_image_level(f));
                IMAGE
            }
        };
        ImageInfo {
            width: size.0,
            height: size.1,
            frame: i.frame,
            time: self
                .image_time
                .lock()
                .unwrap()
                .unwrap_or(0.01 * i.frame as f64),
        }
    }

    fn doppler(&self, cmd: echothigh_runtime::live_doppler::DopplerCommand) -> Result<(), String> {
        self.doppler.command(cmd)
    }

    fn doppler_status(&self) -> Option<echothigh_runtime::live_doppler::DopplerStatus> {
        Some(self.doppler.status())
    }

    fn flow_image(&self, pixels: &mut Vec<u8>, overlay: &mut Vec<u8>) -> ImageInfo {
        let info = self.image(pixels);
        self.doppler
            .frame(info.width as usize, info.height as usize, overlay);
        info
    }

    fn spectral_lines(&self, from: u64, out: &mut echothigh_runtime::live_doppler::SpectralLines) {
        self.doppler.lines(from, out);
    }

    fn page_opened(&self) {
        self.watchers.fetch_add(1, Ordering::SeqCst);
    }

    fn page_closed(&self) {
        self.watchers.fetch_sub(1, Ordering::SeqCst);
    }

    fn set_case(&self, case: Option<&Case>) -> Result<(), String> {
        let mut i = self.inner.lock().unwrap();
        i.case = case.cloned();
        i.probe = None;
        Ok(())
    }

    fn vein(&self) -> VeinState {
        self.inner
            .lock()
            .unwrap()
            .vein
            .unwrap_or(VeinState::Healthy)
    }

    fn limits(&self) -> CommandLimits {
        CommandLimits {
            half_length: LENGTH / 2.0,
            max_physics_rate: 1000.0,
        }
    }

    fn command(&self, cmd: LiveCommand) -> Result<(), String> {
        cmd.validate(&self.limits()).map_err(|e| e.to_string())?;
        if matches!(cmd, LiveCommand::SetMode { .. }) {
            let gate = self.gate.lock().unwrap().take();
            if let Some(rx) = gate {
                if rx.recv_timeout(GATE_WAIT).is_err() {
                    self.gate_timed_out.store(true, Ordering::SeqCst);
                }
            }
        }
        let mut i = self.inner.lock().unwrap();
        i.commands.push(cmd.clone());
        match cmd {
            LiveCommand::Probe {
                theta,
                z,
                depth,
                tilt,
            } => {
                i.probe = Some((theta, z, depth.min(0.9 * D_MAX), tilt));
            }
            LiveCommand::Lift | LiveCommand::Reset => i.probe = None,
            LiveCommand::PlayExam => i.playing = true,
            LiveCommand::StopExam => i.playing = false,
            LiveCommand::SetVein { vein } => i.vein = Some(vein),
            LiveCommand::SetMode { mode } => i.mode = Some(mode),
            LiveCommand::SetPhysicsRate { hz } => i.rate = hz,
            LiveCommand::SetLatency { seconds } => i.latency = seconds,
        }
        Ok(())
    }
}

/// Force (N) at which the double's healthy vein coapts: lumen ratio
/// `1 − f / FAKE_CLOSING`, below [`COAPTED_RATIO`] from 0.9 of it.
pub const FAKE_CLOSING: f64 = 8.0;
/// Force (N) above which the double's artery deforms, by `(f − F)/40 N`.
pub const FAKE_ARTERY_ONSET: f64 = 10.0;

/// `s` (m below the inguinal ligament) of the probe at `z` (m) on the
/// double's cylinder: its length spans the loaded case's leg, groin at
/// `z = LENGTH/2`.
fn s_of(case: &Case, z: f64) -> f64 {
    ((LENGTH / 2.0 - z) / LENGTH * case.anatomy.length()).clamp(0.0, case.anatomy.length())
}

/// The probe's `z` (m) over `s` on the loaded case's leg ([`s_of`]'s inverse).
pub fn z_of(fake: &FakeLive, s: f64) -> f64 {
    let i = fake.inner.lock().unwrap();
    let len = i.case.as_ref().map_or(LENGTH, |c| c.anatomy.length());
    LENGTH / 2.0 - s / len * LENGTH
}

/// The double's reading of a loaded case's section with the probe at `z`
/// (m, [`s_of`]) pressing with `f` (N): the
/// deep vein there; healthy, it closes linearly by [`FAKE_CLOSING`]; where
/// the case's thrombus fills it (fill ≥ ½), it keeps ≥ 0.9 of its lumen.
fn reading(case: &Case, z: f64, f: f64, time: f64) -> SectionReading {
    let s = s_of(case, z);
    let vein = case.anatomy.deep_vein_at(s);
    let filled = case.thrombi.state(vein, s).fill >= 0.5;
    let ratio = if filled {
        1.0 - 0.1 * (f / 40.0).min(1.0)
    } else {
        (1.0 - f / FAKE_CLOSING).max(0.0)
    };
    SectionReading {
        s,
        vein: Some(vein),
        vein_lumen_ratio: ratio,
        artery_lumen_ratio: 1.0 - ((f - FAKE_ARTERY_ONSET).max(0.0) / 40.0).min(0.5),
        walls_met: ratio < COAPTED_RATIO,
        frame: 0,
        time,
        image_depth: 0.060,
        // Its walls meet at 0.9 of FAKE_CLOSING; its artery is at 0.8 of
        // its lumen (the double's "clearly oval") 8 N past its onset.
        target_band: [
            (1.0 - COAPTED_RATIO) * FAKE_CLOSING,
            FAKE_ARTERY_ONSET + 8.0,
        ],
        labels: Default::default(),
    }
}

/// `a − b` wrapped to (−π, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

/// The grey level of the double's image frame `frame`: 16 + 37·frame mod
/// 224, a different level from one frame to the next.
pub fn fake_image_level(frame: u32) -> u8 {
    (16 + (frame.wrapping_mul(37)) % 224) as u8
}
