//! Lumen area versus probe force per vein state: on the model, and
//! segmented from the image by thresholding.

use crate::common;
use common::*;
use echothigh_imaging::*;

const FORCES: [f64; 6] = [0.0, 2.0, 5.0, 10.0, 15.0, 20.0];

#[test]
fn model_lumen_area_versus_force() {
    let cfg = ImagingConfig::default();
    for state in VeinState::ALL {
        let mut r = Renderer::new(&cfg, state).unwrap();
        let mut last = f64::INFINITY;
        for f in FORCES {
            let d = press(&r, indentation(f));
            let input = FrameInput {
                deformation: &d,
                probe_pressure: f / cfg.probe_area(),
                time: 0.0,
                lateral_offset: 0.0,
            };
            let l = r.lumens(&input).unwrap().unwrap();
            let vein = l.vein.area / l.vein.rest_area;
            let artery = l.artery.area / l.artery.rest_area;
            assert!(vein <= last + 1e-12, "{state:?}: lumen grows with force");
            last = vein;
            // Up to the exam force the artery keeps its shape (the tissue
            // pressure at it stays below its 60 mmHg onset); past it, it
            // ovalises (the pressure cue, tested in `artery_cue.rs`).
            if f <= EXAM_FORCE {
                assert!(artery > 0.8, "{state:?} at {f} N: artery {artery}");
            }
            match state {
                VeinState::Healthy if f >= EXAM_FORCE => {
                    assert!(vein < 0.1, "healthy at {f} N: {vein}")
                }
                VeinState::Healthy if f == 0.0 => assert_eq!(vein, 1.0),
                VeinState::Healthy => {}
                _ => assert!(vein > 0.6, "{state:?} at {f} N: {vein}"),
            }
            // The tissue pressure at the vessels grows with the probe's but stays below it.
            assert!(l.vein.tissue_pressure <= input.probe_pressure + 1e-9);
            r.render(&input).unwrap();
        }
        // A healthy vein is closed at the exam force, and not at 2 N.
        if state == VeinState::Healthy {
            let (_, l) = render_force(&mut r, 2.0, 0.0);
            assert!(l.vein.area / l.vein.rest_area > 0.9);
        }
    }
}

/// Area (m²) of the dark region connected to the lumen's centre
/// ([`dark_region`], `threshold_db` below the muscle) inside a box of the
/// vessel's rest size + 2 mm.
fn segmented_area(
    cfg: &ImagingConfig,
    frame: &[u8],
    l: &Lumen,
    rest_half: f64,
    threshold_db: f64,
) -> f64 {
    dark_region(cfg, frame, l, rest_half + 2e-3, threshold_db).area(cfg)
}

#[test]
fn segmented_lumen_area_versus_force() {
    let cfg = ImagingConfig::default();
    for state in VeinState::ALL {
        let mut r = Renderer::new(&cfg, state).unwrap();
        let vein_half = r.anatomy().unwrap().vein().radius;
        let art_half = r.anatomy().unwrap().artery().radius;
        // Thrombus is echogenic: segment it with a threshold above its echo level.
        let vein_thr = match state {
            VeinState::Chronic => 7.0,
            _ => 10.0,
        };
        let (rest, l0) = render_force(&mut r, 0.0, 0.0);
        let vein0 = segmented_area(&cfg, &rest, &l0.vein, vein_half, vein_thr);
        let art0 = segmented_area(&cfg, &rest, &l0.artery, art_half, 10.0);
        for (seg, model) in [(vein0, l0.vein.rest_area), (art0, l0.artery.rest_area)] {
            assert!(
                (seg / model - 1.0).abs() < 0.35,
                "{state:?}: segmented rest {seg} vs model {model}"
            );
        }
        let (frame, l) = render_force(&mut r, EXAM_FORCE, 0.0);
        let vein = segmented_area(&cfg, &frame, &l.vein, vein_half, vein_thr) / vein0;
        let artery = segmented_area(&cfg, &frame, &l.artery, art_half, 10.0) / art0;
        assert!(artery > 0.8, "{state:?}: segmented artery ratio {artery}");
        match state {
            VeinState::Healthy => assert!(vein < 0.1, "healthy: segmented vein ratio {vein}"),
            _ => assert!(vein > 0.6, "{state:?}: segmented vein ratio {vein}"),
        }
    }
}

#[test]
fn artery_pulses_and_stays_open() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let mut areas = Vec::new();
    for k in 0..20 {
        let (_, l) = render_force(&mut r, EXAM_FORCE, k as f64 * 0.05);
        areas.push(l.artery.area / l.artery.rest_area);
    }
    let max = areas.iter().cloned().fold(0.0, f64::max);
    let min = areas.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        min > 0.8 && max - min > 0.04,
        "artery ratio in [{min}, {max}]"
    );
    // Period 1 s at 60 bpm.
    let (_, a) = render_force(&mut r, 0.0, 0.12);
    let (_, b) = render_force(&mut r, 0.0, 1.12);
    assert!((a.artery.area - b.artery.area).abs() < 1e-12);
}
