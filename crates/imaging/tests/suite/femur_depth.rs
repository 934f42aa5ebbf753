//! The femur under the probe (issue 21): the bone is rigid and held (the
//! normal springs of the physical model end on it), so pressing the soft
//! tissue above it brings its cortex towards the probe by the compression
//! of the tissue column above it, no more, and no vessel's warp moves it;
//! its shadow begins at the cortex.
//!
//! In the image's column model ([`column_depth`]) the column between the
//! skin, displaced by `s(u)`, and the femur's top `B` is compressed
//! uniformly, and the bone below `B` is not moved: its image depth (below
//! the face, the deepest skin point) is its rest depth less the face's
//! depth. Under a flat face (`s(u)` equal to the face's depth over the
//! femur) the cortex rises by exactly the column's compression `s`.

use crate::common;
use common::*;
use echothigh_imaging::*;

/// Forces (N) and indentations (m): the physical model's (`echothigh image
/// --sweep`, default scenario, main at 33ee31e: 16.06 and 21.26 mm at 10
/// and 15 N) and 25 mm, deeper than the physics reaches at 15 N.
const PRESSES: [(f64, f64); 3] = [(10.0, 16.06e-3), (15.0, 21.26e-3), (15.0, 25e-3)];

/// Depth (m, below the undeformed skin) of the femur's outer surface in
/// the column at lateral `u` (m), if the column crosses it.
fn femur_surface(a: &Anatomy, u: f64) -> Option<f64> {
    let (fu, fd) = a.femur_centre();
    let r = a.config().femur_radius;
    let du = u - fu;
    (du.abs() < r).then(|| fd - (r * r - du * du).sqrt())
}

/// In every vein state, at 10 and 15 N, in every image column over the
/// femur: the cortex's top is drawn where the column puts it, its rest
/// depth less the skin's displacement at the face, to rounding (1e-12 m
/// on depths of ~4e-2 m); at the femur's top that is a rise of `s`, the
/// compression of the column above it. On the pixels, in the column
/// through the femur's top, the shadow begins in the cortex: the first
/// depth below which the echo stays ≥ 15 dB under the muscle beside the
/// femur for 3 mm lies between the cortex's top less 0.5 mm (the axial
/// PSF's reach, ≈ 2 FWHM of 0.2 mm, and a 5-row mean) and its inner
/// surface (the cortex is 5 mm thick; bone attenuates ≈ 30 times more than
/// muscle, so the echo falls through it).
#[test]
fn the_cortex_rises_by_the_compression_above_it_and_shadows_below() {
    let mut cfg = ImagingConfig::default();
    cfg.texture.muscle_fascicles = false;
    let mut failures = Vec::new();
    for state in [VeinState::Healthy, VeinState::Acute, VeinState::Chronic] {
        let mut r = Renderer::new(&cfg, state).unwrap();
        let a = r.anatomy().unwrap().clone();
        let (fu, _) = a.femur_centre();
        let (cortex, top) = (a.config().cortex_thickness, a.femur_top());
        for (force, indentation) in PRESSES {
            let d = press(&r, indentation);
            let input = press_input(&cfg, &d, force, 0.0);
            let frame = r.render(&input).unwrap();
            let face = d.face_depth(0.5 * cfg.probe_width);
            let mut worst: f64 = 0.0;
            for j in 0..cfg.columns {
                let u = r.column_lateral(j);
                if let Some(depth) = femur_surface(&a, u) {
                    worst = worst.max((r.drawn_depth(j, depth) - (depth - face)).abs());
                }
            }
            let jf = ((fu + 0.5 * cfg.width) / cfg.pixel_width()) as usize;
            let rise = top - r.drawn_depth(jf, top);
            let column = d.surface_at(r.column_lateral(jf));
            // The shadow's start on the pixels.
            let z_top = top - face;
            let muscle = mean_db(&cfg, &frame, (-19e-3, -15e-3), (z_top - 3e-3, z_top + 3e-3));
            let dz = cfg.pixel_depth();
            let rows = (3e-3 / dz) as usize;
            let db = |i: usize| {
                let z = i as f64 * dz;
                mean_db(&cfg, &frame, (fu - 0.5e-3, fu + 0.5e-3), (z, z + 5.0 * dz))
            };
            let start = (0..cfg.rows - rows - 5)
                .find(|&i| (i..i + rows).all(|k| db(k) <= muscle - 15.0))
                .map(|i| i as f64 * dz);
            println!(
                "{state:?} {force} N ({:.2} mm): cortex rises {:.3} mm (column compressed {:.3} mm), drawn off its column by {worst:.1e} m, shadow from {:?} mm, cortex {:.2}–{:.2} mm",
                indentation * 1e3,
                rise * 1e3,
                column * 1e3,
                start.map(|s| s * 1e3),
                z_top * 1e3,
                (z_top + cortex) * 1e3
            );
            if worst > 1e-12 || rise > column + 1e-12 {
                failures.push(format!(
                    "{state:?} at {force} N: cortex off by {worst} m, rises {rise} m over {column} m"
                ));
            }
            if !start.is_some_and(|s| (z_top - 0.5e-3..=z_top + cortex).contains(&s)) {
                failures.push(format!(
                    "{state:?} at {force} N: shadow from {start:?} m, cortex at {z_top} m"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
