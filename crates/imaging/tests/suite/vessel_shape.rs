//! The shapes the vessels take under the probe (issue 21, "vessels that
//! deform as they do"): an oval vein at rest that flattens about its own
//! axis into a lens and then a bright line of coapted walls, and an artery
//! that stays round until its pressure cue.
//!
//! Shapes are measured on the rendered pixels (the extent of the dark
//! region around the vessel) and on the lumen geometry the renderer
//! reports ([`Renderer::lumens`]).
//!
//! The shapes on the pixels are measured with plain muscle speckle around
//! the vessels ([`plain_muscle`]): the dark region is thresholded against
//! muscle's mean, and the starry sky (`texture.muscle_fascicles`, a
//! background 1.5 dB darker carrying sparse +15 dB dots) moves that
//! threshold's meaning from region to region. With it on, the artery's
//! measured aspect at 10 N read 1.12 of rest against the 1.10 bound
//! (2026-11-27), with its lumen geometry exactly round: the measurement,
//! not the vessel, changed. The lumen geometry tests do not depend on it.

use crate::common;
use common::*;
use echothigh_imaging::*;

/// The default configuration without the starry sky (see the module's comment).
fn plain_muscle() -> ImagingConfig {
    let mut cfg = ImagingConfig::default();
    cfg.texture.muscle_fascicles = false;
    cfg
}

/// Extent `(width, height)` (m) of the dark region connected to the
/// lumen's reported centre ([`dark_region`]: thresholded 10 dB below the
/// muscle beside the vessels, the threshold of `lumen.rs`) inside a box of
/// the vessel's rest half-width (or its widened one, if larger) + 2 mm.
/// `None` if the centre is not dark.
fn dark_extent(cfg: &ImagingConfig, frame: &[u8], l: &Lumen, rest_half: f64) -> Option<(f64, f64)> {
    dark_region(cfg, frame, l, rest_half.max(l.half_width) + 2e-3, 10.0).extent
}

/// Forces (N) of a slow press, 0 to 20 N.
fn forces() -> impl Iterator<Item = f64> {
    (0..=40).map(|k| 0.5 * k as f64)
}

/// Width over height of a reported lumen (∞ when flat).
fn aspect(l: &Lumen) -> f64 {
    l.half_width / l.half_height
}

#[test]
fn vein_is_oval_at_rest_and_artery_round() {
    let cfg = plain_muscle();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, l) = render_force(&mut r, 0.0, 0.0);
    // The geometry: the documented estimate for a patent vein, 1.2–1.5
    // (`VEIN_REST_ASPECT`), and a round artery.
    let v = aspect(&l.vein);
    assert!((1.2..=1.5).contains(&v), "rest vein aspect {v}");
    assert!((aspect(&l.artery) - 1.0).abs() < 1e-9);
    // On the pixels: the dark region's extent. Its width and height are
    // each off by the blur at the threshold, under 1 mm (the lateral PSF
    // at 30 mm is ≈ 0.5 mm wide, the 5-pixel smoothing 0.4 mm); on a
    // ~10 mm lumen that moves the aspect by < 0.2, so a rest vein measured
    // ≥ 1.15 is oval and an artery within 0.85–1.15 is round.
    let a = r.anatomy().unwrap();
    let (vw, vh) = dark_extent(&cfg, &frame, &l.vein, a.vein().half_width()).unwrap();
    let (aw, ah) = dark_extent(&cfg, &frame, &l.artery, a.artery().half_width()).unwrap();
    assert!(vw / vh >= 1.15, "rest vein on the image {vw} × {vh} m");
    assert!(
        (aw / ah - 1.0).abs() < 0.15,
        "rest artery on the image {aw} × {ah} m"
    );
}

#[test]
fn compressed_vein_flattens_about_its_axis_and_keeps_its_width() {
    let cfg = plain_muscle();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let rest_half = r.anatomy().unwrap().vein().half_width();
    let (rest_frame, l0) = render_force(&mut r, 0.0, 0.0);
    let (w0, h0) = dark_extent(&cfg, &rest_frame, &l0.vein, rest_half).unwrap();
    let mut last = 0.0;
    let mut last_pixels = 0.0;
    let mut measured = 0;
    for f in forces() {
        let (frame, l) = render_force(&mut r, f, 0.0);
        let c = l.vein.area / l.vein.rest_area;
        if c <= 0.0 {
            break;
        }
        // The reported lumen: the aspect rises with every step of force (to
        // rounding, 1e-9)
        // (its height scales by c, its width stays), and the centre stays
        // where the column puts the vessel's axis: it does not sink onto
        // the lower wall. At rest the centre is at the axis; the column
        // map `y = d + s (1 − d/B)` moves it to `d + s (1 − d/B)`.
        let a = aspect(&l.vein);
        assert!(a >= last - 1e-9, "aspect falls at {f} N: {a} < {last}");
        last = a;
        let s = indentation(f);
        let bone = r.anatomy().unwrap().femur_top();
        let v = r.anatomy().unwrap().vein();
        let axis = v.depth + s * (1.0 - v.depth / bone) - s;
        assert!(
            (l.vein.depth - axis).abs() < 1e-9,
            "centre off the axis at {f} N"
        );
        // On the pixels, while the lumen is taller than the blur (c ≥ 0.3:
        // 2.6 mm of a 8.8 mm rest height): the width stays ≥ 80 % of
        // rest and the aspect rises, up to one pixel of quantisation on
        // the height (0.078 mm of ≥ 2.6 mm, 3 %) plus the speckle at the
        // threshold's edge (a 5 × 5 mean of ~3 speckle cells: ±1 pixel on
        // each of width and height), so within 8 % of the previous force's.
        if c >= 0.3 {
            let (w, h) = dark_extent(&cfg, &frame, &l.vein, rest_half).unwrap();
            assert!(w >= 0.8 * w0, "width {w} m at {f} N, rest {w0} m");
            let ap = w / h;
            assert!(
                ap >= 0.92 * last_pixels,
                "image aspect falls at {f} N: {ap}"
            );
            last_pixels = ap;
            measured += 1;
            if c <= 0.5 {
                assert!(ap > 1.5 * w0 / h0, "not a lens at {f} N: {w} × {h} m");
            }
        }
    }
    assert!(measured >= 4, "too few open frames measured: {measured}");
    assert!(last > 2.0 * aspect(&l0.vein), "the vein never flattened");
}

#[test]
fn coapted_walls_leave_a_bright_line() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, l) = render_force(&mut r, EXAM_FORCE, 0.0);
    assert_eq!(l.vein.area, 0.0, "closed at the exam force");
    // The line: the two walls (0.5 mm each, +4 dB over muscle) meet on the
    // axis, 1 mm thick, blurred by the axial PSF (≈ 0.3 mm); averaged over
    // ±0.4 mm in depth and the middle 60 % of the vein's width it is ~+3
    // dB, over ~20 speckle cells (a mean's spread ≈ 5.6/√20 ≈ 1.3 dB). The
    // muscle beside is averaged over a 7 × 6 mm box (spread < 0.5 dB). The
    // line must stand ≥ 1 dB above it: an image where the walls vanish
    // (anechoic blood or muscle at the axis) fails.
    let half = 0.6 * l.vein.half_width;
    let line = mean_db(
        &cfg,
        &frame,
        (l.vein.lateral - half, l.vein.lateral + half),
        (l.vein.depth - 0.4e-3, l.vein.depth + 0.4e-3),
    );
    let muscle = mean_db(
        &cfg,
        &frame,
        (12e-3, 19e-3),
        (l.vein.depth - 3e-3, l.vein.depth + 3e-3),
    );
    println!("coapted line {:.1} dB over muscle", line - muscle);
    assert!(line > muscle + 1.0, "line {line} dB, muscle {muscle} dB");
}

#[test]
fn artery_stays_round_below_its_cue_then_ovalises() {
    let cfg = plain_muscle();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let onset = r.anatomy().unwrap().config().artery_collapse_onset;
    let rest_half = r.anatomy().unwrap().artery().half_width();
    let (rest_frame, l0) = render_force(&mut r, 0.0, 0.0);
    let (w0, h0) = dark_extent(&cfg, &rest_frame, &l0.artery, rest_half).unwrap();
    let mut ovalised = false;
    for f in forces() {
        let (frame, l) = render_force(&mut r, f, 0.0);
        let a = aspect(&l.artery);
        if l.artery.tissue_pressure < onset {
            // Below the cue the reported lumen is round (within rounding).
            assert!((a - 1.0).abs() < 1e-6, "artery aspect {a} at {f} N");
            // On the image: within 10 % of its rest aspect (the bound of
            // the issue; the same blur at the same threshold applies to
            // both frames, and ±1 pixel of 7 mm on each side is ±2 %).
            if f.rem_euclid(5.0) == 0.0 {
                let (w, h) = dark_extent(&cfg, &frame, &l.artery, rest_half).unwrap();
                let rel = (w / h) / (w0 / h0);
                assert!(
                    (rel - 1.0).abs() < 0.1,
                    "artery on the image at {f} N: {rel}"
                );
            }
        } else if a > 1.1 {
            ovalised = true;
        }
    }
    assert!(ovalised, "the artery never ovalised within 20 N");
}

/// Width and height (m) of the dark run through the lumen's reported
/// centre along its row and its column, with the smoothing and threshold of
/// [`dark_extent`]. Through the centre only: here the artery's dark region
/// joins the refraction edge shadow beside it (the flood fill's box read
/// 8.2 mm wide for a 7 mm lumen at rest, 7.7 mm at 5 N as the shadow
/// moved), which is not the lumen's shape.
fn centre_extent(cfg: &ImagingConfig, frame: &[u8], l: &Lumen) -> (f64, f64) {
    let (w, h) = (cfg.columns, cfg.rows);
    let limit = dark_limit(cfg, frame, l, 10.0);
    let dark = |j: usize, i: usize| smoothed_intensity(cfg, frame, j, i) < limit;
    let j = ((l.lateral + 0.5 * cfg.width) / cfg.pixel_width()) as usize;
    let i = (l.depth / cfg.pixel_depth()) as usize;
    let run = |step: &dyn Fn(usize, isize) -> Option<(usize, usize)>| {
        let mut n = 0;
        for dir in [-1isize, 1] {
            let mut k = 1;
            while let Some((jj, ii)) = step(k, dir) {
                if !dark(jj, ii) {
                    break;
                }
                n += 1;
                k += 1;
            }
        }
        n + 1
    };
    let across = run(&|k, d| {
        let jj = j as isize + d * k as isize;
        (0..w as isize).contains(&jj).then_some((jj as usize, i))
    });
    let down = run(&|k, d| {
        let ii = i as isize + d * k as isize;
        (0..h as isize).contains(&ii).then_some((j, ii as usize))
    });
    (
        across as f64 * cfg.pixel_width(),
        down as f64 * cfg.pixel_depth(),
    )
}

/// An artery lying on the vein (as at the groin in `cfv-free-floating`,
/// 130 mm, where it rests 0.08 mm above the vein's wall) stays round on
/// the image while the vein collapses under it, below its own cue: the
/// vein's collapse carries it down whole (`crate::carry`) instead of
/// stretching it into a teardrop towards the vein. Without the carriage
/// its measured aspect fell to 0.744 of rest at 6 N (0.948 at 4 N; its
/// near half pulled down with the vein's wall, its far half left; run on
/// 2026-11-27); with it, 0.979–1.045 from 2 to 8 N. The same teardrop's
/// tip, in the vein's window, failed `runtime/tests/case_compression`.
#[test]
fn an_artery_on_the_vein_stays_round_as_the_vein_collapses() {
    let mut cfg = plain_muscle();
    cfg.reverberation.enabled = false;
    let a = &mut cfg.anatomy;
    // The default vein (10 mm, oval 1.3: half-height 4.39 mm, wall
    // 0.5 mm) with the artery (7 mm, wall 0.7 mm) 1 mm lateral and 0.1 mm
    // above it, wall to wall.
    let vein_top = a.vein_depth - 0.5 * a.vein_diameter / 1.3f64.sqrt() - 0.5e-3;
    a.artery_lateral = a.vein_lateral + 1e-3;
    a.artery_depth = vein_top - 0.1e-3 - a.artery_wall_thickness - 0.5 * a.artery_diameter;
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let onset = r.anatomy().unwrap().config().artery_collapse_onset;
    let (rest_frame, l0) = render_force(&mut r, 0.0, 0.0);
    let (w0, h0) = centre_extent(&cfg, &rest_frame, &l0.artery);
    let mut collapsed = false;
    for f in [2.0, 4.0, 6.0, 8.0, 10.0] {
        let (frame, l) = render_force(&mut r, f, 0.0);
        if l.artery.tissue_pressure >= onset {
            continue;
        }
        collapsed |= l.vein.area < 0.5 * l.vein.rest_area;
        // The reported lumen: round, and as tall as at rest (the carriage
        // translates it; within rounding).
        assert!((aspect(&l.artery) - 1.0).abs() < 1e-6, "report at {f} N");
        // On the image: within 10 % of its rest aspect, the bound of
        // `artery_stays_round_below_its_cue_then_ovalises` (same blur and
        // threshold in both frames; ±1 pixel of 7 mm per side is ±2 %),
        // measured through its centre (`centre_extent`).
        let (w, h) = centre_extent(&cfg, &frame, &l.artery);
        let rel = (w / h) / (w0 / h0);
        println!(
            "artery on the vein at {f} N: aspect {rel:.3} of rest, vein area {:.2}",
            l.vein.area / l.vein.rest_area
        );
        assert!(
            (rel - 1.0).abs() < 0.1,
            "artery on the image at {f} N: {rel}"
        );
    }
    assert!(collapsed, "the vein never halved below the artery's cue");
}

#[test]
fn compressed_vein_widens_as_its_wall_keeps_its_length() {
    let cfg = plain_muscle();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (v, art) = {
        let a = r.anatomy().unwrap();
        (*a.vein(), *a.artery())
    };
    let (a, b) = (v.half_width(), v.half_height());
    let perimeter = ellipse_perimeter(v.radius, v.radius_b);
    let (rest_frame, l0) = render_force(&mut r, 0.0, 0.0);
    let (w0, _) = dark_extent(&cfg, &rest_frame, &l0.vein, a).unwrap();
    let (mut last_half, mut last_px) = (a, w0);
    let (mut measured, mut compared) = (0, 0);
    for f in forces() {
        let (frame, l) = render_force(&mut r, f, 0.0);
        let area = l.vein.area / l.vein.rest_area;
        if area <= 0.0 {
            break;
        }
        // The reported lumen: its height ratio in space (the warp is
        // compensated for the column's strain), the law's area and, while
        // no edge is at its cap (the medial cap, 4.1 mm, binds below
        // c ≈ 0.1), the rest wall's length; all to the bisections'
        // 2⁻⁴⁰ of their brackets (≈ 1e-12 relative), so within 1e-9.
        let c = l.vein.half_height / b;
        let (hw, hh) = (l.vein.half_width, l.vein.half_height);
        assert!((hw * hh / (a * b) - area).abs() < 1e-9, "area at {f} N");
        if c >= 0.15 && area < 1.0 {
            let p = ellipse_perimeter(hw, hh);
            assert!(
                (p / perimeter - 1.0).abs() < 1e-9,
                "perimeter at {f} N: {p}"
            );
        }
        // Wider with every step of force.
        assert!(
            hw >= last_half - 1e-12,
            "narrower at {f} N: {hw} < {last_half}"
        );
        last_half = hw;
        // On the pixels, while the lumen is taller than the blur (c ≥ 0.3,
        // as in `compressed_vein_flattens_about_its_axis_and_keeps_its_width`).
        // Each lateral edge is where the 5 × 5 mean crosses the threshold
        // on the wall's flank; the 5 × 5 window holds about one speckle
        // cell, so the crossing moves with the speckle (which changes as
        // the column compresses) by up to half the lateral PSF's FWHM,
        // ±0.22 mm (0.44 mm at 30 mm), per edge. The width then never
        // falls by more than 0.44 mm from one force to the next (measured:
        // 0.23 mm between 1 and 1.5 N, the lumen still round).
        if c >= 0.3 {
            let (w, _) = dark_extent(&cfg, &frame, &l.vein, a).unwrap();
            println!(
                "{f:4.1} N: c = {c:.2}, image width {:.2} mm, model {:.2} mm",
                w * 1e3,
                2e3 * hw
            );
            assert!(
                w >= last_px - 0.44e-3,
                "image width falls at {f} N: {w} < {last_px}"
            );
            last_px = w;
            measured += 1;
            // At mid compression the widening on the image is the law's,
            // 2 (a' − a) = 3.1–3.9 mm for c = 0.5–0.3, within 0.7 mm: the
            // four edges of the two frames, each ±0.22 mm of speckle
            // (0.44 mm in quadrature; the blur at the threshold is the same
            // in both frames and cancels), and the lens's tips, thinner
            // than the axial PSF and smoothing (≈ 0.45 mm) over the last
            // 1.5 % of a' for c b ≥ 1.3 mm, reading up to 0.24 mm short.
            if c <= 0.5 {
                let want = 2.0 * (hw - a);
                let got = w - w0;
                println!("  widening {:.2} mm, law {:.2} mm", got * 1e3, want * 1e3);
                assert!(
                    (got - want).abs() < 0.7e-3,
                    "widening {got} m, law {want} m at {f} N"
                );
                compared += 1;
            }
        }
        // The artery below its cue: untouched by the vein's widening (its
        // report exactly at rest: width and centre; its shape on the image
        // is `artery_stays_round_below_its_cue_then_ovalises`'s). The dark
        // region's box on the image is no measure of its position: at rest
        // it reaches towards the vein (9.5 mm for a 7 mm lumen) and at
        // 3.5 N its lateral edge read 1.6 mm further out, so it is not
        // compared.
        if l.artery.tissue_pressure < r.anatomy().unwrap().config().artery_collapse_onset {
            assert_eq!(l.artery.half_width, art.half_width());
            assert_eq!(l.artery.lateral, l0.artery.lateral);
        }
    }
    assert!(measured >= 4, "too few open frames measured: {measured}");
    assert!(compared >= 1, "no frame at mid compression");
}

#[test]
fn thrombosed_vein_does_not_widen() {
    // An occlusive thrombus is a solid plug: its lumen keeps its width and
    // centre at every force, and its height ratio is its area ratio.
    for state in [VeinState::Acute, VeinState::Chronic] {
        let cfg = ImagingConfig::default();
        let mut r = Renderer::new(&cfg, state).unwrap();
        let v = *r.anatomy().unwrap().vein();
        let (_, l0) = render_force(&mut r, 0.0, 0.0);
        for f in [2.0, 5.0, EXAM_FORCE, 20.0] {
            let (_, l) = render_force(&mut r, f, 0.0);
            assert_eq!(l.vein.half_width, v.half_width(), "{state:?} at {f} N");
            assert_eq!(l.vein.lateral, l0.vein.lateral);
            let c = l.vein.half_height / v.half_height();
            assert!((c - l.vein.area / l.vein.rest_area).abs() < 1e-9);
        }
    }
}

#[test]
fn widened_frames_are_deterministic() {
    // Two renderers, the same widened frame: the same bytes.
    let cfg = ImagingConfig::default();
    let mut a = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let mut b = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (fa, la) = render_force(&mut a, 3.0, 0.1);
    let (fb, _) = render_force(&mut b, 3.0, 0.1);
    assert!(la.vein.half_width > a.anatomy().unwrap().vein().half_width());
    assert!(fa == fb);
}

/// Prints the shapes (reported and on the image) at 0, 2, 5, 10 N:
/// `cargo test -p echothigh-imaging --test suite vessel_shape:: -- --ignored --nocapture`.
#[test]
#[ignore]
fn print_shapes() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (vh, ah) = {
        let a = r.anatomy().unwrap();
        (a.vein().half_width(), a.artery().half_width())
    };
    for f in [0.0, 2.0, 5.0, 10.0, 15.0, 20.0] {
        let (frame, l) = render_force(&mut r, f, 0.0);
        if let Ok(dir) = std::env::var("SHAPES_DIR") {
            let path = std::path::Path::new(&dir).join(format!("healthy_{f:.0}N.png"));
            write_gray_png(&path, cfg.columns, cfg.rows, &frame).unwrap();
        }
        let px = |x: Option<(f64, f64)>| match x {
            Some((w, h)) => format!("{:.1} x {:.1} mm ({:.2})", w * 1e3, h * 1e3, w / h),
            None => "closed".to_string(),
        };
        println!(
            "{f:>4} N vein c={:.2} model {:.2} image {} | artery p={:.0} mmHg model {:.2} image {}",
            l.vein.area / l.vein.rest_area,
            aspect(&l.vein),
            px(dark_extent(&cfg, &frame, &l.vein, vh)),
            l.artery.tissue_pressure / 133.322,
            aspect(&l.artery),
            px(dark_extent(&cfg, &frame, &l.artery, ah)),
        );
    }
}
