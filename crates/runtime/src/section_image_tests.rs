//! The image is a section of the 3D leg: pixel checks at the places the
//! `anatomy` section names (issue 12). Frames at rest (no press) at the
//! live size 256 × 384.

use super::*;
use echothigh_imaging::{
    FrameInput, ImagingConfig, Renderer, SectionDeformation, Tissue, VeinState, Vessel,
};

/// Gray levels per dB of the default display (255 / 72 dB).
fn gray_per_db(cfg: &ImagingConfig) -> f64 {
    255.0 / cfg.dynamic_range
}

/// The renderer and its frame at rest on the lean male, at `at_mm` below
/// the inguinal ligament over the deep vein, or at a site.
fn frame(at_mm: Option<f64>, site: Option<&str>) -> (Renderer, Vec<u8>, Section) {
    let anatomy = Anatomy::new(echothigh_anatomy::Patient::preset("lean-male").unwrap()).unwrap();
    let pose = match (at_mm, site) {
        (_, Some(name)) => anatomy.site_pose(name.parse().unwrap()),
        (Some(mm), None) => {
            let s = mm * 1e-3;
            anatomy.pose_over(s, anatomy.deep_vein_at(s)).unwrap()
        }
        (None, None) => unreachable!("a test gives --at or a site"),
    };
    let mut cfg = ImagingConfig::default().live();
    cfg.anatomy = section_anatomy(&cfg.anatomy, &anatomy, &pose).unwrap();
    let section = anatomy.section(&pose).unwrap();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    let img = r
        .render(&FrameInput {
            deformation: &rest,
            probe_pressure: 0.0,
            time: 0.0,
            lateral_offset: 0.0,
        })
        .unwrap();
    (r, img, section)
}

/// Mean gray of the pixels inside `v`'s lumen scaled by `k` (at rest the
/// image depth is the tissue depth), and how many.
fn mean_in(r: &Renderer, img: &[u8], v: &Vessel, k: f64) -> (f64, usize) {
    let (cols, rows) = r.frame_size();
    let dz = r.config().pixel_depth();
    let shrunk = Vessel {
        radius: k * v.radius,
        radius_b: k * v.radius_b,
        ..*v
    };
    let (mut sum, mut n) = (0.0, 0);
    for j in 0..cols {
        let u = r.column_lateral(j);
        for i in 0..rows {
            if shrunk.contains(u, (i as f64 + 0.5) * dz, 0.0) {
                sum += img[i * cols + j] as f64;
                n += 1;
            }
        }
    }
    (sum / n.max(1) as f64, n)
}

/// Mean gray of the soft tissue (fat or muscle, no vessel) in the ring
/// 1.4 to 2.2 times `v`'s size around it.
fn ring_tissue(r: &Renderer, img: &[u8], v: &Vessel) -> f64 {
    let (cols, rows) = r.frame_size();
    let dz = r.config().pixel_depth();
    let a = r.anatomy().unwrap();
    let grow = |k: f64| Vessel {
        radius: k * v.radius,
        radius_b: k * v.radius_b,
        ..*v
    };
    let (inner, outer) = (grow(1.4), grow(2.2));
    let (mut sum, mut n) = (0.0, 0);
    for j in 0..cols {
        let u = r.column_lateral(j);
        for i in 0..rows {
            let d = (i as f64 + 0.5) * dz;
            let t = a.tissue_at(u, d);
            let soft = matches!(t, Tissue::Fat | Tissue::Muscle);
            if soft && outer.contains(u, d, 0.0) && !inner.contains(u, d, 0.0) {
                sum += img[i * cols + j] as f64;
                n += 1;
            }
        }
    }
    assert!(n > 50, "too few tissue pixels around the vessel");
    sum / n as f64
}

/// The lumen of every vessel the section cuts inside the image is dark
/// against the tissue around it. Lumen echo −50 dB and clutter −35 dB
/// re muscle against fat (−9 dB) or muscle (0 dB): ≥ 26 dB expected;
/// the inner 60 % of the lumen keeps the PSF's skirt (lateral FWHM
/// ≤ 0.6 mm, vessels ≥ 1.8 mm in radius) out. Asserted: ≥ 13 dB, half
/// of it, for the log-speckle's spread over a few hundred pixels.
fn assert_vessels_dark(r: &Renderer, img: &[u8], section: &Section, ids: &[&str]) {
    let db = gray_per_db(r.config());
    let a = r.anatomy().unwrap();
    for id in ids {
        let x = section
            .structures
            .iter()
            .find(|x| x.id.as_str() == *id)
            .unwrap_or_else(|| panic!("the section has no {id}"));
        let v = a
            .vessels()
            .iter()
            .map(|sv| sv.vessel)
            .find(|v| {
                (v.lateral - x.ellipse.lateral).abs() < 1e-9
                    && (v.depth - x.ellipse.depth).abs() < 1e-9
            })
            .unwrap_or_else(|| panic!("{id} is not drawn"));
        let (lumen, n) = mean_in(r, img, &v, 0.6);
        let tissue = ring_tissue(r, img, &v);
        assert!(n > 20, "{id}: {n} lumen pixels");
        assert!(
            tissue - lumen >= 13.0 * db,
            "{id}: lumen {lumen:.0} vs tissue {tissue:.0} gray ({:.1} dB)",
            (tissue - lumen) / db
        );
    }
}

#[test]
fn sfj_shows_the_gsv_joining_the_cfv() {
    let (r, img, section) = frame(None, Some("sfj"));
    assert_vessels_dark(&r, &img, &section, &["gsv", "cfv", "cfa"]);
    // Joined: the band 0.5 mm either side of the segment between the
    // GSV's and the CFV's centres lies in a lumen all along, and each
    // fifth of it (~1.2 mm × 1 mm, several speckle cells) stays at lumen
    // level (tissue less 13 dB, as above): no wall between them.
    let a = r.anatomy().unwrap();
    let g = section.get(StructureId::Gsv).unwrap().ellipse;
    let c = section.get(StructureId::Cfv).unwrap().ellipse;
    let (cols, rows) = r.frame_size();
    let dz = r.config().pixel_depth();
    let tissue = ring_tissue(&r, &img, a.vein());
    let db = gray_per_db(r.config());
    let (eu, ed) = (c.lateral - g.lateral, c.depth - g.depth);
    let len = eu.hypot(ed);
    let mut fifths = [(0.0, 0usize); 5];
    for j in 0..cols {
        let u = r.column_lateral(j);
        for i in 0..rows {
            let d = (i as f64 + 0.5) * dz;
            let t = ((u - g.lateral) * eu + (d - g.depth) * ed) / (len * len);
            let off = ((u - g.lateral) * ed - (d - g.depth) * eu).abs() / len;
            if (0.0..1.0).contains(&t) && off < 0.5e-3 {
                let here = a.tissue_at(u, d);
                assert!(
                    matches!(here, Tissue::VeinLumen | Tissue::Blood),
                    "at {t:.2} of the way GSV→CFV: {here:?}, not lumen"
                );
                let f = &mut fifths[(t * 5.0) as usize];
                f.0 += img[i * cols + j] as f64;
                f.1 += 1;
            }
        }
    }
    for (k, (sum, n)) in fifths.iter().enumerate() {
        let m = sum / *n as f64;
        assert!(
            tissue - m >= 13.0 * db,
            "fifth {k} of the way GSV→CFV: {m:.0} vs tissue {tissue:.0} ({n} px)"
        );
    }
}

#[test]
fn above_the_sfj_no_gsv_and_below_it_a_separate_gsv() {
    // At the CFV site (above the junction) the section has no GSV and
    // where the GSV opens at the SFJ the image shows tissue.
    let (_, _, sfj) = frame(None, Some("sfj"));
    let gsv = sfj.get(StructureId::Gsv).unwrap().ellipse;
    let (r, img, section) = frame(None, Some("cfv"));
    assert!(section.get(StructureId::Gsv).is_none());
    assert_vessels_dark(&r, &img, &section, &["cfv", "cfa"]);
    // The GSV's place at the SFJ, less the CFV grown by 1 mm (the PSF
    // and its wall), is tissue-bright here.
    let a = r.anatomy().unwrap();
    let spot = Vessel::circle(gsv.lateral, gsv.depth, gsv.radii[1], 0.0);
    let (cols, rows) = r.frame_size();
    let dz = r.config().pixel_depth();
    let (mut sum, mut n) = (0.0, 0);
    for j in 0..cols {
        let u = r.column_lateral(j);
        for i in 0..rows {
            let d = (i as f64 + 0.5) * dz;
            if spot.contains(u, d, 0.0) && !a.vein().contains(u, d, 1e-3) {
                sum += img[i * cols + j] as f64;
                n += 1;
            }
        }
    }
    assert!(n > 20, "{n} pixels at the GSV's place");
    let there = sum / n as f64;
    let (lumen, _) = mean_in(&r, &img, a.vein(), 0.6);
    let db = gray_per_db(r.config());
    assert!(
        there - lumen >= 13.0 * db,
        "no GSV at the CFV level, yet {there:.0} vs lumen {lumen:.0}"
    );
    // 14 mm below the SFJ (40 mm) the GSV is its own lumen, in the fat,
    // with tissue between it and the CFV.
    let (r, img, section) = frame(Some(40.0), None);
    assert_vessels_dark(&r, &img, &section, &["gsv"]);
    let g = section.get(StructureId::Gsv).unwrap().ellipse;
    let c = section.get(StructureId::Cfv).unwrap().ellipse;
    let a = r.anatomy().unwrap();
    let between = (0..=40).any(|k| {
        let t = k as f64 / 40.0;
        let u = g.lateral + t * (c.lateral - g.lateral);
        let d = g.depth + t * (c.depth - g.depth);
        matches!(
            a.tissue_at(u, d),
            Tissue::Fat | Tissue::Muscle | Tissue::Fascia
        )
    });
    assert!(between, "no tissue between the GSV and the CFV at 40 mm");
}

#[test]
fn profunda_only_below_its_branch_point() {
    for site in ["cfv", "sfj"] {
        let (r, _, section) = frame(None, Some(site));
        assert!(section.get(StructureId::Dfv).is_none() && section.get(StructureId::Dfa).is_none());
        // Nothing drawn beyond the section's vessels.
        assert_eq!(
            r.anatomy().unwrap().vessels().len(),
            section
                .structures
                .iter()
                .filter(|x| x.kind.is_vessel())
                .count()
        );
    }
    let (r, img, section) = frame(None, Some("fv-proximal"));
    assert_vessels_dark(&r, &img, &section, &["fv", "fa", "dfv", "dfa"]);
}
