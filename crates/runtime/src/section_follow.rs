//! The live image follows the probe on the leg (issue 12): the probe's pose
//! on the patient's leg from the device's position and orientation, and a
//! renderer of the section under it, rebuilt from
//! [`echothigh_anatomy::Anatomy::section`] when the probe has moved far
//! enough for the drawn anatomy to lag, its scatterers fixed in the
//! tissue's material coordinates ([`echothigh_imaging::MaterialWindow`]) so
//! that the speckle stays continuous as the probe slides.
//!
//! Runs on the imaging thread only (a rebuild takes tens of ms; nothing
//! here is on the physics' or the haptic tick's path).
//!
//! **Material coordinates of the leg** (m): elevation = `s` of the probe's
//! face centre; lateral = `±θ r(s, θ)`, the arc from the anterior line on a
//! circle of the local skin radius, signed along the image's lateral axis
//! (`+` in the front half, where the image's right is increasing θ, `−`
//! behind, see [`echothigh_anatomy::section`]).
//!
//! **Rebuild threshold** `δ = max(r_min / 4, Δx)`: `r_min` the smallest
//! radius of a vessel the section cuts, `Δx` the lateral pixel pitch. Between
//! rebuilds the drawn anatomy is panned with the probe (lateral) but not
//! moved along the leg; a vessel's centreline runs within 45° of the leg's
//! axis (|dc/ds| ≤ 1), so after `δ` of travel it is drawn at most `r/4`
//! from where the section puts it, three quarters of its lumen still in
//! place. The speckle does not wait for a rebuild: the plane moves across
//! the slice ([`echothigh_imaging::Renderer::set_elevation`]) at every
//! frame, within a margin of `δ`.

use crate::section_image::section_anatomy_with;
use anyhow::{Context, Result};
use echothigh_anatomy::section::MAX_ANGLE;
use echothigh_anatomy::{frame, Anatomy, ProbePose, StructureId, Thrombi};
use echothigh_imaging::{AnatomyConfig, ImagingConfig, MaterialWindow, Renderer, VeinState};
use echothigh_model::{LegSurface, Vec3};
use nalgebra::{Quaternion, UnitQuaternion};
use std::sync::Arc;

/// The probe's pose on `leg` from its face centre `position` (m, model
/// frame) and `orientation` (w, x, y, z; model ← tool, the beam along the
/// tool's `−y`): `s` and `θ` of the point where the beam's axis meets the
/// rest skin ([`contact_point`]: a face pressed into the skin along its
/// beam keeps its place, on the leg's taper too), and the tilt of the beam
/// out of the transverse plane (+ distally), clamped to ±60°
/// ([`MAX_ANGLE`]); the spin about the beam is taken as 0 (the page and the
/// simulated devices hold the image transverse). Errors when the face is
/// beyond the leg's ends or the input is not finite.
pub fn leg_pose(leg: &LegSurface, position: [f64; 3], orientation: [f64; 4]) -> Result<ProbePose> {
    let face = leg.to_leg(&Vec3::from(position));
    let anatomy = leg.anatomy();
    anatomy.check_s("probe position s (m)", frame::s_of(&face))?;
    anyhow::ensure!(
        frame::theta_of(&face).is_finite() && orientation.iter().all(|v| v.is_finite()),
        "the probe's position or orientation is not finite"
    );
    let [w, x, y, z] = orientation;
    let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
    let beam = -(q * Vec3::y());
    let p = contact_point(anatomy, &face, &beam);
    let s = frame::s_of(&p);
    let theta = frame::theta_of(&p);
    anatomy.check_s("probe contact s (m)", s)?;
    let plane = anatomy.image_plane(&ProbePose::transverse(s, theta))?;
    let mut distal = plane.lateral.cross(&plane.depth);
    if distal.z > 0.0 {
        distal = -distal;
    }
    let tilt = beam
        .dot(&distal)
        .atan2(beam.dot(&plane.depth))
        .clamp(-MAX_ANGLE, MAX_ANGLE);
    Ok(ProbePose {
        s,
        theta,
        tilt,
        spin: 0.0,
    })
}

/// Where the beam's axis through a pressed `face` centre (m, leg frame)
/// meets the rest skin: the face moved back along `beam` (unit, into the
/// tissue) by the `t ∈ [0, 0.1 m]` at which its distance from the leg's
/// axis reaches the skin's radius there (bisection to 1 nm). A face on or
/// off the skin is its own contact point. Pressing along the beam moves the
/// face's `s` by the depth times the taper's slope (0.8 mm for 8 mm on the
/// default thigh), which rebuilt the live section at every press.
fn contact_point(anatomy: &Anatomy, face: &Vec3, beam: &Vec3) -> Vec3 {
    let outside = |p: &Vec3| {
        let s = frame::s_of(p);
        anatomy.check_s("s", s).is_err()
            || p.xy().norm() >= anatomy.leg().skin_radius(s, frame::theta_of(p))
    };
    if outside(face) {
        return *face;
    }
    let (mut lo, mut hi) = (0.0, 0.1);
    if !outside(&(face - hi * beam)) {
        return *face;
    }
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if outside(&(face - mid * beam)) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    face - hi * beam
}

/// Material lateral coordinate (m) of the image centre at `pose` (see the
/// module docs).
fn material_lateral(anatomy: &Anatomy, pose: &ProbePose) -> f64 {
    let sign = if pose.theta.cos() >= 0.0 { 1.0 } else { -1.0 };
    sign * pose.theta * anatomy.leg().skin_radius(pose.s, pose.theta)
}

/// The renderer of the section under the probe, rebuilt as it moves.
#[derive(Debug)]
pub struct SectionImager {
    leg: LegSurface,
    cfg: ImagingConfig,
    vein: VeinState,
    renderer: Renderer,
    /// A case's thrombus segments on this leg (issue 13), `None` for a
    /// healthy leg (the vein then follows the global `vein` state).
    thrombi: Option<Arc<Thrombi>>,
    /// The pose the drawn anatomy was taken at.
    built: ProbePose,
    /// The pose of the last rebuild attempt (a failed one keeps `built`).
    tried: ProbePose,
    threshold: f64,
    rebuilds: u64,
    last_error: Option<String>,
    /// The ids of the drawn vessels, in the renderer's order (empty when the
    /// anatomy was not the leg's section).
    names: Vec<Option<StructureId>>,
}

impl SectionImager {
    /// The imager of `leg` with `cfg`'s image geometry and beam and the
    /// vein in `vein`, its first section at `pose` (where no section can be
    /// drawn, `cfg`'s own `[imaging.anatomy]` until the probe reaches one).
    pub fn new(
        leg: LegSurface,
        cfg: &ImagingConfig,
        vein: VeinState,
        pose: ProbePose,
    ) -> Result<Self> {
        Self::with_thrombi(leg, cfg, vein, pose, None)
    }

    /// As [`SectionImager::new`], each section drawn with `thrombi` (a
    /// case's segments on `leg`'s anatomy: every vein the plane cuts takes
    /// its lumen law at the `s` where it is cut,
    /// [`crate::section_image::section_anatomy_with`]).
    pub fn with_thrombi(
        leg: LegSurface,
        cfg: &ImagingConfig,
        vein: VeinState,
        pose: ProbePose,
        thrombi: Option<Arc<Thrombi>>,
    ) -> Result<Self> {
        let t = thrombi.as_deref();
        let (renderer, threshold, last_error, names) =
            match Self::build(&leg, cfg, vein, &pose, None, t)? {
                Outcome::Built(r, t, n) => (*r, t, None, n),
                Outcome::Undrawable(e) => {
                    match Self::build(&leg, cfg, vein, &pose, Some(&cfg.anatomy), t)? {
                        Outcome::Built(r, t, n) => (*r, t, Some(e), n),
                        Outcome::Undrawable(e2) => anyhow::bail!("imaging: {e2}"),
                    }
                }
            };
        Ok(SectionImager {
            leg,
            cfg: cfg.clone(),
            vein,
            renderer,
            thrombi,
            built: pose,
            tried: pose,
            threshold,
            rebuilds: 0,
            last_error,
            names,
        })
    }

    /// A renderer at `pose` with `anatomy`, or else the section's, and its
    /// threshold; [`Outcome::Undrawable`] when the section's anatomy cannot
    /// be drawn.
    fn build(
        leg: &LegSurface,
        cfg: &ImagingConfig,
        vein: VeinState,
        pose: &ProbePose,
        anatomy: Option<&AnatomyConfig>,
        thrombi: Option<&Thrombi>,
    ) -> Result<Outcome> {
        let leg_anatomy = leg.anatomy();
        let dx = cfg.pixel_width();
        let section = leg_anatomy.section(pose)?;
        let r_min = section
            .structures
            .iter()
            .filter(|x| x.kind.is_vessel())
            .map(|x| x.ellipse.radii[0].min(x.ellipse.radii[1]))
            .fold(f64::INFINITY, f64::min);
        let threshold = if r_min.is_finite() {
            (0.25 * r_min).max(dx)
        } else {
            dx
        };
        let mut c = cfg.clone();
        let from_section = anatomy.is_none();
        // The pan only spans the travel between rebuilds (plus a column
        // of rounding each way), which keeps the field small.
        c.pan_range = threshold + 2.0 * dx;
        c.anatomy = match anatomy {
            Some(a) => a.clone(),
            None => match section_anatomy_with(&cfg.anatomy, leg_anatomy, pose, thrombi) {
                Ok(a) => a,
                Err(e) => return Ok(Outcome::Undrawable(format!("{e:#}"))),
            },
        };
        if cfg.auto_depth {
            // The depth a sonographer sets at this level (issue 21): the
            // studied vein's far wall at ¾ of the image, in whole cm.
            c.depth = crate::image_depth::section_depth(&c.anatomy)?;
        }
        let window = MaterialWindow {
            lateral: material_lateral(leg_anatomy, pose),
            elevation: pose.s,
            margin: threshold,
        };
        let r =
            Renderer::in_tissue(&c, vein, window).map_err(|e| anyhow::anyhow!("imaging: {e}"))?;
        let names = if from_section {
            crate::section_image::vessel_ids(
                &section,
                pose.s,
                leg_anatomy.deep_vein_at(pose.s),
                &c.anatomy,
            )
        } else {
            Vec::new()
        };
        Ok(Outcome::Built(Box::new(r), threshold, names))
    }

    /// Follows the probe to `pose` on the calling thread: rebuilds the
    /// section when it is [due](SectionImager::due), else moves the plane
    /// across the slice ([`SectionImager::track`]). Returns whether it
    /// rebuilt. A section that cannot be drawn keeps the last one (see
    /// [`SectionImager::last_error`]).
    pub fn follow(&mut self, pose: &ProbePose) -> Result<bool> {
        if self.due(pose) {
            self.mark_tried(pose);
            let b = self.builder().build(pose, self.vein)?;
            if self.install(b) {
                return Ok(true);
            }
        }
        self.track(pose)?;
        Ok(false)
    }

    /// Whether the probe at `pose` has moved more than the threshold from
    /// the drawn section and from the last attempt (along the leg, around
    /// it, or tilted by `δ / depth`).
    pub fn due(&self, pose: &ProbePose) -> bool {
        let a = self.leg.anatomy();
        let d = self.threshold;
        let depth = self.cfg.depth;
        let moved = |from: &ProbePose| {
            (pose.s - from.s).abs() > d
                || (material_lateral(a, pose) - material_lateral(a, from)).abs() > d
                || (pose.tilt - from.tilt).abs() * depth > d
        };
        moved(&self.tried) && moved(&self.built)
    }

    /// Records an attempt at `pose` (a build was asked for there).
    pub fn mark_tried(&mut self, pose: &ProbePose) {
        self.tried = *pose;
    }

    /// What builds this imager's sections, for another thread.
    pub fn builder(&self) -> SectionBuilder {
        SectionBuilder {
            leg: self.leg.clone(),
            cfg: self.cfg.clone(),
            thrombi: self.thrombi.clone(),
        }
    }

    /// Installs a section built by [`SectionBuilder::build`]: returns
    /// whether it was drawable and for the current vein state (else it is
    /// dropped, its error kept in [`SectionImager::last_error`]).
    pub fn install(&mut self, b: SectionBuild) -> bool {
        if b.vein != self.vein {
            return false;
        }
        match b.outcome {
            Outcome::Built(r, t, names) => {
                self.renderer = *r;
                self.names = names;
                self.built = b.pose;
                self.threshold = t;
                self.rebuilds += 1;
                self.last_error = None;
                true
            }
            Outcome::Undrawable(e) => {
                self.last_error = Some(e);
                false
            }
        }
    }

    /// Moves the image plane to the probe's `s` across the slice, within the
    /// drawn section's margin.
    pub fn track(&mut self, pose: &ProbePose) -> Result<()> {
        let win = self
            .renderer
            .material_window()
            .context("a material renderer")?;
        let e = pose
            .s
            .clamp(win.elevation - win.margin, win.elevation + win.margin);
        self.renderer
            .set_elevation(e)
            .map_err(|e| anyhow::anyhow!("imaging: {e}"))
    }

    /// The lateral offset (m) of the probe at `pose` from the drawn
    /// section's centre, along the image's lateral axis
    /// ([`echothigh_imaging::FrameInput::lateral_offset`]).
    /// Whole lateral pixels, so that image column `j` always shows material
    /// column `round(a/Δx) + j` ([`SectionImager::material_column`]),
    /// whether the section was just rebuilt or panned.
    pub fn lateral_offset(&self, pose: &ProbePose) -> f64 {
        let dx = self.cfg.pixel_width();
        (self.material_column(pose) - self.material_column(&self.built)) as f64 * dx
    }

    /// The material lateral column (lateral pixels) of the image centre at
    /// `pose`: `round(a / Δx)`, `a` the material lateral coordinate (see
    /// the module docs).
    pub fn material_column(&self, pose: &ProbePose) -> i64 {
        (material_lateral(self.leg.anatomy(), pose) / self.cfg.pixel_width()).round() as i64
    }

    /// Changes the vein state (a new renderer at the drawn pose).
    pub fn set_vein(&mut self, vein: VeinState) -> Result<()> {
        if vein != self.vein {
            let drawn = self.renderer.config().anatomy.clone();
            if let Outcome::Built(r, _, _) =
                Self::build(&self.leg, &self.cfg, vein, &self.built, Some(&drawn), None)?
            {
                self.renderer = *r;
            }
            self.vein = vein;
        }
        Ok(())
    }

    /// The renderer and [`Self::vessel_ids`] together.
    pub fn renderer_and_ids(&mut self) -> (&mut Renderer, &[Option<StructureId>]) {
        (&mut self.renderer, &self.names)
    }

    /// The ids of the drawn vessels in the renderer's order
    /// (`echothigh_imaging::Anatomy::vessels`); empty when the drawn anatomy
    /// is not the leg's section (none could be drawn here).
    pub fn vessel_ids(&self) -> &[Option<StructureId>] {
        &self.names
    }

    /// The case's thrombus segments it draws, if any.
    pub fn thrombi(&self) -> Option<&Thrombi> {
        self.thrombi.as_deref()
    }

    /// The leg it images.
    pub fn leg(&self) -> &LegSurface {
        &self.leg
    }

    /// The renderer of the drawn section, read-only.
    pub fn renderer_ref(&self) -> &Renderer {
        &self.renderer
    }

    /// The renderer of the current section.
    pub fn renderer(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// The pose the drawn section was taken at.
    pub fn built_pose(&self) -> ProbePose {
        self.built
    }

    /// The rebuild threshold δ (m) of the drawn section.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Sections rebuilt since construction.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Why the last rebuild kept the previous section, if it did.
    pub fn last_error(&self) -> Option<&str> {
        self.last_error.as_deref()
    }
}

/// Builds sections of one leg and image geometry (on any thread).
#[derive(Debug, Clone)]
pub struct SectionBuilder {
    leg: LegSurface,
    cfg: ImagingConfig,
    thrombi: Option<Arc<Thrombi>>,
}

impl SectionBuilder {
    /// The section at `pose` with the vein in `vein` (tens to hundreds of
    /// ms: the scatterer field is drawn anew).
    pub fn build(&self, pose: &ProbePose, vein: VeinState) -> Result<SectionBuild> {
        Ok(SectionBuild {
            pose: *pose,
            vein,
            outcome: SectionImager::build(
                &self.leg,
                &self.cfg,
                vein,
                pose,
                None,
                self.thrombi.as_deref(),
            )?,
        })
    }
}

/// A section built for [`SectionImager::install`].
#[derive(Debug)]
pub struct SectionBuild {
    pose: ProbePose,
    vein: VeinState,
    outcome: Outcome,
}

/// What [`SectionImager::build`] made.
#[derive(Debug)]
enum Outcome {
    /// A renderer, its threshold (m) and its vessels' ids.
    Built(Box<Renderer>, f64, Vec<Option<StructureId>>),
    /// Why the section cannot be drawn.
    Undrawable(String),
}
