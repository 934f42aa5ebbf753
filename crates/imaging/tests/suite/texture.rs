//! Issue 21's textures and reverberation on the rendered section: muscle's
//! starry sky, the veins' slow-flow smoke (an option), the reverberation
//! in the top of a vein's lumen.

use crate::common;
use common::*;
use echothigh_imaging::*;

/// Muscle boxes away from the vessels, fascias and femur (lateral, depth; m).
const MUSCLE: [((f64, f64), (f64, f64)); 2] = [
    ((-19e-3, -14e-3), (20e-3, 38e-3)),
    ((9e-3, 19e-3), (20e-3, 36e-3)),
];

/// Linear intensities of the pixels of box `(u, d)`, by row.
fn rows_of(cfg: &ImagingConfig, frame: &[u8], u: (f64, f64), d: (f64, f64)) -> Vec<Vec<f64>> {
    let (cols, rows) = region(cfg, u, d);
    rows.map(|i| {
        cols.clone()
            .map(|j| intensity(frame[i * cfg.columns + j], cfg.dynamic_range))
            .collect()
    })
    .collect()
}

/// Mean linear intensity over the muscle boxes.
fn muscle_mean(cfg: &ImagingConfig, frame: &[u8]) -> f64 {
    let all: Vec<f64> = MUSCLE
        .iter()
        .flat_map(|&(u, d)| rows_of(cfg, frame, u, d).into_iter().flatten())
        .collect();
    all.iter().sum::<f64>() / all.len() as f64
}

/// Fraction of the muscle boxes' pixels at ≥ 10 × the median of their row
/// (the row's median removes the depth's trend: focal gain, attenuation).
fn bright_fraction(cfg: &ImagingConfig, frame: &[u8]) -> f64 {
    let (mut over, mut n) = (0usize, 0usize);
    for &(u, d) in &MUSCLE {
        for mut row in rows_of(cfg, frame, u, d) {
            let median = {
                let mut s = row.clone();
                s.sort_by(f64::total_cmp);
                s[s.len() / 2]
            };
            n += row.len();
            row.retain(|&v| v >= 10.0 * median);
            over += row.len();
        }
    }
    over as f64 / n as f64
}

#[test]
fn muscle_shows_a_starry_sky_at_its_former_mean() {
    // Two seeds, so that the mean compares over ~500 mm² of muscle.
    let (mut on, mut off) = (0.0, 0.0);
    let mut tails = Vec::new();
    for seed in [7, 8] {
        for fascicles in [true, false] {
            let cfg = ImagingConfig {
                seed,
                texture: TextureConfig {
                    muscle_fascicles: fascicles,
                    ..Default::default()
                },
                ..Default::default()
            };
            let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
            let (frame, _) = render_force(&mut r, 0.0, 0.0);
            let m = muscle_mean(&cfg, &frame);
            if fascicles {
                on += m;
                tails.push(bright_fraction(&cfg, &frame));
            } else {
                off += m;
            }
        }
    }
    let shift = 10.0 * (on / off).log10();
    // Exponential intensity (fully developed speckle): median = ln 2 · mean,
    // P(I ≥ 10 median) = exp(−10 ln 2) = 2⁻¹⁰ ≈ 0.098 %.
    let speckle = 2f64.powi(-10);
    eprintln!("starry sky: mean {shift:+.2} dB re the former texture; pixels ≥ 10× their row's median: {tails:?} (speckle {speckle:.5})");
    // Mean: the fascicle background is set to keep muscle's mean power
    // (texture::fascicle_amplitude). The two textures are independent
    // realisations; the sampling spread of their mean ratio over the boxes
    // (2 seeds × ~250 mm²: ~150 dots at 58 % of the power, ~100 lines at
    // 41 %, ~8000 speckle cells) is ≈ √(0.58²/150 + 0.41²/100 + 2/8000)
    // ≈ 6.4 % ≈ 0.27 dB: the issue's ±1 dB is ≈ 3.7 σ.
    assert!(shift.abs() <= 1.0, "muscle mean moved {shift:+.2} dB");
    // Tail: ~125 mm² a frame ≈ 2000 speckle cells (0.063 mm² each) expect
    // 2 cells over the bar from speckle alone; 5 × that (10) has Poisson
    // probability < 10⁻³ under speckle. The dots (4.5 % of the area at
    // +15 dB, ≈ 80 % of their pixels over the bar) predict ≈ 3–4 %.
    for t in tails {
        assert!(
            t >= 5.0 * speckle,
            "bright tail {t:.5} vs speckle {speckle:.5}"
        );
    }
}

/// Mean (dB) of the centre of `l` (±60 % of its half-width and height).
fn lumen_centre_db(cfg: &ImagingConfig, frame: &[u8], l: &Lumen) -> f64 {
    let (h, v) = (0.6 * l.half_width, 0.6 * l.half_height);
    mean_db(
        cfg,
        frame,
        (l.lateral - h, l.lateral + h),
        (l.depth - v, l.depth + v),
    )
}

/// Pixels of the centre of `l`, linear.
fn lumen_pixels(cfg: &ImagingConfig, frame: &[u8], l: &Lumen) -> Vec<f64> {
    let (h, v) = (0.6 * l.half_width, 0.6 * l.half_height);
    rows_of(
        cfg,
        frame,
        (l.lateral - h, l.lateral + h),
        (l.depth - v, l.depth + v),
    )
    .into_iter()
    .flatten()
    .collect()
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn slow_flow_smoke_moves_in_a_patent_vein_and_not_in_a_closed_one() {
    let smoky = ImagingConfig {
        texture: TextureConfig {
            smoke: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let plain = ImagingConfig::default();
    let mut r = Renderer::new(&smoky, VeinState::Healthy).unwrap();
    let (a, lumens) = render_force(&mut r, 0.0, 0.0);
    let (b, _) = render_force(&mut r, 0.0, 0.5);
    let muscle = mean_db(&smoky, &a, (12e-3, 18e-3), (26e-3, 32e-3));
    let vein = lumens.vein;
    let level = lumen_centre_db(&smoky, &a, &vein) - muscle;
    let rho = correlation(
        &lumen_pixels(&smoky, &a, &vein),
        &lumen_pixels(&smoky, &b, &vein),
    );
    let mut q = Renderer::new(&plain, VeinState::Healthy).unwrap();
    let (a0, _) = render_force(&mut q, 0.0, 0.0);
    let level0 = lumen_centre_db(&plain, &a0, &vein) - muscle;
    eprintln!("smoke: lumen {level:.1} dB re muscle ({level0:.1} without), frame-to-frame correlation {rho:.3}");
    // Smoke at −32 dB over the lumen's static −32.6 dB (measured without
    // smoke: the −35 dB clutter, the noise, the walls' side lobes):
    // −29.3 dB predicted; the window −40 to −25 dB.
    assert!(
        (-40.0..=-25.0).contains(&level),
        "lumen {level:.1} dB re muscle"
    );
    // The static part holds a fraction `s` ≈ 10^(−0.33) ≈ 0.47 of the
    // lumen's power; the smoke 10 decorrelation times later is new.
    // Circular Gaussian fields: the frames' intensity correlation is
    // `s²` ≈ 0.22, against the bound 0.5.
    assert!(rho < 0.5, "smoke does not move: correlation {rho:.3}");
    // Closed under the exam force: no smoke, the frame of the plain config.
    let (c, l) = render_force(&mut r, EXAM_FORCE, 0.5);
    let (c0, _) = render_force(&mut q, EXAM_FORCE, 0.5);
    assert!(l.vein.area / l.vein.rest_area < 0.1);
    assert!(c == c0, "smoke in a closed vein");
    // And patent, the smoke changes the frame.
    assert!(a != a0);
}

#[test]
fn the_top_of_a_vein_lumen_shows_the_near_walls_reverberation() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, lumens) = render_force(&mut r, 0.0, 0.0);
    let v = lumens.vein;
    // The band starts 0.3 mm under the lumen's top: clear of the wall's own
    // echo (the axial PSF's main lobe reaches ±0.2 mm, FWHM 0.2 mm).
    let top = v.depth - v.half_height + 0.3e-3;
    let h = 0.3 * v.half_width;
    let lateral = (v.lateral - h, v.lateral + h);
    let band = mean_db(&cfg, &frame, lateral, (top, top + 2e-3));
    let centre = mean_db(&cfg, &frame, lateral, (v.depth - 1e-3, v.depth + 1e-3));
    let muscle = mean_db(&cfg, &frame, (12e-3, 18e-3), (top, top + 2e-3));
    eprintln!(
        "lumen top 2 mm {:.1} dB, centre {:.1} dB re muscle",
        band - muscle,
        centre - muscle
    );
    // The first copy of the wall (−21.1 dB re muscle,
    // reverberation::Reverberation::lumen_db) fills its 0.5 mm (the wall's
    // thickness) of the 2 mm band, over the −35 dB clutter of the rest:
    // ¼ · 10^−2.11 + ¾ · 10^−3.5 → −26.6 dB; the centre holds the clutter,
    // −35 dB: +8.4 dB predicted. Spread: the copy's ~25 speckle cells
    // (±20 %) and its rows' quantization (±1 of 6.4 rows, ±15 %): ≈ 1 dB;
    // the bar, 4 dB, is ≈ 4 σ below the prediction.
    assert!(
        band - centre >= 4.0,
        "top {band:.1} vs centre {centre:.1} dB"
    );
    // Still anechoic to the eye: −26.6 dB predicted, ≥ 20 dB under muscle.
    assert!(
        muscle - band >= 20.0,
        "top only {:.1} dB under muscle",
        muscle - band
    );
}

#[test]
fn the_near_field_repeats_the_fascia_at_twice_its_depth() {
    let on = ImagingConfig::default();
    let off = ImagingConfig {
        reverberation: ReverbConfig {
            enabled: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut a = Renderer::new(&on, VeinState::Healthy).unwrap();
    let mut b = Renderer::new(&off, VeinState::Healthy).unwrap();
    render_force(&mut a, 0.0, 0.0);
    render_force(&mut b, 0.0, 0.0);
    let an = &on.anatomy;
    let fascia = (
        an.skin_thickness + an.fat_thickness,
        an.skin_thickness + an.fat_thickness + an.fascia_thickness,
    );
    let dz = on.pixel_depth();
    // Muscle columns away from the vessels; the echo before attenuation
    // (`Renderer::iq`): the reverberation is the difference of the two.
    let (cols, _) = region(&on, (12e-3, 18e-3), (0.0, 0.0));
    let power = |rows: std::ops::Range<usize>, diff: bool| {
        let mut p = 0.0;
        for j in cols.clone() {
            for i in rows.clone() {
                let (x, y) = (a.iq(j, i), b.iq(j, i));
                let v = if diff { [x[0] - y[0], x[1] - y[1]] } else { y };
                p += (v[0] * v[0] + v[1] * v[1]) as f64;
            }
        }
        p / (cols.len() * rows.len()) as f64
    };
    let rows = |z: (f64, f64)| (z.0 / dz).round() as usize..(z.1 / dz).round() as usize;
    let source = power(rows(fascia), false);
    let copy = power(rows((2.0 * fascia.0, 2.0 * fascia.1)), true);
    let db = 10.0 * (copy / source).log10();
    let r = ReverbConfig::default();
    let predicted = 20.0 * (r.probe_reflection * r.interface_reflection).log10();
    eprintln!("fascia's copy at twice its depth: {db:.1} dB (predicted {predicted:.1})");
    // The copy is the fascia's echo times R_p R_i, stretched twice as deep
    // (each source row fills two rows: the same power per row). Its rows
    // also take the n = 2 copies of the fat and muscle just around the
    // fascia (the rows' rounding, ≤ 1 of ~6.4) and the n = 3 copies of fat
    // at a third of the depth (−9 dB − 2 · 32.8 dB: nothing). ±1.5 dB:
    // one row of ~13 of −20 dB fat or muscle instead of fascia in each
    // band, ±0.7 dB each.
    assert!(
        (db - predicted).abs() <= 1.5,
        "copy {db:.1} dB, predicted {predicted:.1}"
    );
    // Nothing below three times the fascia's depth (outside the lumens).
    let deep = power(rows((3.0 * fascia.1 + 1e-3, 55e-3)), true);
    assert_eq!(deep, 0.0);
}
