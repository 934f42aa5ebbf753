//! The anatomy is fixed in the thigh, the image centred on the probe:
//! sliding the probe across the thigh pans the anatomy across the image
//! (exactly, column for column), and a probe far from the vessels neither
//! images nor compresses them.

use crate::common;
use common::*;
use echothigh_imaging::*;

/// A small frame without clutter and noise: those are fixed to the probe
/// (body-wall reverberation, electronics), not to the tissue, so only the
/// tissue echoes pan exactly.
fn small() -> ImagingConfig {
    ImagingConfig {
        columns: 128,
        rows: 192,
        beam: BeamConfig {
            noise_db: -200.0,
            clutter_db: -200.0,
            ..Default::default()
        },
        ..ImagingConfig::default()
    }
}

fn input<'a>(
    d: &'a SectionDeformation,
    force: f64,
    cfg: &ImagingConfig,
    offset: f64,
) -> FrameInput<'a> {
    FrameInput {
        deformation: d,
        probe_pressure: force / cfg.probe_area(),
        time: 0.0,
        lateral_offset: offset,
    }
}

#[test]
fn panning_shifts_the_frame_column_for_column() {
    let cfg = small();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    let dx = cfg.pixel_width();
    let a = r.render(&input(&rest, 0.0, &cfg, 0.0)).unwrap();
    let la = r.lumens(&input(&rest, 0.0, &cfg, 0.0)).unwrap().unwrap();
    for k in [1usize, 17, 40] {
        let offset = k as f64 * dx;
        let b = r.render(&input(&rest, 0.0, &cfg, offset)).unwrap();
        for i in 0..cfg.rows {
            let row = i * cfg.columns;
            assert_eq!(
                &b[row..row + cfg.columns - k],
                &a[row + k..row + cfg.columns],
                "row {i}, pan {k} columns"
            );
        }
        let lb = r.lumens(&input(&rest, 0.0, &cfg, offset)).unwrap().unwrap();
        assert!((lb.vein.lateral - (la.vein.lateral - offset)).abs() < 1e-12);
        assert!((lb.artery.lateral - (la.artery.lateral - offset)).abs() < 1e-12);
    }
    // Back at zero pan the frame is the first one again.
    assert_eq!(r.render(&input(&rest, 0.0, &cfg, 0.0)).unwrap(), a);
}

/// Mean gray level of each column over the rows of the band `[d0, d1]` (m below the face).
fn band_means(cfg: &ImagingConfig, f: &[u8], d0: f64, d1: f64) -> Vec<f64> {
    let (r0, r1) = (
        (d0 / cfg.pixel_depth()) as usize,
        (d1 / cfg.pixel_depth()) as usize,
    );
    (0..cfg.columns)
        .map(|j| {
            (r0..r1)
                .map(|i| f64::from(f[i * cfg.columns + j]))
                .sum::<f64>()
                / (r1 - r0) as f64
        })
        .collect()
}

#[test]
fn a_probe_far_from_the_vessels_neither_images_nor_compresses_them() {
    let cfg = small();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let a = cfg.anatomy.clone();
    let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    let band = (
        a.vein_depth - 0.25 * a.vein_diameter,
        a.vein_depth + 0.25 * a.vein_diameter,
    );
    let darkest = |f: &[u8]| {
        let m = band_means(&cfg, f, band.0, band.1);
        let mut sorted = m.clone();
        sorted.sort_by(f64::total_cmp);
        (sorted[0], sorted[sorted.len() / 2])
    };
    // Over the vessels: the vein's lumen is an anechoic gap in the band.
    let (min0, median0) = darkest(&r.render(&input(&rest, 0.0, &cfg, 0.0)).unwrap());
    assert!(
        min0 < 0.3 * median0,
        "vein imaged at zero pan: {min0} vs {median0}"
    );
    for offset in [0.035, -0.035] {
        let f = r.render(&input(&rest, 0.0, &cfg, offset)).unwrap();
        let (min, median) = darkest(&f);
        assert!(
            min > 0.5 * median,
            "no vessel at {offset} m: {min} vs {median}"
        );
        let l = r.lumens(&input(&rest, 0.0, &cfg, offset)).unwrap().unwrap();
        assert!(l.vein.lateral.abs() > 0.5 * cfg.width + 0.5 * a.vein_diameter);
    }
    // The exam force that closes the vein under the probe leaves it open
    // 35 mm away: the stress under the face decays laterally.
    let d = press(&r, indentation(EXAM_FORCE));
    let here = r
        .lumens(&input(&d, EXAM_FORCE, &cfg, 0.0))
        .unwrap()
        .unwrap();
    let away = r
        .lumens(&input(&d, EXAM_FORCE, &cfg, 0.035))
        .unwrap()
        .unwrap();
    assert!(here.vein.area / here.vein.rest_area < 0.1);
    assert!(
        away.vein.area / away.vein.rest_area > 0.8,
        "vein 35 mm away: ratio {}",
        away.vein.area / away.vein.rest_area
    );
    assert!(away.vein.tissue_pressure < 0.3 * here.vein.tissue_pressure);
}

#[test]
fn pan_is_quantized_to_columns_and_clamped_to_the_range() {
    let cfg = small();
    let r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let dx = cfg.pixel_width();
    let p = cfg.pan_columns() as isize;
    assert_eq!(p, (cfg.pan_range / dx).floor() as isize);
    assert_eq!(r.pan(0.0), (0.0, 0));
    assert_eq!(r.pan(0.4 * dx), (0.0, 0));
    assert_eq!(r.pan(0.6 * dx).1, 1);
    assert_eq!(r.pan(-2.6 * dx).1, -3);
    assert_eq!(r.pan(1.0).1, p);
    assert_eq!(r.pan(-1.0).1, -p);
    assert!((r.pan(1.0).0 - p as f64 * dx).abs() < 1e-15);
    // A non-finite offset is an input error naming the field.
    let rest = SectionDeformation::rest(0.04);
    let e = r.lumens(&input(&rest, 0.0, &cfg, f64::NAN)).unwrap_err();
    assert!(e.to_string().contains("lateral_offset"), "{e}");
}
