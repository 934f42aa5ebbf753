//! [`Anatomy`]: one patient's leg, its vessel tree, bones and landmarks, and
//! the queries on them (skin, inside, femur depth, image plane, section,
//! sites).

use crate::cut::{cut, Ellipse};
use crate::error::AnatomyError;
use crate::frame::{self, Vec3};
use crate::interp::Profile;
use crate::leg::LegShape;
use crate::levels::Levels;
use crate::patient::Patient;
use crate::section::{ImagePlane, ProbePose, Section, SectionStructure, Site, MAX_ANGLE};
use crate::structure::{Ellipsoid, StructureId, Tube};
use crate::vessels;
use nalgebra::{Matrix2x3, Matrix3, Matrix3x2, RowVector3};

/// Step (m) of the search for the plane's crossings of a centreline: 1 mm,
/// finer than any centreline's turn (each moves < 1.2 mm per mm of s).
const ROOT_SCAN: f64 = 1e-3;

/// How far (m) above the inguinal ligament a tube that starts there (the
/// common femoral vessels, the femur) is continued when the plane crosses
/// its line only beyond it: 40 mm. On the leg the vessels go on as the
/// external iliac ones and the femur as its neck; a transverse plane at
/// `s` ≈ 0 on the sloping groin (the skin normal tilts proximally) reaches
/// `s` < 0 at depth: at 60 mm depth a 30° slope moves the plane ≈ 35 mm.
const PROXIMAL_CONTINUATION: f64 = 0.04;

/// One patient's leg anatomy (a right leg; frame in [`crate::frame`]).
#[derive(Debug, Clone)]
pub struct Anatomy {
    patient: Patient,
    leg: LegShape,
    levels: Levels,
    fat: Profile,
    tubes: Vec<Tube>,
    node: Option<Ellipsoid>,
}

impl Anatomy {
    /// Builds and checks the anatomy of `patient` (validated first): errors
    /// name the key at fault, or the structure that would leave the leg or
    /// cross a bone and the keys that place it.
    pub fn new(patient: Patient) -> Result<Anatomy, AnatomyError> {
        patient.validate()?;
        let leg = LegShape::new(&patient);
        let built = vessels::build(&patient, &leg)?;
        Ok(Anatomy {
            levels: Levels::new(&patient),
            fat: vessels::fat_profile(&patient),
            leg,
            patient,
            tubes: built.tubes,
            node: built.node,
        })
    }

    /// The patient.
    pub fn patient(&self) -> &Patient {
        &self.patient
    }
    /// The skin surface.
    pub fn leg(&self) -> &LegShape {
        &self.leg
    }
    /// The named levels along the leg.
    pub fn levels(&self) -> &Levels {
        &self.levels
    }
    /// Every swept structure (vessels, femur, tibia, sartorius).
    pub fn tubes(&self) -> &[Tube] {
        &self.tubes
    }
    /// The swept structure `id`, if this patient has it.
    pub fn tube(&self, id: StructureId) -> Option<&Tube> {
        self.tubes.iter().find(|t| t.id() == id)
    }
    /// The lymph node (variant), if present.
    pub fn lymph_node(&self) -> Option<&Ellipsoid> {
        self.node.as_ref()
    }
    /// Modelled length (m).
    pub fn length(&self) -> f64 {
        self.leg.length()
    }
    /// Subcutaneous fat thickness (m) at `s`.
    pub fn fat_thickness(&self, s: f64) -> f64 {
        self.fat.eval(s)
    }
    /// Depth (m) of the muscular fascia below the skin surface at `s`,
    /// along the skin's normal: skin + fat.
    pub fn fascia_depth(&self, s: f64) -> f64 {
        self.patient.skin_thickness + self.fat.eval(s)
    }

    /// `Ok(())` when `s` lies in `[0, length]`; else an error naming `what`.
    pub fn check_s(&self, what: &'static str, s: f64) -> Result<(), AnatomyError> {
        if !s.is_finite() || s < 0.0 || s > self.length() {
            return Err(AnatomyError::OutsideLeg {
                what,
                value: s,
                length: self.length(),
            });
        }
        Ok(())
    }

    fn check_angle(what: &'static str, a: f64, max: f64) -> Result<(), AnatomyError> {
        if !a.is_finite() || a.abs() > max {
            return Err(AnatomyError::BadQuery {
                what,
                value: a,
                reason: "must be finite and within the accepted range (θ any finite angle; tilt and spin within ±60°)",
            });
        }
        Ok(())
    }

    /// Skin point (m, leg frame) at `(s, θ)`.
    pub fn skin_point(&self, s: f64, theta: f64) -> Result<Vec3, AnatomyError> {
        self.check_s("s", s)?;
        Self::check_angle("theta", theta, f64::MAX)?;
        Ok(self.leg.skin_point(s, theta))
    }

    /// Outward unit normal of the skin at `(s, θ)`.
    pub fn skin_normal(&self, s: f64, theta: f64) -> Result<Vec3, AnatomyError> {
        self.check_s("s", s)?;
        Self::check_angle("theta", theta, f64::MAX)?;
        Ok(self.leg.skin_normal(s, theta))
    }

    /// Whether `p` (leg frame, m) lies inside the leg.
    pub fn contains(&self, p: &Vec3) -> bool {
        self.leg.contains(p)
    }

    /// Distance (m) from the skin point at `(s, θ)` along `direction`
    /// (default: the inward normal; normalised) to the femur's surface, or
    /// `None` when the ray leaves the leg without meeting the femur. Ray
    /// marched in 0.5 mm steps (thinner than any bone wall here: the femur's
    /// radius ≥ 13 mm) and refined by bisection to 1 µm.
    pub fn femur_depth(
        &self,
        s: f64,
        theta: f64,
        direction: Option<Vec3>,
    ) -> Result<Option<f64>, AnatomyError> {
        let o = self.skin_point(s, theta)?;
        let d = match direction {
            None => -self.leg.skin_normal(s, theta),
            Some(v) if v.iter().all(|c| c.is_finite()) && v.norm() > 0.0 => v.normalize(),
            Some(v) => {
                return Err(AnatomyError::BadQuery {
                    what: "direction",
                    value: v.norm(),
                    reason: "must be a finite non-zero vector",
                })
            }
        };
        let femur = self
            .tube(StructureId::Femur)
            .expect("every anatomy has a femur");
        let inside_bone = |t: f64| {
            let p = o + t * d;
            let s = frame::s_of(&p);
            if !femur.exists_at(s) {
                return false;
            }
            let c = femur.cross_section(s);
            (p.xy() - nalgebra::Vector2::new(c.x, c.y)).norm() <= c.r1
        };
        let step = 5e-4;
        let mut t = step;
        loop {
            let p = o + t * d;
            if !self.leg.contains(&p) {
                return Ok(None);
            }
            if inside_bone(t) {
                let (mut lo, mut hi) = (t - step, t);
                while hi - lo > 1e-6 {
                    let mid = 0.5 * (lo + hi);
                    if inside_bone(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Ok(Some(hi));
            }
            t += step;
        }
    }

    /// The image plane of `pose` (see [`crate::section`] for the convention).
    pub fn image_plane(&self, pose: &ProbePose) -> Result<ImagePlane, AnatomyError> {
        self.check_s("s", pose.s)?;
        Self::check_angle("theta", pose.theta, f64::MAX)?;
        Self::check_angle("tilt", pose.tilt, MAX_ANGLE)?;
        Self::check_angle("spin", pose.spin, MAX_ANGLE)?;
        let o = self.leg.skin_point(pose.s, pose.theta);
        let w0 = -self.leg.skin_normal(pose.s, pose.theta);
        let t = self.leg.transverse_tangent(pose.s, pose.theta);
        let u0 = if pose.theta.cos() >= 0.0 { t } else { -t };
        // Elevation direction pointing distally (−z), orthogonal to u0 and w0.
        let distal = |a: &Vec3, b: &Vec3| {
            let e = a.cross(b).normalize();
            if e.z > 0.0 {
                -e
            } else {
                e
            }
        };
        let e0 = distal(&u0, &w0);
        let w = pose.tilt.cos() * w0 + pose.tilt.sin() * e0;
        let e1 = distal(&u0, &w);
        let u = pose.spin.cos() * u0 + pose.spin.sin() * e1;
        Ok(ImagePlane {
            origin: o,
            lateral: u,
            depth: w,
            normal: u.cross(&w),
        })
    }

    /// The section under the probe at `pose`: every structure the plane
    /// cuts, as ellipses in image coordinates, sorted by depth.
    pub fn section(&self, pose: &ProbePose) -> Result<Section, AnatomyError> {
        let plane = self.image_plane(pose)?;
        let mut structures = Vec::new();
        for tube in &self.tubes {
            for (s, e) in cut_tube(tube, &plane) {
                structures.push(SectionStructure {
                    id: tube.id(),
                    kind: tube.kind(),
                    ellipse: e,
                    s,
                });
            }
        }
        if let Some(n) = &self.node {
            let l: Matrix3<f64> =
                Matrix3::from_diagonal(&n.semi_axes.map(|a| 1.0 / a)) * n.axes.transpose();
            let m: Matrix3x2<f64> = Matrix3x2::from_columns(&[l * plane.lateral, l * plane.depth]);
            if let Some(e) = cut(&m, &(l * (plane.origin - n.centre))) {
                structures.push(SectionStructure {
                    id: n.id,
                    kind: n.kind,
                    ellipse: e,
                    s: frame::s_of(&n.centre),
                });
            }
        }
        structures.sort_by(|a, b| a.ellipse.depth.total_cmp(&b.ellipse.depth));
        let cos = (-self.leg.skin_normal(pose.s, pose.theta))
            .dot(&plane.depth)
            .max(1e-6);
        Ok(Section {
            pose: *pose,
            plane,
            skin_depth: self.patient.skin_thickness / cos,
            fascia_depth: self.fascia_depth(pose.s) / cos,
            structures,
        })
    }

    /// The probe pose of an exam site: its level (see [`Site`]), transverse,
    /// centred over the site's vein (the θ where its centre has lateral
    /// position 0), from the front except the popliteal site, from behind.
    pub fn site_pose(&self, site: Site) -> ProbePose {
        let lv = &self.levels;
        let s = match site {
            Site::Cfv => 0.5 * lv.sfj,
            Site::Sfj => lv.sfj + 0.015 * lv.knee,
            Site::FvProximal => lv.confluence + 0.05 * lv.knee,
            Site::FvMid => 0.5 * lv.knee,
            Site::FvDistal => 0.62 * lv.knee,
            Site::Popliteal => 0.9 * lv.knee,
        };
        let pose = self.pose_over(s, site.target());
        pose.expect("every site's vein exists at its level")
    }

    /// The deep vein at `s`: `cfv`, `fv` or `pv` by level.
    pub fn deep_vein_at(&self, s: f64) -> StructureId {
        [StructureId::Cfv, StructureId::Fv, StructureId::Pv]
            .into_iter()
            .find(|&id| self.tube(id).is_some_and(|t| t.exists_at(s)))
            .unwrap_or(StructureId::Pv)
    }

    /// The transverse pose at `s` centred over structure `id` (the θ where
    /// its centre has lateral position 0 in the image), searched from the
    /// angle of its centre (±1.2 rad, bracket then bisection to 1e-12 rad).
    /// Errors when `id` does not exist at `s`.
    pub fn pose_over(&self, s: f64, id: StructureId) -> Result<ProbePose, AnatomyError> {
        self.check_s("s", s)?;
        let tube = self
            .tube(id)
            .filter(|t| t.exists_at(s))
            .ok_or(AnatomyError::BadQuery {
                what: "s",
                value: s,
                reason: "the structure to centre on does not exist at this level",
            })?;
        let guess = frame::theta_of(&tube.centre(s));
        // The image's lateral axis flips with the sign of cos θ (see
        // `section`); undo the flip so that the function searched is
        // continuous and its sign changes are true centrings.
        let lateral = |th: f64| {
            let flip = if th.cos() >= 0.0 { 1.0 } else { -1.0 };
            self.image_plane(&ProbePose::transverse(s, th))
                .ok()
                .and_then(|p| cut_tube(tube, &p).first().map(|(_, e)| flip * e.lateral))
        };
        // Bracket a sign change of the lateral offset around the guess, then bisect.
        for i in 0..60 {
            let (a, b) = (guess - 0.02 * (i + 1) as f64, guess + 0.02 * i as f64);
            for (lo, hi) in [(b, b + 0.02), (a, a + 0.02)] {
                if let (Some(fl), Some(fh)) = (lateral(lo), lateral(hi)) {
                    if fl * fh <= 0.0 {
                        let (mut lo, mut hi, mut flo) = (lo, hi, fl);
                        for _ in 0..50 {
                            let mid = 0.5 * (lo + hi);
                            let fm = lateral(mid).unwrap_or(0.0);
                            if fm * flo <= 0.0 {
                                hi = mid;
                            } else {
                                lo = mid;
                                flo = fm;
                            }
                        }
                        return Ok(ProbePose::transverse(s, 0.5 * (lo + hi)));
                    }
                }
            }
        }
        Ok(ProbePose::transverse(s, guess))
    }
}

/// The plane's cuts of `tube`: each crossing `s*` of its centreline and the
/// ellipse of the tube linearised there (see [`crate::cut`]).
///
/// Linearised tube at `C₀ = C(s*)`, `a = dC/ds` (a_z = −1): a point `q`
/// lies at `s = −q_z`, its transverse offset from the axis is
/// `d = (q − C₀)_xy + a_xy (q − C₀)_z` (= `P (q − C₀)`), and it is inside
/// when `(d·e₁/r₁)² + (d·e₂/r₂)² ≤ 1` (`e₁` at angle ω).
pub fn cut_tube(tube: &Tube, plane: &ImagePlane) -> Vec<(f64, Ellipse)> {
    let (s0, s1) = tube.s_range();
    let s_hi = if tube.exists_at(s1) { s1 } else { s1 - 1e-9 };
    let g = |s: f64| plane.normal.dot(&(tube.centre(s) - plane.origin));
    let n = ((s_hi - s0) / ROOT_SCAN).ceil().max(1.0) as usize;
    let mut out = Vec::new();
    let mut prev = (s0, g(s0));
    for i in 1..=n {
        let s = s0 + (s_hi - s0) * i as f64 / n as f64;
        let gs = g(s);
        let (sa, ga) = prev;
        if ga == 0.0 || ga * gs < 0.0 {
            let (mut lo, mut hi, mut glo) = (sa, s, ga);
            while hi - lo > 1e-10 && glo != 0.0 {
                let mid = 0.5 * (lo + hi);
                let gm = g(mid);
                if gm * glo <= 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                    glo = gm;
                }
            }
            let sr = if glo == 0.0 { lo } else { 0.5 * (lo + hi) };
            if let Some(e) = ellipse_at(tube, plane, sr) {
                out.push((sr, e));
            }
        }
        prev = (s, gs);
    }
    if prev.1 == 0.0 {
        if let Some(e) = ellipse_at(tube, plane, prev.0) {
            out.push((prev.0, e));
        }
    }
    if out.is_empty() && s0 <= 0.0 {
        // The tube continues above the ligament (see PROXIMAL_CONTINUATION):
        // its line extended straight from s0, `C(s0) + a (s − s0)`, crosses
        // the plane at `s − s0 = −g(s0)/(n·a)`; within the continuation, the
        // cut is that of the tube linearised at s0 (reported at s0, the
        // nearest `s` of the tube's own range).
        let a = tube.axis_derivative(s0);
        let na = plane.normal.dot(&a);
        if na.abs() > 1e-9 {
            let t = -g(s0) / na;
            if (-PROXIMAL_CONTINUATION..0.0).contains(&t) {
                if let Some(e) = ellipse_at(tube, plane, s0) {
                    out.push((s0, e));
                }
            }
        }
    }
    out
}

fn ellipse_at(tube: &Tube, plane: &ImagePlane, s: f64) -> Option<Ellipse> {
    let c0 = tube.centre(s);
    let a = tube.axis_derivative(s);
    let cs = tube.cross_section(s);
    let p = Matrix2x3::new(1.0, 0.0, a.x, 0.0, 1.0, a.y);
    let (so, co) = cs.omega.sin_cos();
    let r1 = RowVector3::from(nalgebra::RowVector2::new(co, so) * p) / cs.r1;
    let r2 = RowVector3::from(nalgebra::RowVector2::new(-so, co) * p) / cs.r2;
    let l = Matrix3::from_rows(&[r1, r2, RowVector3::zeros()]);
    let m = Matrix3x2::from_columns(&[l * plane.lateral, l * plane.depth]);
    cut(&m, &(l * (plane.origin - c0)))
}
