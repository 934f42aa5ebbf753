//! What the physics publishes for the front end (mesh, forces, the section
//! under the probe) and the imaging thread that renders it.

use super::doppler::{DopplerShared, FlowImaging};
use super::imaging_source::{Probe, Source};
use super::shared::{vein_of, Shared};
use crate::live::{SectionReading, VesselLabel, COAPTED_RATIO, MAX_LABELS};
use crate::physics_side::{self, PhysicsSide};
use crate::scenario::Scenario;
use crate::section::{lateral_offset, section_deformation, SectionScratch};
use anyhow::{Context, Result};
use echothigh_anatomy::{Levels, StructureId, Thrombi};
use echothigh_imaging::{Anatomy, FrameInput, ImagingConfig, SectionDeformation, VeinState};
use echothigh_model::{LegSurface, ThighGeometry};
use echothigh_transport::ProbeMsg;
use nalgebra::Isometry3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Copies the physics state into the shared snapshot and image input,
/// never waiting for a lock.
pub(super) struct Publisher {
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
    /// The leg's `centre_s` (m) and levels, when the mesh follows one.
    leg: Option<(f64, Levels)>,
    steps: u64,
    first: Option<f64>,
}

impl Publisher {
    /// The publisher of `s`'s physics (its leg's levels when the mesh
    /// follows a patient's leg; the scenario is validated, so the leg
    /// builds).
    pub(super) fn new(shared: Arc<Shared>, s: &Scenario) -> Self {
        let leg = LegSurface::new(&s.thigh, "thigh").ok().flatten();
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
            leg: leg.map(|l| (s.thigh.centre_s, *l.anatomy().levels())),
            steps: 0,
            first: None,
        }
    }

    pub(super) fn publish(&mut self, physics: &PhysicsSide, probe: &ProbeMsg, now: f64) {
        self.steps += 1;
        let first = *self.first.get_or_insert(now);
        let Some(sample) = physics.last_sample() else {
            return;
        };
        let model = physics.model();
        if let Ok(mut snap) = self.shared.snapshot.try_lock() {
            let mesh = model.mesh();
            let (x, rest, normals) = (
                model.positions(),
                mesh.rest_positions(),
                mesh.rest_normals(),
            );
            snap.positions.clear();
            snap.compression.clear();
            for i in 0..x.len() {
                snap.positions
                    .push([x[i].x as f32, x[i].y as f32, x[i].z as f32]);
                // The normal column's compression (along the rest normal).
                let c = normals[i].dot(&(rest[i] - x[i])) / self.asymptote;
                snap.compression.push(c.clamp(0.0, 1.0) as f32);
            }
            snap.status.time = now;
            snap.status.probe_position = probe.position;
            snap.status.probe_orientation = probe.orientation;
            if let Some((centre_s, levels)) = &self.leg {
                let s = centre_s - probe.position[2];
                snap.status.level_s = s;
                snap.status.level = Some(levels.level_at(s));
            }
            snap.status.physics_force = sample.force.into();
            snap.status.physics_rate = if now > first {
                (self.steps - 1) as f64 / (now - first)
            } else {
                0.0
            };
        }
        let pose: Isometry3<f64> = physics_side::probe_pose(probe);
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
            input.probe_position = probe.position;
            input.probe_orientation = probe.orientation;
        }
    }
}

/// The imaging thread: renders the section under the probe at [`crate::live::IMAGING_RATE_SETTING`]
/// while a page looks ([`Shared::watchers`] > 0) and sleeps otherwise.
pub(super) struct ImagingThread {
    stop: Arc<AtomicBool>,
    handle: JoinHandle<Result<()>>,
}

impl ImagingThread {
    /// Starts rendering `scenario`'s section from `shared`'s image input:
    /// on a patient's leg the section under the probe
    /// ([`SectionImager`]), each vein with its segments of `thrombi` (a
    /// case's, on that leg's anatomy) where the plane cuts it; on the
    /// elliptic cylinder the scenario's `[imaging.anatomy]`. Installs a new
    /// section reading handoff in `shared` ([`Shared::section`]).
    pub(super) fn spawn(
        shared: Arc<Shared>,
        scenario: &Scenario,
        thrombi: Option<Arc<Thrombi>>,
        doppler: Arc<DopplerShared>,
    ) -> Result<Self> {
        let cfg = scenario.live_imaging_config();
        let raise = scenario.haptics.runner.realtime_priority;
        let leg = LegSurface::new(&scenario.thigh, "thigh").context("the scenario's leg")?;
        let (reading, reading_out) = triple_buffer::triple_buffer(&None);
        *shared
            .section
            .lock()
            .map_err(|_| anyhow::anyhow!("live state poisoned"))? = Some(reading_out);
        let stop = Arc::new(AtomicBool::new(false));
        let st = stop.clone();
        let handle = std::thread::Builder::new()
            .name("imaging".into())
            .spawn(move || {
                super::imaging_priority::request_imaging_priority(raise);
                let r = imaging_loop(&shared, &doppler, &cfg, leg, thrombi, reading, &st);
                if let Err(e) = &r {
                    shared.report_fault("imaging", e);
                }
                r
            })
            .context("starting the imaging thread")?;
        Ok(Self { stop, handle })
    }

    /// Wakes the thread (a page opened, or it must stop).
    pub(super) fn wake(&self) {
        self.handle.thread().unpark();
    }

    /// Signals the thread to stop, joins it and returns its error, if any.
    pub(super) fn stop(self) -> Result<()> {
        self.stop.store(true, Ordering::Release);
        self.wake();
        match self.handle.join() {
            Ok(r) => r,
            Err(_) => Err(anyhow::anyhow!("the imaging thread panicked")),
        }
    }
}

/// How long the idle imaging thread sleeps between looks at its stop flag
/// when nobody unparks it (s); a page opening or a stop unparks it at once.
const IDLE_NAP: Duration = Duration::from_millis(200);

/// The imaging thread's body: until `stop`, render a frame every 1 / [`crate::live::IMAGING_RATE_SETTING`] s
/// while a page looks, park while none does; with each frame, write the
/// reading of the section under the probe into `reading`.
fn imaging_loop(
    shared: &Shared,
    doppler: &DopplerShared,
    cfg: &ImagingConfig,
    leg: Option<LegSurface>,
    thrombi: Option<Arc<Thrombi>>,
    mut reading: triple_buffer::Input<Option<SectionReading>>,
    stop: &AtomicBool,
) -> Result<()> {
    let mut vein = shared.vein.load(Ordering::Relaxed);
    let mut source = Source::new(shared, cfg, leg, vein_of(vein), thrombi)?;
    let mut local = SectionDeformation::rest(0.04);
    let mut pixels = vec![0u8; cfg.columns * cfg.rows];
    // The colour overlay of the frame (issue 17), and its processor.
    let mut overlay = Vec::with_capacity(cfg.columns * cfg.rows);
    let mut flow = FlowImaging::default();
    let no_thrombi = Thrombi::default();
    // A fixed-rate schedule: the render's own time does not lengthen the
    // period (a late frame starts the next period now).
    let period = Duration::from_secs_f64(1.0 / crate::live::IMAGING_RATE_SETTING);
    let mut next = Instant::now();
    // The achieved rate, over windows of at least a second.
    let (mut window, mut frames) = (Instant::now(), 0u32);
    let publish_rate = |hz: f64| shared.imaging_rate.store(hz.to_bits(), Ordering::Relaxed);
    while !stop.load(Ordering::Acquire) {
        if shared.watchers.load(Ordering::Acquire) == 0 {
            publish_rate(0.0);
            std::thread::park_timeout(IDLE_NAP);
            next = Instant::now();
            (window, frames) = (next, 0);
            continue;
        }
        let started = Instant::now();
        let v = shared.vein.load(Ordering::Relaxed);
        if v != vein {
            source.set_vein(cfg, vein_of(v))?;
            vein = v;
        }
        let input = {
            let i = shared
                .image_input
                .lock()
                .map_err(|_| anyhow::anyhow!("imaging: the physics' image input is poisoned"))?;
            local.clone_from(&i.deformation);
            Probe {
                pressure: i.pressure,
                time: i.time,
                lateral_offset: i.lateral_offset,
                position: i.probe_position,
                orientation: i.probe_orientation,
            }
        };
        let super::imaging_source::SourceFrame {
            renderer,
            lateral_offset,
            studied,
            ids,
        } = source.frame(&input, vein_of(vein))?;
        if let Some(a) = renderer.anatomy() {
            // The drawn section's femur (the deformation falls to 0 there);
            // kept below the deepest skin displacement, which the model's
            // own femur bounds.
            let deepest = local
                .surface_displacement
                .iter()
                .fold(0.0f64, |m, &d| m.max(d));
            local.bone_depth = a.femur_top().max(deepest + 1e-4);
        }
        let frame = FrameInput {
            deformation: &local,
            probe_pressure: input.pressure,
            time: input.time,
            lateral_offset,
        };
        // The studied vein drawn distended by a Valsalva strain (issue 17).
        renderer.set_vein_distension(flow.vein_distension());
        renderer
            .render_into(&frame, &mut pixels)
            .map_err(|e| anyhow::anyhow!("imaging: rendering a frame: {e}"))?;
        let drawn_depth = renderer.config().depth;
        let lumens = renderer
            .lumens(&frame)
            .map_err(|e| anyhow::anyhow!("imaging: the frame's lumens: {e}"))?;
        let labels = vessel_labels(renderer, &frame, ids)?;
        let band = renderer
            .target_band(&frame, COAPTED_RATIO)
            .map_err(|e| anyhow::anyhow!("imaging: the frame's target band: {e}"))?
            .map_or([0.0; 2], |b| [b.walls_meet, b.artery_clearly_oval]);
        match source.flow_parts(&no_thrombi) {
            Some((renderer, ctx)) => flow.frame(
                doppler,
                &ctx,
                renderer,
                &frame,
                &pixels,
                lumens.as_ref().map(|l| l.vein.area / l.vein.rest_area),
                &mut overlay,
            )?,
            None => overlay.clear(),
        }
        let frame_no = {
            let mut slot = shared
                .image
                .lock()
                .map_err(|_| anyhow::anyhow!("imaging: the image slot is poisoned"))?;
            slot.pixels.copy_from_slice(&pixels);
            slot.overlay.clone_from(&overlay);
            slot.frame += 1;
            slot.time = input.time;
            slot.field.depth = drawn_depth;
            // Published after the slot is written: a reader who sees the
            // number finds that frame (or a newer one) in the slot.
            shared.image_frame.store(slot.frame, Ordering::Release);
            slot.frame
        };
        reading.write(lumens.map(|l| {
            let vein_lumen_ratio = l.vein.area / l.vein.rest_area;
            SectionReading {
                s: studied.map_or(0.0, |(s, _)| s),
                vein: studied.map(|(_, id)| id),
                vein_lumen_ratio,
                artery_lumen_ratio: l.artery.area / l.artery.rest_area,
                walls_met: vein_lumen_ratio < COAPTED_RATIO,
                frame: frame_no,
                time: input.time,
                image_depth: drawn_depth,
                target_band: band,
                labels,
            }
        }));
        frames += 1;
        let now = Instant::now();
        let span = now.duration_since(window).as_secs_f64();
        if span >= 1.0 {
            publish_rate(f64::from(frames) / span);
            (window, frames) = (now, 0);
        }
        next += period;
        wait_for_frame(shared, stop, started, &mut next);
    }
    Ok(())
}

/// The shortest time between the starts of two frames when a front end
/// hurries them ([`crate::live::LiveControl::hurry_image`]): 25 ms, at most
/// 40 frames a second (a live frame costs ~10 ms of a core in release).
const HURRY_INTERVAL: Duration = Duration::from_millis(25);

/// Waits until the frame scheduled at `next` is due, or, when a front end
/// hurries the next frame, until [`HURRY_INTERVAL`] after `started` (the
/// last frame's start), whichever comes first; returns at once on `stop`.
/// A late schedule starts its period now (the frames never burst to catch
/// up).
fn wait_for_frame(shared: &Shared, stop: &AtomicBool, started: Instant, next: &mut Instant) {
    loop {
        let now = Instant::now();
        if stop.load(Ordering::Acquire) || now >= *next {
            break;
        }
        let hurried = shared.hurry_image.load(Ordering::Acquire);
        let earliest = started + HURRY_INTERVAL;
        if hurried && now >= earliest {
            break;
        }
        let until = if hurried { earliest.min(*next) } else { *next };
        std::thread::park_timeout(until - now);
    }
    shared.hurry_image.store(false, Ordering::Release);
    let now = Instant::now();
    if *next < now {
        *next = now;
    }
}

/// The vessels of the frame inside the image, with their ids (`ids`, in
/// the renderer's vessel order; none on the elliptic cylinder): where each
/// lumen is drawn ([`echothigh_imaging::Renderer::vessel_lumen`]).
fn vessel_labels(
    renderer: &echothigh_imaging::Renderer,
    frame: &FrameInput,
    ids: &[Option<StructureId>],
) -> Result<[VesselLabel; MAX_LABELS]> {
    let mut out = [VesselLabel::default(); MAX_LABELS];
    let (half, depth) = (0.5 * renderer.config().width, renderer.config().depth);
    let mut n = 0;
    for (i, id) in ids.iter().enumerate() {
        let (Some(id), true) = (id, n < MAX_LABELS) else {
            continue;
        };
        let Some(l) = renderer
            .vessel_lumen(i, frame)
            .map_err(|e| anyhow::anyhow!("imaging: a vessel's lumen: {e}"))?
        else {
            break;
        };
        if l.lateral.abs() <= half && l.depth > 0.0 && l.depth <= depth {
            out[n] = VesselLabel {
                id: Some(*id),
                lateral: l.lateral,
                depth: l.depth,
                radii: [l.half_width, l.half_height],
            };
            n += 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::{LiveMesh, LiveSnapshot};
    use crate::live_system::shared::{ImageInput, ImageSlot};
    use std::sync::atomic::{AtomicU8, AtomicUsize};
    use std::sync::Mutex;

    /// The imaging thread's failure path (issue 16: every thread reports its
    /// error): a renderer that cannot be built stops the thread with the
    /// error, `stop` joins it and returns that error, and the page's fault
    /// line names the thread.
    #[test]
    fn a_failing_imaging_thread_is_joined_and_reports_its_error() {
        let shared = Arc::new(Shared {
            mesh: Mutex::new(LiveMesh {
                rest: Vec::new(),
                triangles: Vec::new(),
            }),
            snapshot: Mutex::new(LiveSnapshot::default()),
            image_input: Mutex::new(ImageInput {
                deformation: SectionDeformation::rest(0.04),
                pressure: 0.0,
                time: 0.0,
                lateral_offset: 0.0,
                probe_position: [0.0; 3],
                probe_orientation: [1.0, 0.0, 0.0, 0.0],
            }),
            image: Mutex::new(ImageSlot {
                pixels: Vec::new(),
                overlay: Vec::new(),
                width: 0,
                height: 0,
                frame: 0,
                time: 0.0,
                field: crate::live::ImageGeometry::default(),
            }),
            vein: AtomicU8::new(0),
            haptic: Mutex::new(None),
            section: Mutex::new(None),
            device: Mutex::new(None),
            watchers: AtomicUsize::new(1),
            haptic_priority: AtomicU8::new(0),
            imaging_rate: std::sync::atomic::AtomicU64::new(0),
            image_frame: std::sync::atomic::AtomicU64::new(0),
            hurry_image: AtomicBool::new(false),
            fault: Mutex::new(None),
        });
        // An image of no rows: the scenario loader refuses it, so it is set
        // here behind the loader's back to make the renderer fail.
        let mut scenario = Scenario::default();
        scenario.imaging.live_rows = 0;
        let thread =
            ImagingThread::spawn(shared.clone(), &scenario, None, Default::default()).unwrap();
        let err = thread.stop().unwrap_err();
        assert!(format!("{err:#}").contains("imaging"), "{err:#}");
        let fault = shared.fault.lock().unwrap().clone();
        let fault = fault.expect("the fault reached the page's status");
        assert!(fault.starts_with("the imaging thread stopped"), "{fault}");
    }
}
