//! The live flow (issue 17): the case's flow model run on the simulation's
//! clock by the imaging thread, frame by frame, with the manoeuvres the
//! page asks for; the colour (or power) overlay of each frame and the PW
//! spectral lines at the sample gate.
//!
//! - **Flow** ([`SectionFlows`]): each vessel of the drawn section with its
//!   segment flow (breathing, Valsalva, augmentation, the case's thrombi
//!   and iliac obstruction), rebuilt when the section is. The page holds
//!   the probe normal to the skin (its probe has no heel-toe), where the
//!   beam is nearly perpendicular to the vessels; a sonographer angles the
//!   probe to see flow, so the Doppler beam is rocked [`DOPPLER_TILT`]
//!   distally unless the probe itself is tilted more than
//!   [`OWN_TILT_MIN`] (the angle `bench image --doppler` uses).
//! - **Manoeuvres** ([`Maneuvers`] in [`DopplerShared::controls`]): a calf
//!   squeeze and a held Valsalva from the page, stamped with the physics'
//!   time; the release of a probe compression (the studied vein's lumen
//!   back above `closed_ratio` after being below it) adds a release
//!   augmentation. Under the probe a vein closed below `closed_ratio`
//!   carries nothing (`SegmentFlow::velocity`).
//! - **Colour** ([`ColorFlow::codes`]): one overlay code a pixel.
//! - **Spectral** ([`PwDoppler`]): lines at the PW line rate up to the
//!   frame's time, each drawn as a [`SPECTRAL_ROWS`] column
//!   ([`SpectralDisplay::column`]) into the ring the pages read.

use crate::live_doppler::{
    DopplerMode, DopplerStatus, Gate, SpectralLines, SPECTRAL_RING, SPECTRAL_ROWS,
};
use anyhow::{Context, Result};
use echothigh_anatomy::{Anatomy, ProbePose, Thrombi};
use echothigh_doppler::{
    ColorConfig, ColorFlow, ColorMode, FlowConfig, FlowScene, Maneuvers, Profile, PwConfig,
    PwDoppler, SectionFlows, SpectralDisplay,
};
use echothigh_imaging::{FrameInput, Renderer};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Mutex;

/// Heel-toe of the Doppler beam when the probe is held normal (rad): 20°,
/// as `bench image --doppler`.
pub const DOPPLER_TILT: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// A probe's own tilt beyond which the beam is taken as it is (rad, 5°).
pub const OWN_TILT_MIN: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Lines computed at most per frame: a frame 0.32 s after the last one
/// (64 lines of 5 ms); a longer gap restarts the gate at the frame's time.
const MAX_LINES_PER_FRAME: usize = 64;

/// What the page sets and the imaging thread reads.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Controls {
    /// The manoeuvres on the physics' clock.
    pub maneuvers: Maneuvers,
    /// The PW sample gate.
    pub gate: Gate,
}

/// The spectral lines kept for the pages.
#[derive(Debug)]
pub(crate) struct LineRing {
    data: Vec<u8>,
    times: Vec<f64>,
    next: u64,
    interval: f64,
}

impl LineRing {
    fn new(interval: f64) -> Self {
        LineRing {
            data: vec![0; SPECTRAL_RING * SPECTRAL_ROWS],
            times: vec![0.0; SPECTRAL_RING],
            next: 0,
            interval,
        }
    }

    /// Appends a line (`SPECTRAL_ROWS` magnitudes) of time `t` (s).
    pub fn push(&mut self, line: &[u8], t: f64) {
        let k = (self.next % SPECTRAL_RING as u64) as usize;
        self.data[k * SPECTRAL_ROWS..(k + 1) * SPECTRAL_ROWS].copy_from_slice(line);
        self.times[k] = t;
        self.next += 1;
    }

    /// Copies the lines numbered `from` on that the ring still holds.
    pub fn copy(&self, from: u64, out: &mut SpectralLines) {
        let oldest = self.next.saturating_sub(SPECTRAL_RING as u64);
        let first = from.max(oldest);
        out.first = first;
        out.count = self.next.saturating_sub(first) as usize;
        out.interval = self.interval;
        out.data.clear();
        for n in first..self.next {
            let k = (n % SPECTRAL_RING as u64) as usize;
            out.data
                .extend_from_slice(&self.data[k * SPECTRAL_ROWS..(k + 1) * SPECTRAL_ROWS]);
        }
        out.time = if out.count > 0 {
            self.times[(first % SPECTRAL_RING as u64) as usize]
        } else {
            0.0
        };
    }
}

/// The Doppler state the page's commands and the imaging thread share.
#[derive(Debug)]
pub(crate) struct DopplerShared {
    /// [`DopplerMode`] as a code ([`mode_code`]).
    pub mode: AtomicU8,
    /// The loaded case's iliac obstruction (`[doppler] proximal_obstruction`).
    pub proximal_obstruction: AtomicBool,
    /// Manoeuvres and gate.
    pub controls: Mutex<Controls>,
    /// The spectral lines.
    pub lines: Mutex<LineRing>,
    /// What the page shows.
    pub status: Mutex<DopplerStatus>,
}

impl Default for DopplerShared {
    fn default() -> Self {
        DopplerShared {
            mode: AtomicU8::new(0),
            proximal_obstruction: AtomicBool::new(false),
            controls: Mutex::new(Controls::default()),
            lines: Mutex::new(LineRing::new(PwConfig::default().line_interval)),
            status: Mutex::new(DopplerStatus::default()),
        }
    }
}

/// The code of `m` in [`DopplerShared::mode`].
pub(crate) fn mode_code(m: DopplerMode) -> u8 {
    match m {
        DopplerMode::Bmode => 0,
        DopplerMode::Color => 1,
        DopplerMode::Power => 2,
        DopplerMode::Spectral => 3,
    }
}

/// The inverse of [`mode_code`] (unknown codes are B-mode).
pub(crate) fn mode_of(code: u8) -> DopplerMode {
    match code {
        1 => DopplerMode::Color,
        2 => DopplerMode::Power,
        3 => DopplerMode::Spectral,
        _ => DopplerMode::Bmode,
    }
}

impl DopplerShared {
    /// The imaging mode.
    pub fn mode(&self) -> DopplerMode {
        mode_of(self.mode.load(Ordering::Acquire))
    }
}

/// The drawn section the flow is imaged in.
pub(crate) struct FlowContext<'a> {
    /// The leg's anatomy.
    pub anatomy: &'a Anatomy,
    /// The case's segments (empty for a healthy leg).
    pub thrombi: &'a Thrombi,
    /// The pose the section was built at.
    pub pose: ProbePose,
    /// Changes whenever the section (and its renderer) is rebuilt.
    pub key: u64,
}

/// The PW gate's processor and what it was built for.
struct Gated {
    pw: PwDoppler,
    /// (section key, vessel index or `usize::MAX` outside flow, true
    /// angle in tenths of a degree).
    key: (u64, usize, i64),
}

/// The imaging thread's flow processing (see the module docs).
pub(crate) struct FlowImaging {
    fc: FlowConfig,
    cc: ColorConfig,
    pc: PwConfig,
    display: SpectralDisplay,
    flows: Option<(u64, SectionFlows)>,
    color: Option<(u64, ColorMode, ColorFlow)>,
    scene: FlowScene,
    gated: Option<Gated>,
    column: Vec<u8>,
    reference: f64,
    closed: bool,
    last: Option<(f64, f64)>,
    distension: f64,
}

impl Default for FlowImaging {
    fn default() -> Self {
        FlowImaging {
            fc: FlowConfig::default(),
            cc: ColorConfig::default(),
            pc: PwConfig::default(),
            display: SpectralDisplay::default(),
            flows: None,
            color: None,
            scene: FlowScene::new(),
            gated: None,
            column: vec![0; SPECTRAL_ROWS],
            reference: 0.0,
            closed: false,
            last: None,
            distension: 1.0,
        }
    }
}

impl FlowImaging {
    /// The studied vein's diameter factor at the last frame
    /// (`SegmentFlow::diameter_factor`: its Valsalva distension, +100 %
    /// healthy, +30 % with thrombus or an obstruction above), for the
    /// renderer's next frame (`Renderer::set_vein_distension`).
    pub fn vein_distension(&self) -> f64 {
        self.distension
    }

    /// Processes the frame `pixels` that `renderer` drew for `input` in
    /// `ctx`: updates the manoeuvres (a compression's release, from the
    /// studied vein's `vein_lumen_ratio`), then in colour or power mode
    /// writes the overlay codes into `overlay` (else empties it), in
    /// spectral mode appends the lines up to the frame's time to
    /// `shared.lines`; publishes the status.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        shared: &DopplerShared,
        ctx: &FlowContext,
        renderer: &Renderer,
        input: &FrameInput,
        pixels: &[u8],
        vein_lumen_ratio: Option<f64>,
        overlay: &mut Vec<u8>,
    ) -> Result<()> {
        let t = input.time;
        let face = input.deformation.face_depth(0.5 * renderer.config().width);
        // The probe's motion along the beam (the flash source): the face's
        // depth change since the last frame; a clock that went back (a
        // new session) drops the old manoeuvres.
        let tissue_velocity = match self.last {
            Some((t0, f0)) if t > t0 => ((face - f0) / (t - t0)).clamp(-0.2, 0.2),
            _ => 0.0,
        };
        let restarted = matches!(self.last, Some((t0, _)) if t + 0.1 < t0);
        self.last = Some((t, face));
        let controls = {
            let mut c = shared
                .controls
                .lock()
                .map_err(|_| anyhow::anyhow!("imaging: the Doppler controls are poisoned"))?;
            if restarted {
                c.maneuvers = Maneuvers::new();
                self.gated = None;
            }
            if let Some(r) = vein_lumen_ratio {
                let closed = r < self.fc.closed_ratio;
                if self.closed && !closed {
                    c.maneuvers.release(t);
                }
                self.closed = closed;
            }
            *c
        };
        let mode = shared.mode();
        if self.flows.as_ref().map(|f| f.0) != Some(ctx.key) {
            let section = ctx.anatomy.section(&ctx.pose)?;
            let obstruction = shared.proximal_obstruction.load(Ordering::Acquire);
            let tilt = if ctx.pose.tilt.abs() > OWN_TILT_MIN {
                ctx.pose.tilt
            } else {
                DOPPLER_TILT
            };
            let flows = SectionFlows::new(
                &self.fc,
                ctx.anatomy,
                ctx.thrombi,
                obstruction,
                &section,
                &renderer.config().anatomy,
            )?
            .beam_tilted(ctx.anatomy, tilt)?;
            self.flows = Some((ctx.key, flows));
            self.gated = None;
        }
        let Some((key, flows)) = self.flows.take() else {
            return Ok(());
        };
        let r = self.with_flows(
            shared,
            key,
            &flows,
            renderer,
            input,
            pixels,
            &controls,
            tissue_velocity,
            mode,
            overlay,
        );
        self.flows = Some((key, flows));
        r
    }

    /// [`FlowImaging::frame`] once the section's flows are known.
    #[allow(clippy::too_many_arguments)]
    fn with_flows(
        &mut self,
        shared: &DopplerShared,
        key: u64,
        flows: &SectionFlows,
        renderer: &Renderer,
        input: &FrameInput,
        pixels: &[u8],
        controls: &Controls,
        tissue_velocity: f64,
        mode: DopplerMode,
        overlay: &mut Vec<u8>,
    ) -> Result<()> {
        self.distension = flows.flow(0).map_or(1.0, |f| {
            f.diameter_factor(&self.fc, &controls.maneuvers, input.time)
        });
        let steer = self.cc.steer_deg.to_radians();
        flows
            .fill(
                &self.fc,
                &controls.maneuvers,
                renderer,
                input,
                steer,
                tissue_velocity,
                &mut self.scene,
            )
            .map_err(|e| anyhow::anyhow!("imaging: the flow scene: {e}"))?;
        let (w, h) = renderer.frame_size();
        let mut status = DopplerStatus {
            mode,
            available: true,
            valsalva: controls.maneuvers.valsalva_held(),
            color_nyquist: self.cc.nyquist_velocity(),
            color_box: self.color_box(renderer),
            gate: controls.gate,
            prf: self.pc.prf,
            line_rate: 1.0 / self.pc.line_interval,
            velocity_per_hz: self.pc.sound_speed
                / (2.0 * self.pc.center_frequency * controls.gate.angle_deg.to_radians().cos()),
            gate_in_flow: false,
            gate_velocity: 0.0,
        };
        match mode {
            DopplerMode::Color | DopplerMode::Power => {
                let cm = if mode == DopplerMode::Color {
                    ColorMode::Velocity
                } else {
                    ColorMode::Power
                };
                if !matches!(&self.color, Some((k, m, _)) if *k == key && *m == cm) {
                    let cols: Vec<f64> = (0..w).map(|j| renderer.column_lateral(j)).collect();
                    let cf =
                        ColorFlow::new(&self.cc, cm, &cols, h, renderer.config().pixel_depth())?;
                    self.color = Some((key, cm, cf));
                }
                if let Some((_, _, cf)) = self.color.as_mut() {
                    overlay.resize(w * h, 0);
                    cf.codes(pixels, &self.scene, overlay)?;
                }
            }
            DopplerMode::Spectral => {
                overlay.clear();
                self.spectral(shared, key, flows, renderer, input, controls, &mut status)?;
            }
            DopplerMode::Bmode => overlay.clear(),
        }
        if let Ok(mut s) = shared.status.lock() {
            *s = status;
        }
        Ok(())
    }

    /// The colour box as fractions of the image (left, top, right, bottom).
    fn color_box(&self, renderer: &Renderer) -> [f64; 4] {
        let (w, h) = renderer.frame_size();
        let (l0, l1) = (renderer.column_lateral(0), renderer.column_lateral(w - 1));
        let depth = h as f64 * renderer.config().pixel_depth();
        let fx = |lat: f64| ((lat - l0) / (l1 - l0)).clamp(0.0, 1.0);
        let fy = |d: f64| (d / depth).clamp(0.0, 1.0);
        [
            fx(self.cc.box_left),
            fy(self.cc.box_top),
            fx(self.cc.box_right),
            fy(self.cc.box_bottom),
        ]
    }
}

impl FlowImaging {
    /// The PW lines at the gate up to the frame's time (see the module docs).
    // The frame's context, as the two functions above take it.
    #[allow(clippy::too_many_arguments)]
    fn spectral(
        &mut self,
        shared: &DopplerShared,
        section_key: u64,
        flows: &SectionFlows,
        renderer: &Renderer,
        input: &FrameInput,
        controls: &Controls,
        status: &mut DopplerStatus,
    ) -> Result<()> {
        let t = input.time;
        let (w, h) = renderer.frame_size();
        let g = controls.gate;
        let col = ((g.x * (w - 1) as f64).round() as usize).min(w - 1);
        let lateral = renderer.column_lateral(col);
        let depth = g.y * h as f64 * renderer.config().pixel_depth();
        let steer = self.cc.steer_deg.to_radians();
        let hit = self
            .scene
            .blood_at_indexed(lateral, depth)
            .map(|(i, v, _)| {
                let lumen = (v.half_width * v.half_height).sqrt();
                (i, lumen, v.profile)
            });
        let (vessel, radius, profile, cos) = match hit {
            Some((i, r, p)) => (i, r, p, flows.cos_to_probe(i, steer)),
            None => (usize::MAX, 3e-3, Profile::Parabolic, 0.0),
        };
        let angle = cos.abs().clamp(0.0, 1.0).acos().to_degrees().min(90.0);
        let key = (section_key, vessel, (angle * 10.0).round() as i64);
        // The lumen ratio under the probe this frame, held over its lines.
        let ratio = if vessel == usize::MAX {
            1.0
        } else {
            renderer
                .vessel_lumen(vessel, input)
                .map_err(|e| anyhow::anyhow!("imaging: the gate's lumen: {e}"))?
                .map_or(1.0, |l| l.area / l.rest_area.max(1e-12))
        };
        let segment = flows.flow(vessel).copied();
        let (fc, m) = (self.fc, controls.maneuvers);
        let sign = if cos < 0.0 { -1.0 } else { 1.0 };
        let v = move |tt: f64| segment.map_or(0.0, |s| sign * s.velocity(&fc, &m, tt, ratio));
        status.gate_in_flow = segment.is_some();
        status.gate_velocity = segment.map_or(0.0, |s| s.velocity(&fc, &m, t, ratio));
        let stale = match &self.gated {
            Some(gd) => {
                gd.key != key
                    || t - gd.pw.time() > MAX_LINES_PER_FRAME as f64 * self.pc.line_interval
            }
            None => true,
        };
        if stale {
            let cfg = PwConfig {
                angle_deg: angle,
                ..self.pc
            };
            let pw = PwDoppler::new(&cfg, radius.clamp(2e-4, 0.05), profile, t, v(t))
                .context("imaging: the PW gate")?;
            self.gated = Some(Gated { pw, key });
        }
        let Some(gd) = self.gated.as_mut() else {
            return Ok(());
        };
        let mut lines = shared
            .lines
            .lock()
            .map_err(|_| anyhow::anyhow!("imaging: the spectral lines are poisoned"))?;
        let dt = self.pc.line_interval;
        // Per-bin noise power: `noise_power` is the sum over the N bins.
        let floor = gd.pw.noise_power() / self.pc.fft_size as f64 * 10f64.powf(3.5);
        for _ in 0..MAX_LINES_PER_FRAME {
            if gd.pw.time() + dt > t + 1e-9 {
                break;
            }
            let sp = gd.pw.line(v);
            // Automatic gain: 255 at the strongest bin of the last second
            // (a decay of 1/200 a line at 200 lines/s), never below 35 dB
            // over the noise, which the 40 dB range then draws at 32/255.
            let peak = sp.power.iter().fold(0.0f32, |a, &b| a.max(b)) as f64;
            self.reference = (self.reference * (1.0 - dt)).max(peak).max(floor);
            self.display
                .column(sp, self.pc.prf, self.reference, &mut self.column);
            lines.push(&self.column, gd.pw.time());
        }
        Ok(())
    }
}
