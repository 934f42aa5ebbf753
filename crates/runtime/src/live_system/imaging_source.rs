//! What the live imaging thread renders: the scenario's fixed section (the
//! elliptic cylinder), or the section under the probe on the patient's leg
//! ([`SectionImager`]), whose rebuilds (a new scatterer field, a few hundred
//! ms) run on a worker thread while the imaging thread keeps rendering the
//! last section, panned and moved across the slice with the probe.

use super::shared::Shared;
use crate::section_follow::{leg_pose, SectionBuild, SectionImager};
use anyhow::{Context, Result};
use echothigh_anatomy::{ProbePose, StructureId, Thrombi};
use echothigh_imaging::{ImagingConfig, Renderer, VeinState};
use echothigh_model::LegSurface;
use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;

/// The probe's part of a frame's input, copied out of the shared image input.
pub(super) struct Probe {
    /// Mean pressure under the probe face (Pa).
    pub pressure: f64,
    /// Session time (s).
    pub time: f64,
    /// The cylinder's lateral offset (m).
    pub lateral_offset: f64,
    /// Face centre (m, model frame).
    pub position: [f64; 3],
    /// Orientation (w, x, y, z).
    pub orientation: [f64; 4],
}

/// The section builder's thread: asked a pose and a vein state, answers a
/// built section; stops when its request channel closes (joined on drop).
pub(super) struct Worker {
    requests: Option<Sender<(ProbePose, VeinState)>>,
    built: Receiver<Result<SectionBuild>>,
    handle: Option<JoinHandle<()>>,
    busy: bool,
}

impl Worker {
    fn spawn(imager: &SectionImager) -> Result<Self> {
        let builder = imager.builder();
        let (req_tx, req_rx) = channel::<(ProbePose, VeinState)>();
        let (out_tx, out_rx) = channel();
        let handle = std::thread::Builder::new()
            .name("imaging-sections".into())
            .spawn(move || {
                for (pose, vein) in req_rx {
                    if out_tx.send(builder.build(&pose, vein)).is_err() {
                        break;
                    }
                }
            })
            .context("starting the section builder thread")?;
        Ok(Worker {
            requests: Some(req_tx),
            built: out_rx,
            handle: Some(handle),
            busy: false,
        })
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.requests = None;
        if let Some(h) = self.handle.take() {
            // A panicking builder already reported through the channel's
            // close; nothing is left to stop.
            let _ = h.join();
        }
    }
}

/// The drawn section's `s` (m) and the deep vein it studies.
pub(super) type Studied = (f64, StructureId);

/// What [`Source::frame`] gives the imaging thread for one frame.
pub(super) struct SourceFrame<'a> {
    /// The renderer to draw with.
    pub renderer: &'a mut Renderer,
    /// The frame's lateral offset (m).
    pub lateral_offset: f64,
    /// On the leg, the drawn section's `s` (m) and its deep vein.
    pub studied: Option<Studied>,
    /// The ids of the renderer's vessels in its order (empty off the leg).
    pub ids: &'a [Option<StructureId>],
}

/// What the imaging thread renders.
pub(super) enum Source {
    /// The scenario's `[imaging.anatomy]`.
    Fixed(Box<Renderer>),
    /// The section under the probe on the leg, and its builder.
    Leg(Box<SectionImager>, Worker),
}

impl Source {
    /// The source of a scenario with (`Some`) or without a leg; the first
    /// section at the probe's published pose (the anterior line at the
    /// mesh's centre before the physics publishes); on a leg, `thrombi` (a
    /// case's segments on it) set each vein's lumen law.
    pub fn new(
        shared: &Shared,
        cfg: &ImagingConfig,
        leg: Option<LegSurface>,
        vein: VeinState,
        thrombi: Option<Arc<Thrombi>>,
    ) -> Result<Self> {
        Ok(match leg {
            None => Source::Fixed(Box::new(
                Renderer::new(cfg, vein).map_err(|e| anyhow::anyhow!("imaging: {e}"))?,
            )),
            Some(leg) => {
                let (pos, q) = shared
                    .image_input
                    .lock()
                    .map(|i| (i.probe_position, i.probe_orientation))
                    .map_err(|_| {
                        anyhow::anyhow!("imaging: the physics' image input is poisoned")
                    })?;
                let pose = leg_pose(&leg, pos, q)
                    .unwrap_or_else(|_| ProbePose::transverse(leg.s_of_z(0.0), 0.0));
                let imager = SectionImager::with_thrombi(leg, cfg, vein, pose, thrombi)?;
                let worker = Worker::spawn(&imager)?;
                Source::Leg(Box::new(imager), worker)
            }
        })
    }

    /// A new vein state (rare: rebuilt on this thread).
    pub fn set_vein(&mut self, cfg: &ImagingConfig, vein: VeinState) -> Result<()> {
        match self {
            Source::Fixed(r) => {
                **r = Renderer::new(cfg, vein)
                    .map_err(|e| anyhow::anyhow!("imaging the new vein state: {e}"))?;
            }
            Source::Leg(f, _) => f.set_vein(vein)?,
        }
        Ok(())
    }

    /// Follows the probe (on the leg: installs a finished section, asks
    /// for a new one when due and none is under way, moves the plane
    /// across the slice) and returns the renderer, the frame's lateral
    /// offset (m), on the leg the drawn section's `s` (m) and the deep
    /// vein it studies, and the ids of the renderer's vessels in its order
    /// (empty on the elliptic cylinder).
    pub fn frame(&mut self, input: &Probe, vein: VeinState) -> Result<SourceFrame<'_>> {
        match self {
            Source::Fixed(r) => Ok(SourceFrame {
                renderer: r,
                lateral_offset: input.lateral_offset,
                studied: None,
                ids: &[],
            }),
            Source::Leg(f, w) => {
                match w.built.try_recv() {
                    Ok(b) => {
                        w.busy = false;
                        f.install(b?);
                    }
                    Err(TryRecvError::Empty) => {}
                    Err(TryRecvError::Disconnected) => {
                        anyhow::bail!("imaging: the section builder thread stopped")
                    }
                }
                let offset = match leg_pose(f.leg(), input.position, input.orientation) {
                    Ok(pose) => {
                        if !w.busy && f.due(&pose) {
                            f.mark_tried(&pose);
                            if let Some(tx) = &w.requests {
                                tx.send((pose, vein))
                                    .context("imaging: the section builder thread stopped")?;
                                w.busy = true;
                            }
                        }
                        f.track(&pose)?;
                        f.lateral_offset(&pose)
                    }
                    // Beyond the leg's ends: the last section, unpanned.
                    Err(_) => 0.0,
                };
                let s = f.built_pose().s;
                let studied = (s, f.leg().anatomy().deep_vein_at(s));
                let (renderer, ids) = f.renderer_and_ids();
                Ok(SourceFrame {
                    renderer,
                    lateral_offset: offset,
                    studied: Some(studied),
                    ids,
                })
            }
        }
    }

    /// On the leg, the drawn section's renderer and what its flow needs
    /// (issue 17): the leg's anatomy, the case's segments (`empty` for a
    /// healthy leg), the section's pose and a key that changes with each
    /// rebuild. `None` on the elliptic cylinder (no flow model).
    pub fn flow_parts<'a>(
        &'a self,
        empty: &'a Thrombi,
    ) -> Option<(&'a Renderer, super::doppler::FlowContext<'a>)> {
        match self {
            Source::Fixed(_) => None,
            Source::Leg(f, _) => Some((
                f.renderer_ref(),
                super::doppler::FlowContext {
                    anatomy: f.leg().anatomy(),
                    thrombi: f.thrombi().unwrap_or(empty),
                    pose: f.built_pose(),
                    key: f.rebuilds(),
                },
            )),
        }
    }
}
