//! The seam between the live simulation (the runtime, in-process threads) and
//! its front ends (the web viewer). The runtime implements [`LiveControl`];
//! the viewer only reads [`LiveSnapshot`]s and sends [`LiveCommand`]s.
//!
//! Units: SI (m, N, s), thigh frame (z along the thigh, x lateral, y up).

pub use echothigh_anatomy::{LegLevel, StructureId};
use serde::{Deserialize, Serialize};

/// Coupling between physics and haptics (see `DESIGN.md` §3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CouplingMode {
    /// The paper's method: physics at its rate, buffer model, 1 kHz haptic loop.
    Buffer,
    /// No buffer model: the physics' contact force held between physics steps.
    Hold,
    /// The physics stepped at the haptic rate with the device (ground truth).
    Direct,
}

/// State of the femoral vein: the imaging crate's own type, so that the
/// front ends, the runtime and the renderer share one definition.
pub use echothigh_imaging::VeinState;

/// Static mesh topology, sent once per connection.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LiveMesh {
    /// Rest positions of the surface nodes (m).
    pub rest: Vec<[f32; 3]>,
    /// Triangles as node indices.
    pub triangles: Vec<[u32; 3]>,
}

/// A vein's lumen below this fraction of its rest area counts as coapted,
/// its walls met: issue 13's criterion ("a healthy segment coapts: lumen <
/// 10 % of rest"), which the image's segmentation also reaches (a healthy
/// vein's dark-pixel ratio 0.03 at 10 N, `tests/suite/case_compression.rs`).
pub const COAPTED_RATIO: f64 = 0.10;

/// What scheduling the haptic thread got.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum HapticPriority {
    /// Not raised (or not started yet).
    #[default]
    Normal = 0,
    /// The highest time-sharing priority (real-time was refused).
    Raised = 1,
    /// Real-time, first-in first-out.
    Realtime = 2,
}

impl HapticPriority {
    /// The priority of code `c` (`self as u8`); unknown codes are `Normal`.
    pub fn from_code(c: u8) -> HapticPriority {
        match c {
            2 => HapticPriority::Realtime,
            1 => HapticPriority::Raised,
            _ => HapticPriority::Normal,
        }
    }
}

/// Most vessels named on the image ([`SectionReading::labels`]).
pub const MAX_LABELS: usize = 8;

/// A vessel of the drawn section, where the image shows it (issue 19: the
/// vessels named on the image when the trainee asks for a hint).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct VesselLabel {
    /// The vessel (`cfv`, `cfa`, `gsv`, …); `None`: an empty slot.
    pub id: Option<StructureId>,
    /// Its lumen's centre across the image (m from the probe's centre,
    /// positive to the image's right).
    pub lateral: f64,
    /// Its lumen's centre below the probe face (m).
    pub depth: f64,
    /// Its lumen's half-width and half-height (m), as drawn.
    pub radii: [f64; 2],
}

/// The section under the probe as the imaging thread last drew it (issue
/// 13, for the live exam's event detector of issue 14): published with each
/// frame, lock-free, and carried in [`LiveStatus::section`]. The ratios are
/// the renderer's lumen laws at the frame's tissue pressure at each vessel
/// (`echothigh_imaging::Renderer::lumens`), the vein's per-segment law when a
/// case's thrombi are loaded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SectionReading {
    /// Where the drawn section cuts the leg: m below the inguinal ligament
    /// (the section the imaging thread built, within its rebuild threshold
    /// of the probe's `level_s`); 0 on the elliptic cylinder.
    pub s: f64,
    /// The deep vein the section studies (`cfv`, `fv`, `pv`); `None` on the
    /// elliptic cylinder, whose one vein has no name.
    pub vein: Option<StructureId>,
    /// The studied vein's lumen area over its rest area (0 to ~1.2).
    pub vein_lumen_ratio: f64,
    /// The companion artery's lumen area over its rest area (its pulse
    /// included).
    pub artery_lumen_ratio: f64,
    /// Whether the vein's walls met: `vein_lumen_ratio <` [`COAPTED_RATIO`].
    pub walls_met: bool,
    /// The frame the reading came with (the image's frame count).
    pub frame: u64,
    /// Simulated time of the physics state the frame shows (s).
    pub time: f64,
    /// The depth the frame was drawn to (m): its rows span it (the depth
    /// follows the level, `crate::image_depth`).
    #[serde(default)]
    pub image_depth: f64,
    /// The target band under the probe (N of tissue force, issue 19): the
    /// force at which a healthy vein here meets its walls, then the force
    /// at which the artery is clearly oval
    /// (`echothigh_imaging::Renderer::target_band`, with
    /// [`COAPTED_RATIO`]); `[0, 0]` when there is none (the elliptic
    /// cylinder's phantom-free section always has one).
    #[serde(default)]
    pub target_band: [f64; 2],
    /// The drawn vessels inside the image, named (the first
    /// [`MAX_LABELS`]; empty slots last).
    #[serde(default)]
    pub labels: [VesselLabel; MAX_LABELS],
}

impl SectionReading {
    /// A copy with every non-finite number replaced by 0.
    pub fn sanitized(&self) -> SectionReading {
        SectionReading {
            s: finite(self.s),
            vein_lumen_ratio: finite(self.vein_lumen_ratio),
            artery_lumen_ratio: finite(self.artery_lumen_ratio),
            time: finite(self.time),
            image_depth: finite(self.image_depth),
            target_band: self.target_band.map(finite),
            labels: self.labels.map(|l| VesselLabel {
                lateral: finite(l.lateral),
                depth: finite(l.depth),
                radii: l.radii.map(finite),
                ..l
            }),
            ..*self
        }
    }
}

/// The scalar part of the live state: what the runtime reports besides the
/// surface geometry. The viewer forwards it to the page as is (after
/// [`LiveStatus::sanitized`]), flattened into its state message.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct LiveStatus {
    /// Simulated time (s).
    pub time: f64,
    /// Probe face centre (m).
    pub probe_position: [f64; 3],
    /// Probe orientation, unit quaternion (w, x, y, z).
    pub probe_orientation: [f64; 4],
    /// Device end-effector position (m).
    pub device: [f64; 3],
    /// Proxy (god-object) position (m).
    pub proxy: [f64; 3],
    /// Force rendered to the user, in tissue units (N).
    pub rendered_force: [f64; 3],
    /// The physics' own contact force on the probe (N).
    pub physics_force: [f64; 3],
    /// Device force limit expressed in tissue units (N), the gauge's full scale.
    pub max_force: f64,
    /// Achieved physics rate (Hz).
    pub physics_rate: f64,
    /// Achieved haptic rate (Hz).
    pub haptic_rate: f64,
    /// Haptic ticks that missed their deadline since start.
    pub missed_deadlines: u64,
    /// Achieved frames per second of the imaging thread over its last
    /// second (0 while no page looks); its schedule is
    /// [`IMAGING_RATE_SETTING`].
    #[serde(default)]
    pub imaging_rate: f64,
    /// The haptic thread's scheduling (issue 19: real-time priority where
    /// permitted).
    #[serde(default)]
    pub haptic_priority: HapticPriority,
    /// Age of the buffer model (s).
    pub model_age: f64,
    /// Coupling mode.
    pub mode: Option<CouplingMode>,
    /// Configured physics rate (Hz).
    pub physics_rate_setting: f64,
    /// Added one-way link latency (s).
    pub latency_setting: f64,
    /// Whether the scripted exam is playing.
    pub exam_playing: bool,
    /// Where the probe is along the leg: m below the inguinal ligament
    /// (`s`), 0 on the elliptic cylinder (which has no groin).
    pub level_s: f64,
    /// The venous segment the probe examines at `level_s` (`None` on the
    /// cylinder).
    pub level: Option<LegLevel>,
    /// The section under the probe with the last frame (`None` before the
    /// imaging thread's first frame, and while no page looks).
    pub section: Option<SectionReading>,
}

impl LiveStatus {
    /// A copy with every non-finite number replaced by 0, so that a front end
    /// never receives NaN or infinity (JSON has neither).
    pub fn sanitized(&self) -> LiveStatus {
        // Destructured without `..` so that a new field must be considered here.
        let LiveStatus {
            time,
            probe_position,
            probe_orientation,
            device,
            proxy,
            rendered_force,
            physics_force,
            max_force,
            physics_rate,
            haptic_rate,
            missed_deadlines,
            imaging_rate,
            model_age,
            mode,
            physics_rate_setting,
            latency_setting,
            exam_playing,
            level_s,
            level,
            section,
            haptic_priority,
        } = *self;
        LiveStatus {
            time: finite(time),
            probe_position: probe_position.map(finite),
            probe_orientation: probe_orientation.map(finite),
            device: device.map(finite),
            proxy: proxy.map(finite),
            rendered_force: rendered_force.map(finite),
            physics_force: physics_force.map(finite),
            max_force: finite(max_force),
            physics_rate: finite(physics_rate),
            haptic_rate: finite(haptic_rate),
            missed_deadlines,
            imaging_rate: finite(imaging_rate),
            model_age: finite(model_age),
            mode,
            physics_rate_setting: finite(physics_rate_setting),
            latency_setting: finite(latency_setting),
            exam_playing,
            level_s: finite(level_s),
            level,
            section: section.map(|r| r.sanitized()),
            haptic_priority,
        }
    }
}

/// The live imaging thread's schedule (frames/s) while a page looks. A
/// scanner's B-mode runs at 25–60 (the pulse-echo time alone, 2 · 80 mm /
/// 1 540 m/s = 104 µs a line over 128 lines, would allow 75), but the page's
/// byte budget (400 KB/s) carries ~9 live frames/s of speckle (~39 KB a
/// JPEG at quality 80): a faster schedule would render frames no page
/// receives (issue 19).
pub const IMAGING_RATE_SETTING: f64 = 20.0;

/// `x` if finite, else 0.
fn finite(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// Latest state of the live system. Filled in place to avoid allocation: the
/// runtime reuses the two vectors' capacity and overwrites `status`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct LiveSnapshot {
    /// Current node positions (m), same order as [`LiveMesh::rest`].
    pub positions: Vec<[f32; 3]>,
    /// Compression of each node's normal spring, as a fraction of its asymptote `b/a` (0..1).
    pub compression: Vec<f32>,
    /// The scalar state (time, probe, forces, rates, settings).
    #[serde(flatten)]
    pub status: LiveStatus,
    /// The last error of a thread of the live system (a stopped physics,
    /// link, haptic or imaging thread), in plain words; `None` when all run.
    pub fault: Option<String>,
    /// The real haptic device driving the probe (issue 15); `None` while
    /// the page drives it.
    #[serde(default)]
    pub haptic_device: Option<crate::live_device::LiveDeviceStatus>,
}

/// A command from a front end. Every numeric field is checked by
/// [`LiveCommand::validate`], the one validation that the page protocol, the
/// runtime and the viewer's test double all call.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LiveCommand {
    /// Place the hand's setpoint on the thigh surface at angle `theta` (rad,
    /// around the thigh axis, 0 = top) and axial position `z` (m), pressed
    /// `depth` (m, ≥ 0) below the rest surface along its inward normal, with
    /// the probe tilted by `tilt` (rad) about the thigh axis.
    Probe {
        /// Angle around the thigh axis (rad), 0 = anterior (top).
        theta: f64,
        /// Axial position (m).
        z: f64,
        /// Press depth below the rest surface (m, [`DEPTH_RANGE`]).
        depth: f64,
        /// Tilt about the thigh axis (rad).
        tilt: f64,
    },
    /// Lift the probe off the thigh.
    Lift,
    /// Play the scenario's scripted exam with the simulated hand.
    PlayExam,
    /// Stop the scripted exam (the mouse drives again).
    StopExam,
    /// Change the vein state.
    SetVein {
        /// New state.
        vein: VeinState,
    },
    /// Change the coupling mode.
    SetMode {
        /// New mode.
        mode: CouplingMode,
    },
    /// Change the physics rate (Hz, 10..=1000).
    SetPhysicsRate {
        /// Rate (Hz).
        hz: f64,
    },
    /// Change the added one-way link latency (s, 0..=0.2).
    SetLatency {
        /// Latency (s).
        seconds: f64,
    },
    /// Reset the tissue, the probe and the haptic side to rest.
    Reset,
}

/// Angle range of [`LiveCommand::Probe`]'s `theta` (rad): the range of
/// `atan2`, which is how the page computes it; one turn, nothing aliased.
pub const THETA_RANGE: (f64, f64) = (-std::f64::consts::PI, std::f64::consts::PI);

/// Press depth range of [`LiveCommand::Probe`] (m): from the rest skin down
/// to the femur, ~40 mm under the anterior skin (`DESIGN.md` §5); deeper
/// would ask the hand to push the probe into the bone. Lifting is
/// [`LiveCommand::Lift`], not a negative depth.
pub const DEPTH_RANGE: (f64, f64) = (0.0, 0.04);

/// Largest |tilt| of [`LiveCommand::Probe`] (rad, ≈ 34°): a flat probe face
/// tilted further on the elliptic thigh rides on its edge, which the contact
/// model (a flat face on the skin) does not describe.
pub const MAX_TILT: f64 = 0.6;

/// Lowest physics rate of [`LiveCommand::SetPhysicsRate`] (Hz): below it the
/// buffer model is older than the 100 ms the paper's Fig. 4 explores.
pub const MIN_PHYSICS_RATE: f64 = 10.0;

/// Added one-way latency range of [`LiveCommand::SetLatency`] (s): up to
/// 200 ms, twice the paper's worst link (§4).
pub const LATENCY_RANGE: (f64, f64) = (0.0, 0.2);

/// The scenario-dependent ranges of the commands.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CommandLimits {
    /// Half the thigh's length (m): the probe's |z| must stay on the thigh.
    pub half_length: f64,
    /// Highest physics rate (Hz): the haptic rate (the physics never steps
    /// faster than the device loop that samples it).
    pub max_physics_rate: f64,
}

/// A command refused by [`LiveCommand::validate`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    /// A number that is not finite or outside its range.
    #[error("`{field}` = {value} {unit} is out of range [{min}, {max}] {unit}")]
    OutOfRange {
        /// `type.field`, e.g. `probe.depth`.
        field: &'static str,
        /// The value received.
        value: f64,
        /// Its unit.
        unit: &'static str,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
}

/// Checks that `value` is finite and in `[min, max]`.
fn check(
    field: &'static str,
    value: f64,
    unit: &'static str,
    (min, max): (f64, f64),
) -> Result<(), CommandError> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(CommandError::OutOfRange {
            field,
            value,
            unit,
            min,
            max,
        })
    }
}

impl LiveCommand {
    /// The one range check of a front end's command against `limits` and
    /// the constants above; the error names the field, its unit and range.
    pub fn validate(&self, limits: &CommandLimits) -> Result<(), CommandError> {
        match *self {
            LiveCommand::Probe {
                theta,
                z,
                depth,
                tilt,
            } => {
                check("probe.theta", theta, "rad", THETA_RANGE)?;
                let h = limits.half_length;
                check("probe.z", z, "m", (-h, h))?;
                check("probe.depth", depth, "m", DEPTH_RANGE)?;
                check("probe.tilt", tilt, "rad", (-MAX_TILT, MAX_TILT))
            }
            LiveCommand::SetPhysicsRate { hz } => check(
                "set_physics_rate.hz",
                hz,
                "Hz",
                (MIN_PHYSICS_RATE, limits.max_physics_rate),
            ),
            LiveCommand::SetLatency { seconds } => {
                check("set_latency.seconds", seconds, "s", LATENCY_RANGE)
            }
            LiveCommand::Lift
            | LiveCommand::PlayExam
            | LiveCommand::StopExam
            | LiveCommand::SetVein { .. }
            | LiveCommand::SetMode { .. }
            | LiveCommand::Reset => Ok(()),
        }
    }
}

/// What [`LiveControl::image`] copied.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImageInfo {
    /// Columns (lateral pixels).
    pub width: u32,
    /// Rows (axial pixels).
    pub height: u32,
    /// Frames rendered so far (0: none yet).
    pub frame: u64,
    /// Simulated time of the physics state the frame shows (s, the clock of
    /// [`LiveStatus::time`]).
    pub time: f64,
}

/// The echographic image's field of view (m): what its columns and rows
/// span, for the page's depth scale. It changes with the patient (the depth
/// a sonographer sets for that build, `crate::image_depth`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImageGeometry {
    /// Lateral extent, centred on the probe (m).
    pub width: f64,
    /// Depth below the probe face (m).
    pub depth: f64,
}

impl Default for ImageGeometry {
    /// `ImagingConfig::default()`'s 40 mm × 60 mm.
    fn default() -> Self {
        ImageGeometry {
            width: 0.040,
            depth: 0.060,
        }
    }
}

impl ImageGeometry {
    /// The field of view of `cfg`.
    pub fn of(cfg: &echothigh_imaging::ImagingConfig) -> Self {
        ImageGeometry {
            width: cfg.width,
            depth: cfg.depth,
        }
    }
}

/// What the runtime offers a live front end.
pub trait LiveControl: Send + Sync {
    /// The mesh topology (static).
    fn mesh(&self) -> LiveMesh;
    /// The image's field of view (m) for the current leg.
    fn image_geometry(&self) -> ImageGeometry {
        ImageGeometry::default()
    }
    /// Copies the latest state into `out`.
    fn snapshot(&self, out: &mut LiveSnapshot);
    /// Copies the latest echographic frame (8-bit grayscale, row-major,
    /// `width × height`, axial rows) into `out`; returns its size, a frame
    /// counter that increases with every new frame, and the time of the
    /// physics state it shows.
    fn image(&self, out: &mut Vec<u8>) -> ImageInfo;
    /// The counter of the latest frame ([`ImageInfo::frame`]) without its
    /// pixels: a front end polls it to send a frame as soon as it is
    /// rendered. This default reads the whole frame; a runtime that can tell
    /// it cheaply overrides it.
    fn image_frame(&self) -> u64 {
        self.image(&mut Vec::new()).frame
    }
    /// Asks for the next frame as soon as it can be rendered rather than
    /// at its schedule (a front end answering the trainee's command; the
    /// runtime bounds how often). A runtime without a schedule ignores it.
    fn hurry_image(&self) {}
    /// Current vein state.
    fn vein(&self) -> VeinState;
    /// The ranges its commands must respect ([`LiveCommand::validate`]).
    fn limits(&self) -> CommandLimits;
    /// Applies a command; an invalid one is refused with a message. May
    /// block for a restart of the threads (tens of ms): an async caller runs
    /// it off its executor.
    fn command(&self, cmd: LiveCommand) -> Result<(), String>;
    /// Loads `case` (issue 13: its patient's leg, its thrombus segments), or
    /// the scenario's own thigh for `None`, and restarts the simulation on
    /// it with the probe lifted. May block for the rebuild (an async caller
    /// runs it off its executor). A runtime without cases refuses.
    fn set_case(&self, case: Option<&echothigh_cases::Case>) -> Result<(), String> {
        let _ = case;
        Err("this live runtime cannot load cases".into())
    }
    /// The name of the real haptic device driving the probe (issue 15),
    /// if one does: the page's probe commands (`probe`, `lift`,
    /// `play_exam`) are then refused
    /// ([`crate::live_system::device_drives_message`]).
    fn driving_device(&self) -> Option<String> {
        None
    }
    /// Applies a Doppler command (issue 17, [`crate::live_doppler`]); a
    /// runtime without a flow model refuses.
    fn doppler(&self, cmd: crate::live_doppler::DopplerCommand) -> Result<(), String> {
        let _ = cmd;
        Err("this live runtime has no Doppler".into())
    }
    /// The Doppler settings to show (`None`: no flow model).
    fn doppler_status(&self) -> Option<crate::live_doppler::DopplerStatus> {
        None
    }
    /// As [`Self::image`], and the colour overlay of that same frame into
    /// `overlay` (one code a pixel, `echothigh_doppler::code_rgb`; left
    /// empty when the frame has none: B-mode or spectral mode).
    fn flow_image(&self, pixels: &mut Vec<u8>, overlay: &mut Vec<u8>) -> ImageInfo {
        overlay.clear();
        self.image(pixels)
    }
    /// Copies the spectral lines numbered `from` on (at most
    /// [`crate::live_doppler::SPECTRAL_RING`], the newest) into `out`;
    /// `out.count` is 0 when there are none.
    fn spectral_lines(&self, from: u64, out: &mut crate::live_doppler::SpectralLines) {
        let _ = from;
        out.count = 0;
        out.data.clear();
    }
    /// A page started looking at the live state (the image is rendered only
    /// while at least one looks). Each call is paired with [`Self::page_closed`].
    fn page_opened(&self) {}
    /// A page stopped looking (see [`Self::page_opened`]).
    fn page_closed(&self) {}
}
