//! The imaging anatomy of a section of the 3D leg: from an
//! [`echothigh_anatomy::Section`] under a probe to the B-mode renderer's
//! [`AnatomyConfig`] (used by `echothigh image --site/--at` and by the live
//! imaging thread as the probe walks along the leg).
//!
//! The renderer draws the studied vein–artery pair over the femur, with the
//! skin, fat, fascia and muscle layers, and the section's other structures;
//! this module fills those from the section: the deep vein of the level
//! (`cfv`, `fv` or `pv`) and its companion artery (`cfa`, `fa`, `pa`) with
//! their position, depth and area-equivalent diameter (`2 √(a b)` of the cut
//! ellipse, which keeps the lumen's area when the plane is oblique), the
//! femur's position and radius, the skin's and the fascia's depth; and every
//! other structure the plane cuts (GSV, profunda vein and artery, a
//! duplicated femoral vein, sartorius, a lymph node) as its cut ellipse in
//! `structures` (veins with the healthy lumen law, arteries with the artery
//! law, the sartorius as a muscle outline). All lengths in metres.
//!
//! With a case's thrombus segments ([`section_anatomy_with`], issue 13),
//! every vein drawn — the studied one and those of `structures` — carries
//! its own condition: the segments' state at the `s` where the plane cuts
//! that vein ([`crate::section_condition`]).

use crate::section_condition::{pattern_seed, vein_condition};
use anyhow::{Context, Result};
use echothigh_anatomy::{Anatomy, Kind, ProbePose, Section, StructureId, Thrombi};
use echothigh_imaging::{AnatomyConfig, StructureConfig, StructureKind};

/// The companion artery of a deep vein.
fn artery_of(vein: StructureId) -> StructureId {
    match vein {
        StructureId::Cfv => StructureId::Cfa,
        StructureId::Fv => StructureId::Fa,
        _ => StructureId::Pa,
    }
}

/// `base` with its layers, vessels and femur taken from `anatomy`'s
/// section under the probe at `pose` (validated with the prefix
/// `imaging.anatomy`: a section the renderer cannot draw, e.g. a vessel
/// beyond ±50 mm of the probe's centre, is refused naming the key).
pub fn section_anatomy(
    base: &AnatomyConfig,
    anatomy: &Anatomy,
    pose: &ProbePose,
) -> Result<AnatomyConfig> {
    section_anatomy_with(base, anatomy, pose, None)
}

/// As [`section_anatomy`], with each vein's condition from `thrombi` (a
/// case's segments on this anatomy) at the `s` where the plane cuts it;
/// `None` or no segment there leaves a vein healthy (and the studied vein
/// to the renderer's global `VeinState`).
pub fn section_anatomy_with(
    base: &AnatomyConfig,
    anatomy: &Anatomy,
    pose: &ProbePose,
    thrombi: Option<&Thrombi>,
) -> Result<AnatomyConfig> {
    let section = anatomy.section(pose)?;
    let vein_id = studied_vein(&section, anatomy.deep_vein_at(pose.s), pose.s);
    let cut = |id: StructureId| -> Result<(f64, f64, f64)> {
        let x = section.get(id).with_context(|| {
            format!(
                "the section at s = {:.1} mm does not cut `{}`: aim the probe at it (--angle)",
                pose.s * 1e3,
                id.as_str()
            )
        })?;
        let e = &x.ellipse;
        Ok((e.lateral, e.depth, 2.0 * (e.radii[0] * e.radii[1]).sqrt()))
    };
    let (vl, vd, vdia) = cut(vein_id)?;
    let artery = drawn_artery(&section, vein_id, pose.s);
    let (al, ad, adia) = cut(artery)?;
    // Below the knee joint the femur has ended: the tibia is the bone
    // under the popliteal vessels down to the trifurcation.
    let bone =
        if section.get(StructureId::Femur).is_none() && section.get(StructureId::Tibia).is_some() {
            StructureId::Tibia
        } else {
            StructureId::Femur
        };
    let (fl, fd, fdia) = cut(bone)?;
    let femur_r = 0.5 * fdia;
    let mut c = base.clone();
    c.skin_thickness = section.skin_depth;
    c.fat_thickness = section.fascia_depth - section.skin_depth;
    c.vein_lateral = vl;
    c.vein_depth = vd;
    c.vein_diameter = vdia;
    c.artery_lateral = al;
    c.artery_depth = ad;
    c.artery_diameter = adia;
    c.femur_lateral = fl;
    c.femur_radius = femur_r;
    c.muscle_thickness = fd - femur_r - section.fascia_depth;
    c.intermuscular_fascia_depth = intermuscular(&section, c.intermuscular_fascia_depth)
        .min(c.femur_top() - FASCIA_CLEARANCE)
        .max(c.skin_thickness + c.fat_thickness + FASCIA_CLEARANCE);
    c.structures = extra_structures(&section, &[vein_id, artery], base, thrombi);
    c.vein_condition = thrombi.and_then(|t| {
        let s = section.get(vein_id).map_or(pose.s, |x| x.s);
        vein_condition(&t.state(vein_id, s), base, pattern_seed(vein_id))
    });
    c.validate("imaging.anatomy").with_context(|| {
        format!(
            "the section at s = {:.1} mm, angle {:.1}° cannot be drawn",
            pose.s * 1e3,
            pose.theta.to_degrees()
        )
    })?;
    Ok(c)
}

/// Least distance (m) of the intermuscular fascia line from the muscle
/// layer's top and from the femur: 1 mm. Beside the popliteal fossa the
/// sartorius' deep surface lies deeper than the femur's top under the
/// probe; the one fascia line the renderer draws then stays just above the
/// femur (the layered section has one line; the sartorius itself is drawn
/// as its own outline).
const FASCIA_CLEARANCE: f64 = 1e-3;

/// The deep vein to draw as the studied one: `level` (the deep vein at the
/// probe's `s`) when the plane cuts it, else the deep vein the plane cuts
/// nearest `s` (an oblique plane just past a level's boundary — the
/// confluence, the adductor hiatus — cuts the previous vein at depth).
fn studied_vein(section: &Section, level: StructureId, s: f64) -> StructureId {
    if section.get(level).is_some() {
        return level;
    }
    nearest_cut(
        section,
        &[StructureId::Cfv, StructureId::Fv, StructureId::Pv],
        s,
    )
    .unwrap_or(level)
}

/// The artery drawn with the studied vein `vein_id` in `section` (at the
/// probe's `s`): its companion, except between the CFA's bifurcation and
/// the profunda's confluence, where the CFV runs with the (superficial)
/// femoral artery (the CFA has ended), or the nearest artery the plane cuts.
fn drawn_artery(section: &Section, vein_id: StructureId, s: f64) -> StructureId {
    match artery_of(vein_id) {
        StructureId::Cfa if section.get(StructureId::Cfa).is_none() => StructureId::Fa,
        a if section.get(a).is_none() => nearest_cut(
            section,
            &[StructureId::Cfa, StructureId::Fa, StructureId::Pa],
            s,
        )
        .unwrap_or(a),
        a => a,
    }
}

/// The ids of the vessels a renderer built from [`section_anatomy_with`]'s
/// config `config` draws, in its order (`echothigh_imaging::Anatomy::vessels`:
/// the studied vein, its artery, then the extra vessels), from `section`
/// at the probe's `s`; an extra vessel whose name is no structure's id is
/// `None`.
pub fn vessel_ids(
    section: &Section,
    s: f64,
    level_vein: StructureId,
    config: &AnatomyConfig,
) -> Vec<Option<StructureId>> {
    let vein = studied_vein(section, level_vein, s);
    let mut ids = vec![Some(vein), Some(drawn_artery(section, vein, s))];
    ids.extend(
        config
            .structures
            .iter()
            .filter(|x| matches!(x.kind, StructureKind::Vein | StructureKind::Artery))
            .map(|x| {
                section
                    .structures
                    .iter()
                    .map(|y| y.id)
                    .find(|id| id.as_str() == x.name)
            }),
    );
    ids
}

/// Of `ids`, the one the section cuts at the `s` nearest `s`.
fn nearest_cut(section: &Section, ids: &[StructureId], s: f64) -> Option<StructureId> {
    section
        .structures
        .iter()
        .filter(|x| ids.contains(&x.id))
        .min_by(|a, b| (a.s - s).abs().total_cmp(&(b.s - s).abs()))
        .map(|x| x.id)
}

/// Depth (m) of the sartorius' deep surface when the section cuts it (the
/// adductor canal's roof), else `fallback`.
fn intermuscular(section: &Section, fallback: f64) -> f64 {
    section
        .get(StructureId::Sartorius)
        .map(|x| x.ellipse.depth + x.ellipse.radii[0].min(x.ellipse.radii[1]))
        .unwrap_or(fallback)
}

/// Every structure of `section` but `drawn` (the studied pair) and the
/// bones, as the renderer's extra structures; structures beyond the
/// renderer's reach (more than 200 mm aside or 250 mm deep) are left out.
fn extra_structures(
    section: &Section,
    drawn: &[StructureId],
    base: &AnatomyConfig,
    thrombi: Option<&Thrombi>,
) -> Vec<StructureConfig> {
    section
        .structures
        .iter()
        .filter(|x| !drawn.contains(&x.id))
        .filter_map(|x| {
            let (kind, wall) = match x.kind {
                Kind::DeepVein | Kind::SuperficialVein => {
                    (StructureKind::Vein, base.healthy.wall_thickness)
                }
                Kind::Artery => (StructureKind::Artery, base.artery_wall_thickness),
                Kind::Muscle => (StructureKind::Muscle, 0.0),
                Kind::LymphNode => (StructureKind::LymphNode, 0.0),
                Kind::Bone => return None,
            };
            let e = &x.ellipse;
            let st = StructureConfig {
                name: x.id.as_str().to_string(),
                kind,
                lateral: e.lateral,
                depth: e.depth,
                radii: e.radii,
                angle: e.angle,
                wall,
                condition: match (x.kind, thrombi) {
                    (Kind::DeepVein | Kind::SuperficialVein, Some(t)) => {
                        vein_condition(&t.state(x.id, x.s), base, pattern_seed(x.id))
                    }
                    _ => None,
                },
            };
            st.validate("imaging.anatomy.structure").ok().map(|_| st)
        })
        .take(echothigh_imaging::MAX_STRUCTURES)
        .collect()
}

#[cfg(test)]
#[path = "section_image_tests.rs"]
mod tests;
