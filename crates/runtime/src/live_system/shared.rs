//! The state the live system's threads share, and the small types they
//! hand each other.

use crate::live::{LiveMesh, LiveSnapshot, SectionReading};
use echothigh_imaging::{SectionDeformation, VeinState};
use std::sync::atomic::{AtomicU64, AtomicU8, AtomicUsize};
use std::sync::Mutex;

/// Where the hand wants the probe.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct HandTarget {
    /// Setpoint of the probe face centre (m).
    pub position: [f64; 3],
    /// Probe orientation (w, x, y, z).
    pub orientation: [f64; 4],
}

/// What the haptic loop reports every tick.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct HapticStatus {
    /// Device position (m).
    pub device: [f64; 3],
    /// Proxy position (m).
    pub proxy: [f64; 3],
    /// Rendered force (N, tissue units).
    pub force: [f64; 3],
    /// Age of the buffer model (s).
    pub model_age: f64,
    /// Ticks since the session started.
    pub ticks: u64,
    /// Ticks that came more than 1.5 periods after the previous one.
    pub late: u64,
    /// Session clock at the last tick (s).
    pub elapsed: f64,
}

/// The echographic image's input, published by the physics.
pub(super) struct ImageInput {
    /// Skin displacement along the section (m).
    pub deformation: SectionDeformation,
    /// Mean pressure under the probe face (Pa).
    pub pressure: f64,
    /// Session time (s).
    pub time: f64,
    /// Where the probe is relative to the vessels (m, along the skin), on
    /// the elliptic cylinder (on a patient's leg the imaging thread works
    /// it out from the probe's pose).
    pub lateral_offset: f64,
    /// The probe face's centre the physics stepped with (m, model frame).
    pub probe_position: [f64; 3],
    /// The probe's orientation (w, x, y, z; model ← tool).
    pub probe_orientation: [f64; 4],
}

/// The latest echographic frame.
pub(super) struct ImageSlot {
    /// 8-bit gray, row-major.
    pub pixels: Vec<u8>,
    /// The colour overlay of the same frame, one code a pixel
    /// (`echothigh_doppler::code_rgb`), empty when none (issue 17).
    pub overlay: Vec<u8>,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Frames rendered so far.
    pub frame: u64,
    /// Simulated time of the physics state the frame shows (s).
    pub time: f64,
    /// The field of view the frames span (m), set with the leg.
    pub field: crate::live::ImageGeometry,
}

/// What the threads share (the real-time side only `try_lock`s).
pub(super) struct Shared {
    /// The mesh's topology and rest positions (replaced when a case
    /// changes the patient's leg, [`super::LiveSystem::set_case`]).
    pub mesh: Mutex<LiveMesh>,
    /// Latest physics state.
    pub snapshot: Mutex<LiveSnapshot>,
    /// Latest input of the imaging thread.
    pub image_input: Mutex<ImageInput>,
    /// Latest frame.
    pub image: Mutex<ImageSlot>,
    /// Vein state code ([`vein_code`]).
    pub vein: AtomicU8,
    /// The haptic loop's status handoff of the running session.
    pub haptic: Mutex<Option<triple_buffer::Output<HapticStatus>>>,
    /// The imaging thread's section reading handoff (lock-free for the
    /// imaging thread, which owns the input side; replaced with each new
    /// imaging thread).
    pub section: Mutex<Option<triple_buffer::Output<Option<SectionReading>>>>,
    /// Pages looking at the live state (the imaging thread idles at 0).
    pub watchers: AtomicUsize,
    /// The haptic thread's scheduling ([`HapticPriority`] as `u8`).
    pub haptic_priority: AtomicU8,
    /// The imaging thread's achieved frames/s over its last second, as
    /// `f64` bits (0 while no page looks).
    pub imaging_rate: AtomicU64,
    /// [`ImageSlot::frame`] of the latest frame, stored once the slot holds
    /// it: read without the slot's lock by a front end polling for frames.
    pub image_frame: AtomicU64,
    /// A front end wants the next frame as soon as it can be rendered
    /// ([`crate::live::LiveControl::hurry_image`]); cleared by the imaging
    /// thread when it starts one.
    pub hurry_image: std::sync::atomic::AtomicBool,
    /// The last error of a thread of the live system, for the page; cleared
    /// when a new session starts.
    pub fault: Mutex<Option<String>>,
    /// The real device's handoff of the running session (`None` while the
    /// page drives the probe).
    pub device: Mutex<Option<triple_buffer::Output<crate::live_device::DeviceTick>>>,
}

impl Shared {
    /// Reports `thread`'s error: logged, and kept for the page's status.
    /// Never called on the haptic tick's path except when the loop stops.
    pub fn report_fault(&self, thread: &str, error: &anyhow::Error) {
        tracing::error!("live {thread} thread stopped: {error:#}");
        if let Ok(mut f) = self.fault.lock() {
            *f = Some(format!("the {thread} thread stopped: {error:#}"));
        }
    }

    /// Reports a fault in plain words (logged, and kept for the page).
    pub fn report(&self, message: String) {
        tracing::error!("{message}");
        if let Ok(mut f) = self.fault.lock() {
            *f = Some(message);
        }
    }
}

/// The vein state as stored in [`Shared::vein`].
pub(super) fn vein_code(v: VeinState) -> u8 {
    match v {
        VeinState::Healthy => 0,
        VeinState::Acute => 1,
        VeinState::Chronic => 2,
    }
}

/// The inverse of [`vein_code`] (unknown codes are healthy).
pub(super) fn vein_of(code: u8) -> VeinState {
    match code {
        1 => VeinState::Acute,
        2 => VeinState::Chronic,
        _ => VeinState::Healthy,
    }
}
