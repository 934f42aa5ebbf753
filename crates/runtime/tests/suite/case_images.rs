//! Case images at rest (issue 13): an acute thrombus mostly looks like
//! blood at 0 N (the diagnosis needs compression), the speckle away from
//! the thrombosed veins is unchanged, and every shipped case renders with
//! each segment's state in its vein. Live-size frames (256 × 384).

use echothigh_anatomy::{Anatomy, StructureId, Thrombi, Thrombus};
use echothigh_cases::{builtin, names, Generator};
use echothigh_imaging::{
    FrameInput, ImagingConfig, Renderer, SectionDeformation, Tissue, VeinState,
};
use echothigh_runtime::section_image::section_anatomy_with;

/// The imaging config of the section over the deep vein at `s`, with or
/// without the case's segments.
fn config(a: &Anatomy, t: Option<&Thrombi>, s: f64) -> anyhow::Result<ImagingConfig> {
    let pose = a.pose_over(s, a.deep_vein_at(s))?;
    let mut cfg = ImagingConfig::default().live();
    cfg.anatomy = section_anatomy_with(&cfg.anatomy, a, &pose, t)?;
    Ok(cfg)
}

/// The frame at rest (0 N) and its renderer.
fn render(cfg: &ImagingConfig) -> (Renderer, Vec<u8>) {
    let mut r = Renderer::new(cfg, VeinState::Healthy).unwrap();
    let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    let img = r
        .render(&FrameInput {
            deformation: &rest,
            probe_pressure: 0.0,
            time: 0.0,
            lateral_offset: 0.0,
        })
        .unwrap();
    (r, img)
}

/// Mean gray over the studied vein's lumen (blood or content) shrunk to
/// 80 % of its size (away from the walls' echoes and the PSF's spread).
fn lumen_mean(r: &Renderer, img: &[u8]) -> f64 {
    let a = r.anatomy().unwrap();
    let v = *a.vein();
    let (cols, rows) = r.frame_size();
    let dz = r.config().pixel_depth();
    let (mut sum, mut n) = (0.0, 0usize);
    for j in 0..cols {
        let u = r.column_lateral(j);
        for i in 0..rows {
            let d = (i as f64 + 0.5) * dz;
            let shrunk = echothigh_imaging::Vessel {
                radius: 0.8 * v.radius,
                radius_b: 0.8 * v.radius_b,
                ..v
            };
            if shrunk.contains(u, d, 0.0)
                && matches!(a.tissue_at(u, d), Tissue::VeinLumen | Tissue::Thrombus)
            {
                sum += img[i * cols + j] as f64;
                n += 1;
            }
        }
    }
    assert!(n > 50, "only {n} lumen pixels");
    sum / n as f64
}

/// The first acute segment of a case on a deep vein the section maps as
/// its studied vein (cfv, fv, pv).
fn studied_acute(t: &Thrombi) -> Option<Thrombus> {
    t.segments()
        .iter()
        .find(|x| {
            x.kind.is_acute()
                && matches!(x.vein, StructureId::Cfv | StructureId::Fv | StructureId::Pv)
        })
        .copied()
}

/// Over generated acute cases, the thrombosed lumen's mean brightness at
/// 0 N is within 6 dB of the same lumen filled with blood in ≥ 70 % of
/// them (issue 13). Expected ≈ 87 %: blood shows at the clutter floor
/// (−35 dB re muscle, `BeamConfig::clutter_db`), so content up to ≈ −31 dB
/// stays within 6 dB (10 log10(10^−3.1 + 10^−3.5) + 35 ≈ 5.5 dB); the
/// generator draws 75 % in [−50, −38] dB and 25 % in [−38, −24] dB, half
/// of which lie under −31 dB. Pixels outside the columns through any vein
/// whose condition changed (with a 6 mm margin for the lateral PSF) are
/// identical: the scatterer field outside vessels does not depend on them.
#[test]
fn acute_thrombus_mostly_looks_like_blood_at_rest() {
    let mut g = Generator::new(1.0, 2026).unwrap();
    let (mut close, mut total, mut skipped) = (0, 0, 0);
    while total < 30 {
        let d = g.draw();
        let case = echothigh_cases::from_toml_str(&d.file.to_toml_string()).unwrap();
        let Some(seg) = studied_acute(&case.thrombi) else {
            continue;
        };
        let s = 0.5 * (seg.s_start + seg.s_end);
        let (Ok(with), Ok(without)) = (
            config(&case.anatomy, Some(&case.thrombi), s),
            config(&case.anatomy, None, s),
        ) else {
            skipped += 1; // a section the mapping cannot draw (counted, printed)
            continue;
        };
        let (rt, it) = render(&with);
        let (rh, ih) = render(&without);
        let per_db = 255.0 / with.dynamic_range;
        let diff_db = (lumen_mean(&rt, &it) - lumen_mean(&rh, &ih)) / per_db;
        total += 1;
        close += usize::from(diff_db.abs() <= 6.0);
        // Speckle elsewhere unchanged.
        // The columns through each such vein as drawn in either frame: a
        // patent vein is oval at rest, wider than the round filled one.
        let mut changed: Vec<(f64, f64)> = Vec::new();
        for r in [&rt, &rh] {
            let a = r.anatomy().unwrap();
            changed.push((a.vein().lateral, a.vein().half_width()));
            for (k, st) in with.anatomy.structures.iter().enumerate() {
                if st.condition.is_some() {
                    let v = a.vessels()[k + 2].vessel;
                    changed.push((v.lateral, v.half_width()));
                }
            }
        }
        let (cols, rows) = rt.frame_size();
        for j in 0..cols {
            let u = rt.column_lateral(j);
            if changed.iter().any(|&(l, hw)| (u - l).abs() < hw + 6e-3) {
                continue;
            }
            for i in 0..rows {
                assert_eq!(
                    it[i * cols + j],
                    ih[i * cols + j],
                    "{}: pixel ({j}, {i}) changed",
                    case.name()
                );
            }
        }
    }
    let frac = close as f64 / total as f64;
    eprintln!(
        "{close} of {total} acute lumens within 6 dB of blood ({skipped} sections not drawable)"
    );
    assert!(
        frac >= 0.7,
        "{close} of {total} acute lumens within 6 dB of blood"
    );
}

/// Every shipped case renders at each segment's middle (or, where the
/// section there cannot be drawn — the mapping refuses some levels, e.g.
/// 320–330 mm on the lean male's popliteal vein and 15–25 mm on the obese
/// CFV —, the drawable level inside the segment nearest its middle)
/// and at the fv-mid site, and the vein drawn there carries the segment's
/// state (its smallest lumen ratio).
#[test]
fn every_shipped_case_renders_its_segments() {
    for name in names() {
        let case = builtin(name).unwrap();
        let a = &case.anatomy;
        let fvmid = a.site_pose(echothigh_anatomy::Site::FvMid).s;
        render(
            &config(a, Some(&case.thrombi), fvmid)
                .unwrap_or_else(|e| panic!("{name} at fv-mid: {e:#}")),
        );
        for seg in case.thrombi.segments() {
            let mid = 0.5 * (seg.s_start + seg.s_end);
            // Levels inside the segment (weight 1), nearest the middle first.
            let t = seg.transition;
            let n = ((seg.s_end - seg.s_start - t) / 2.5e-3) as usize;
            let mut levels: Vec<f64> = (0..=n)
                .map(|k| seg.s_start + 0.5 * t + k as f64 * 2.5e-3)
                .collect();
            levels.sort_by(|x, y| (x - mid).abs().total_cmp(&(y - mid).abs()));
            let Some((s, cfg)) = levels
                .into_iter()
                .find_map(|s| config(a, Some(&case.thrombi), s).ok().map(|c| (s, c)))
            else {
                panic!(
                    "{name}: no drawable section on {} within its segment",
                    seg.vein.as_str()
                );
            };
            let (r, img) = render(&cfg);
            assert_eq!(img.len(), r.frame_size().0 * r.frame_size().1);
            // The state at the `s` where the plane cuts this vein.
            let pose = a.pose_over(s, a.deep_vein_at(s)).unwrap();
            let cut = a.section(&pose).unwrap().get(seg.vein).map_or(s, |x| x.s);
            let want = case.thrombi.state(seg.vein, cut).min_lumen_ratio();
            let an = r.anatomy().unwrap();
            let found = an
                .vessels()
                .iter()
                .filter_map(|v| v.condition())
                .any(|c| (c.min_lumen_ratio() - want).abs() < 1e-9);
            assert!(
                found,
                "{name}: no vein with the state of {} at {:.0} mm (min ratio {want})",
                seg.vein.as_str(),
                s * 1e3
            );
        }
    }
}
