//! Speckle follows the tissue; frames are deterministic.

use crate::common;
use common::*;
use echothigh_imaging::*;

fn frame_at(r: &mut Renderer, indentation_m: f64) -> Vec<u8> {
    let d = press(r, indentation_m);
    let input = FrameInput {
        deformation: &d,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    };
    r.render(&input).unwrap()
}

/// Normalized cross-correlation of two equally sized patches.
fn ncc(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let mut num = 0.0;
    let (mut va, mut vb) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        num += (x - ma) * (y - mb);
        va += (x - ma).powi(2);
        vb += (y - mb).powi(2);
    }
    num / (va * vb).sqrt()
}

fn patch(
    cfg: &ImagingConfig,
    f: &[u8],
    cols: std::ops::Range<usize>,
    row0: usize,
    rows: usize,
) -> Vec<f64> {
    let mut v = Vec::new();
    for i in row0..row0 + rows {
        for j in cols.clone() {
            v.push(f[i * cfg.columns + j] as f64);
        }
    }
    v
}

#[test]
fn speckle_follows_the_tissue_under_small_compression() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let bone = r.anatomy().unwrap().femur_top();
    // A muscle patch beside the vessels, 20–26 mm below the skin at rest.
    let (cols, _) = region(&cfg, (12e-3, 18e-3), (0.0, 0.0));
    let depth0 = 0.020;
    let rows = (6e-3 / cfg.pixel_depth()) as usize;
    let mut prev = frame_at(&mut r, 4e-3);
    for k in 1..=5 {
        let (s0, s1) = (4e-3 + (k - 1) as f64 * 0.1e-3, 4e-3 + k as f64 * 0.1e-3);
        let next = frame_at(&mut r, s1);
        // Track: where the patch's material went (predicted), then search ±3 rows.
        let z0 = column_depth(s0, bone, depth0) - s0;
        let z1 = column_depth(s1, bone, depth0) - s1;
        let row0 = (z0 / cfg.pixel_depth()).round() as usize;
        let a = patch(&cfg, &prev, cols.clone(), row0, rows);
        let predicted = (z1 / cfg.pixel_depth()).round() as i64;
        let best = (-3..=3)
            .map(|dr| {
                ncc(
                    &a,
                    &patch(&cfg, &next, cols.clone(), (predicted + dr) as usize, rows),
                )
            })
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(best > 0.8, "step {k}: NCC {best}");
        prev = next;
    }
    // A large jump in depth decorrelates (the test can fail).
    let far = frame_at(&mut r, 12e-3);
    let a = patch(&cfg, &prev, cols.clone(), 100, rows);
    let b = patch(&cfg, &far, cols.clone(), 100, rows);
    assert!(ncc(&a, &b) < 0.5);
}

#[test]
fn deterministic_for_a_seed() {
    let cfg = ImagingConfig {
        columns: 96,
        rows: 160,
        ..Default::default()
    };
    let mut a = Renderer::new(&cfg, VeinState::Acute).unwrap();
    let mut b = Renderer::new(&cfg, VeinState::Acute).unwrap();
    let fa = frame_at(&mut a, 5e-3);
    let fb = frame_at(&mut b, 5e-3);
    assert_eq!(fa, fb);
    let other = ImagingConfig { seed: 8, ..cfg };
    let mut c = Renderer::new(&other, VeinState::Acute).unwrap();
    let fc = frame_at(&mut c, 5e-3);
    let differing = fa.iter().zip(&fc).filter(|(x, y)| x != y).count();
    assert!(differing > fa.len() / 2, "only {differing} pixels differ");
}
