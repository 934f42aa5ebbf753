//! The reference anatomy: the vessel tree, the bones and the sartorius of a
//! right leg, built for one patient from documented control points.
//!
//! Each table below gives knots `(f, value)` with `f = s / knee_s` (the
//! levels of [`crate::levels`]); [`Profile`] interpolates them (C¹,
//! monotone). Angles θ are those of [`crate::frame`] (0 anterior, +medial);
//! depths `d` (mm) are below the muscular fascia along the skin's normal, for
//! the reference (lean male) muscle bulk, and scale with
//! `muscle_depth_scale`; the skin and the patient's fat lie above them.
//!
//! Courses (reference rows 12–13, 15, 27 and issue 12):
//! - **Artery line** CFA → FA → PA: at the mid-inguinal point (θ 0.30) just
//!   under the fascia lata, along the anteromedial thigh under sartorius,
//!   through the adductor hiatus to the back of the knee, where it lies on
//!   the femur's popliteal surface (`POPLITEAL_GAP` behind the bone).
//! - **Vein line** CFV → FV → PV beside its artery, wall to wall `GAP` apart
//!   ("almost inseparably united", Arch Surg 1997), on the side given by the
//!   angle φ in the artery's local frame (φ = 0 towards +θ — medial on the
//!   front —, φ = π/2 deep): medial at the groin, deep (behind) from the apex
//!   of the femoral triangle through mid-thigh, posterolateral in the distal
//!   canal, superficial to the artery seen from behind the knee.
//! - **GSV** superficial, 0.5 mm above the muscular fascia in its saphenous
//!   compartment, from the SFJ along the medial thigh to behind the medial
//!   condyle, diving to the CFV's wall over the last `0.075 knee_s` above
//!   the SFJ; no companion artery.
//! - **DFA / DFV** leave the CFA / the FV at the bifurcation / confluence and
//!   run deep (posterior) towards the femur's medial side; the DFV lies in
//!   front of the DFA (estimate).
//! - **fv2** (variant) splits from the FV at the apex and rejoins it in the
//!   distal canal, medial to the artery; **lymph node** (variant) medial to
//!   the CFV 1 cm below the SFJ.

use crate::error::AnatomyError;
use crate::frame::{self, Vec3};
use crate::interp::{smoothstep, Profile};
use crate::leg::LegShape;
use crate::levels::Levels;
use crate::patient::Patient;
use crate::structure::{CrossSection, Ellipsoid, Kind, StructureId, Tube};
use nalgebra::{Matrix3, Vector2, Vector3};

use crate::tables::*;

/// Subcutaneous fat thickness (m) along the leg: `fat_thickness_proximal`
/// at the groin to `fat_thickness_distal` at 0.6 knee_s, constant below
/// (Krauze 2019 measured the distal thigh).
pub fn fat_profile(p: &Patient) -> Profile {
    Profile::new(&[
        (0.0, p.fat_thickness_proximal),
        (0.6 * p.knee_s, p.fat_thickness_distal),
    ])
    .expect("increasing knots")
}

fn profile(k: f64, knots: &[(f64, f64)], unit: f64) -> Profile {
    let v: Vec<(f64, f64)> = knots.iter().map(|&(f, x)| (f * k, x * unit)).collect();
    Profile::new(&v).expect("static table: increasing knots")
}

/// Everything [`build`] makes.
pub struct Built {
    /// Tubes (vessels, bones, sartorius).
    pub tubes: Vec<Tube>,
    /// The lymph node, when the variant is on.
    pub node: Option<Ellipsoid>,
}

struct Ctx<'a> {
    leg: &'a LegShape,
    lv: Levels,
    p: &'a Patient,
    fat: Profile,
    art_theta: Profile,
    art_depth: Profile,
    vein_phi: Profile,
    vein_d: Profile,
    ratio: Profile,
    femur_y: Profile,
    femur_r: Profile,
}

impl Ctx<'_> {
    fn k(&self) -> f64 {
        self.lv.knee
    }
    /// Point at depth `depth` (m) below the skin at (s, θ), along the normal
    /// of the transverse contour.
    fn deep(&self, s: f64, theta: f64, depth: f64) -> Vector2<f64> {
        let q = self.leg.skin_point(s, theta);
        let n = self.leg.skin_normal(s, theta).xy().normalize();
        q.xy() - depth * n
    }
    fn below_fascia(&self, s: f64, d: f64) -> f64 {
        self.p.skin_thickness + self.fat.eval(s) + self.p.muscle_depth_scale * d
    }
    fn femur(&self, s: f64) -> (Vector2<f64>, f64) {
        let f = (s / self.k()).min(1.0);
        let x = self.p.femur_obliquity_deg.to_radians().tan() * self.k() * (1.0 - f);
        (Vector2::new(x, self.femur_y.eval(s)), self.femur_r.eval(s))
    }
    fn vein_r(&self, s: f64) -> f64 {
        0.5 * self.vein_d.eval(s)
    }
    fn artery_r(&self, s: f64) -> f64 {
        0.5 * self.vein_d.eval(s) / self.ratio.eval(s)
    }
    fn artery(&self, s: f64) -> Vector2<f64> {
        let th = self.art_theta.eval(s);
        let skin_ref = self.deep(s, th, self.below_fascia(s, self.art_depth.eval(s)));
        let (fc, fr) = self.femur(s);
        let bone_ref = fc + (fr + POPLITEAL_GAP + self.artery_r(s)) * frame::outward(th).xy();
        let w = smoothstep((s - self.lv.hiatus) / (0.8 * self.k() - self.lv.hiatus));
        skin_ref + w * (bone_ref - skin_ref)
    }
    /// Local frame at the artery line's angle: (+θ direction, inward).
    fn local(&self, s: f64) -> (Vector2<f64>, Vector2<f64>) {
        let th = self.art_theta.eval(s);
        (frame::along_theta(th).xy(), -frame::outward(th).xy())
    }
    fn beside_artery(&self, s: f64, phi: f64, r_vein: f64) -> Vector2<f64> {
        let (et, ein) = self.local(s);
        let rho = self.artery_r(s) + r_vein + GAP;
        self.artery(s) + rho * (phi.cos() * et + phi.sin() * ein)
    }
    fn vein(&self, s: f64) -> Vector2<f64> {
        self.beside_artery(s, self.vein_phi.eval(s), self.vein_r(s))
    }
}

fn circle(c: Vector2<f64>, r: f64) -> CrossSection {
    CrossSection {
        x: c.x,
        y: c.y,
        r1: r,
        r2: r,
        omega: 0.0,
    }
}

/// Builds the anatomy of `p` on `leg` (assumes `p` validated); checks that
/// every structure lies inside the leg and clear of the bones.
pub fn build(p: &Patient, leg: &LegShape) -> Result<Built, AnatomyError> {
    let lv = Levels::new(p);
    let k = lv.knee;
    let (c, m) = (p.cfv_diameter, p.fv_diameter_mid);
    let ctx = Ctx {
        leg,
        lv,
        p,
        fat: fat_profile(p),
        art_theta: profile(k, &ARTERY_THETA, 1.0),
        art_depth: profile(k, &ARTERY_DEPTH, MM),
        vein_phi: profile(k, &VEIN_PHI, 1.0),
        // Vein diameter: CFV to the confluence, 1.12× the mid FV just below
        // it (derived: between the CFV and the mid FV; no value retrieved),
        // the mid FV, 0.97× distally (6.4 of 6.6 mm: Hertzberg's 6.4–6.8 mm).
        vein_d: Profile::new(&[
            (0.0, c),
            (0.12 * k, c),
            (0.19 * k, 1.12 * m),
            (0.5 * k, m),
            (2.0 / 3.0 * k, 0.97 * m),
        ])
        .expect("increasing knots"),
        ratio: Profile::new(&[
            (0.10 * k, p.vein_artery_ratio_groin),
            (0.17 * k, p.vein_artery_ratio_below),
        ])
        .expect("increasing knots"),
        femur_y: profile(k, &FEMUR_Y, MM),
        femur_r: profile(k, &FEMUR_R, MM),
    };
    let ctx = &ctx;
    let mut tubes = Vec::new();
    let end = p.length;
    // Artery line and vein line, split by level into their named segments.
    for (id, kind, s0, s1, closed, vein) in [
        (
            StructureId::Cfa,
            Kind::Artery,
            0.0,
            lv.bifurcation,
            false,
            false,
        ),
        (
            StructureId::Fa,
            Kind::Artery,
            lv.bifurcation,
            lv.hiatus,
            false,
            false,
        ),
        (StructureId::Pa, Kind::Artery, lv.hiatus, end, true, false),
        (
            StructureId::Cfv,
            Kind::DeepVein,
            0.0,
            lv.confluence,
            false,
            true,
        ),
        (
            StructureId::Fv,
            Kind::DeepVein,
            lv.confluence,
            lv.hiatus,
            false,
            true,
        ),
        (StructureId::Pv, Kind::DeepVein, lv.hiatus, end, true, true),
    ] {
        tubes.push(Tube::tabulate_vessel(id, kind, s0, s1, closed, |s| {
            if vein {
                (ctx.vein(s), ctx.vein_r(s))
            } else {
                (ctx.artery(s), ctx.artery_r(s))
            }
        }));
    }
    // GSV: diameters from Mendoza 2013 (SFJ 7.5, 15 cm below the groin 3.7 mm).
    let (gs, gt) = (p.gsv_diameter_sfj, p.gsv_diameter_thigh);
    let gsv_d = Profile::new(&[
        (0.05 * k, gs),
        (0.09 * k, 0.6 * gs + 0.4 * gt),
        (0.125 * k, 1.15 * gt),
        (lv.sfj + 0.15, gt),
        (1.125 * k, 0.95 * gt),
    ])
    .expect("increasing knots");
    let gsv_theta = profile(k, &GSV_THETA, 1.0);
    let dive = 0.075 * k;
    tubes.push(Tube::tabulate_vessel(
        StructureId::Gsv,
        Kind::SuperficialVein,
        lv.sfj,
        end,
        true,
        |s| {
            let r = 0.5 * gsv_d.eval(s);
            let depth = p.skin_thickness + ctx.fat.eval(s) - r - 0.5 * MM;
            let sup = ctx.deep(s, gsv_theta.eval(s), depth);
            let v = ctx.vein(s);
            let anchor = v + ctx.vein_r(s) * (sup - v).normalize();
            (anchor + smoothstep((s - lv.sfj) / dive) * (sup - anchor), r)
        },
    ));
    // Profunda: diameter at the confluence from area conservation with the
    // CFV and the proximal FV (derived: d² = d_cfv² − d_fv²), tapering to
    // 4 mm (scaled by the patient's FV) at its end in the lower thigh.
    let d_fv_prox = 1.12 * m;
    let d0 = (c * c - d_fv_prox * d_fv_prox).max(0.25 * c * c).sqrt();
    let dfv_d = Profile::new(&[(lv.confluence, d0), (0.6 * k, 4.0 * MM * m / (6.6 * MM))])
        .expect("increasing knots");
    let pro_theta = profile(k, &PROFUNDA.map(|(f, t, _)| (f, t)), 1.0);
    let pro_depth = profile(k, &PROFUNDA.map(|(f, _, d)| (f, d)), MM);
    let below = p.vein_artery_ratio_below;
    let blend = 0.05 * k;
    let dfa_course =
        |s: f64| ctx.deep(s, pro_theta.eval(s), ctx.below_fascia(s, pro_depth.eval(s)));
    tubes.push(Tube::tabulate_vessel(
        StructureId::Dfa,
        Kind::Artery,
        lv.bifurcation,
        0.6 * k,
        false,
        |s| {
            let a = ctx.artery(s);
            let w = smoothstep((s - lv.bifurcation) / blend);
            (a + w * (dfa_course(s) - a), 0.5 * dfv_d.eval(s) / below)
        },
    ));
    tubes.push(Tube::tabulate_vessel(
        StructureId::Dfv,
        Kind::DeepVein,
        lv.confluence,
        0.6 * k,
        false,
        |s| {
            let (rv, ra) = (0.5 * dfv_d.eval(s), 0.5 * dfv_d.eval(s) / below);
            let q = dfa_course(s) + (ra + rv + GAP) * Vector2::new(0.0, 1.0);
            let v = ctx.vein(s);
            (v + smoothstep((s - lv.confluence) / blend) * (q - v), rv)
        },
    ));
    if p.duplicated_fv {
        let (s0, s1, ramp) = (lv.apex, 0.62 * k, 0.04 * k);
        tubes.push(Tube::tabulate_vessel(
            StructureId::Fv2,
            Kind::DeepVein,
            s0,
            s1,
            false,
            |s| {
                let r2 = 0.8 * ctx.vein_r(s);
                let twin = ctx.beside_artery(s, ctx.vein_phi.eval(s) - 1.9, r2);
                let w = smoothstep((s - s0) / ramp) * (1.0 - smoothstep((s - (s1 - ramp)) / ramp));
                let v = ctx.vein(s);
                (v + w * (twin - v), r2)
            },
        ));
    }
    let sart_theta = profile(k, &SARTORIUS_THETA, 1.0);
    tubes.push(Tube::tabulate(
        StructureId::Sartorius,
        Kind::Muscle,
        0.0,
        (1.05 * k).min(end),
        false,
        |s| {
            let th = sart_theta.eval(s);
            let c = ctx.deep(
                s,
                th,
                ctx.below_fascia(s, SARTORIUS_HALF_THICKNESS + 0.5 * MM),
            );
            let t = leg.transverse_tangent(s, th);
            CrossSection {
                x: c.x,
                y: c.y,
                r1: SARTORIUS_HALF_WIDTH,
                r2: SARTORIUS_HALF_THICKNESS,
                omega: t.y.atan2(t.x),
            }
        },
    ));
    tubes.push(Tube::tabulate(
        StructureId::Femur,
        Kind::Bone,
        0.0,
        k,
        false,
        |s| {
            let (c, r) = ctx.femur(s);
            circle(c, r)
        },
    ));
    // Tibia below the joint line (6 mm joint space, estimate): centre 12 mm
    // anterior of the axis, radius 24 mm at the plateau narrowing to 18 mm
    // 5 cm below (estimates).
    let tibia_r = Profile::new(&[(k, 24.0 * MM), (k + 0.05, 18.0 * MM)]).expect("increasing");
    tubes.push(Tube::tabulate(
        StructureId::Tibia,
        Kind::Bone,
        k + 0.006,
        end,
        true,
        |s| circle(Vector2::new(0.0, 12.0 * MM), tibia_r.eval(s)),
    ));
    let node = p.lymph_node.then(|| {
        let s = lv.sfj + 0.025 * k;
        let (et, ein) = ctx.local(s);
        let centre = ctx.vein(s) + (ctx.vein_r(s) + 1.0 * MM + 5.0 * MM) * et;
        let z = Vector3::new(0.0, 0.0, 1.0);
        let a1 = Vector3::new(et.x, et.y, 0.0);
        let a2 = Vector3::new(ein.x, ein.y, 0.0);
        Ellipsoid {
            id: StructureId::LymphNode,
            kind: Kind::LymphNode,
            centre: Vec3::new(centre.x, centre.y, -s),
            axes: Matrix3::from_columns(&[z, a1, a2]),
            // Long axis 16 mm along the leg, short axes 10 × 8 mm (estimate:
            // a normal node, short axis < 10 mm).
            semi_axes: Vector3::new(8.0 * MM, 5.0 * MM, 4.0 * MM),
        }
    });
    check(leg, &tubes, node.as_ref())?;
    Ok(Built { tubes, node })
}

fn keys_of(id: StructureId) -> &'static str {
    match id {
        StructureId::Gsv => {
            "{fat_thickness_proximal, fat_thickness_distal, gsv_diameter_sfj, gsv_diameter_thigh}"
        }
        StructureId::Femur | StructureId::Tibia => "{femur_obliquity_deg, circumference_*}",
        _ => "{muscle_depth_scale, fat_thickness_*, circumference_*, *_diameter*}",
    }
}

/// Every structure inside the leg (its radius, or the band's thickness,
/// within the skin along its radial line),
/// and every vessel, the sartorius and the node clear of the bones.
fn check(leg: &LegShape, tubes: &[Tube], node: Option<&Ellipsoid>) -> Result<(), AnatomyError> {
    let bones: Vec<&Tube> = tubes.iter().filter(|t| t.kind() == Kind::Bone).collect();
    for t in tubes {
        let (s0, s1) = t.s_range();
        let n = ((s1 - s0) / 2e-3).ceil() as usize;
        for i in 0..=n {
            let s = s0 + (s1 - s0) * i as f64 / n as f64;
            let cs = t.cross_section(s);
            let c = Vec3::new(cs.x, cs.y, -s);
            // The sartorius band lies flat under the fascia: its thickness
            // (r2) faces the skin; a vessel is a circle.
            let r = if t.kind() == Kind::Muscle {
                cs.r2
            } else {
                cs.r1.max(cs.r2)
            };
            let room = leg.skin_radius(s, frame::theta_of(&c)) - c.xy().norm();
            let fail = |problem| AnatomyError::StructureOutside {
                structure: t.id().as_str(),
                s,
                problem,
                keys: keys_of(t.id()),
            };
            if room < r {
                return Err(fail("lies outside the leg"));
            }
            if t.kind() == Kind::Bone {
                continue;
            }
            for b in &bones {
                if b.exists_at(s) {
                    let bc = b.cross_section(s);
                    let d = (Vector2::new(bc.x, bc.y) - c.xy()).norm();
                    // The band's thinner semi-axis for the sartorius (it
                    // lies flat over the bone's side), the radius of a vessel.
                    if d < bc.r1 + cs.r1.min(cs.r2) {
                        return Err(fail("crosses the bone"));
                    }
                }
            }
        }
    }
    if let Some(e) = node {
        let s = frame::s_of(&e.centre);
        let r = e.semi_axes.max();
        if leg.skin_radius(s, frame::theta_of(&e.centre)) - e.centre.xy().norm() < r {
            return Err(AnatomyError::StructureOutside {
                structure: "lymph_node",
                s,
                problem: "lies outside the leg",
                keys: "{fat_thickness_*, circumference_*}",
            });
        }
    }
    Ok(())
}
