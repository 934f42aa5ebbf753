//! Helpers shared by the integration tests.
#![allow(dead_code)]

use echothigh_imaging::*;

/// Probe force of a standard compression exam (N).
pub const EXAM_FORCE: f64 = 10.0;

/// Flat-probe indentation (m) for `force` (N): the stand-in law of the CLI,
/// `δ = F b / (1 + F a)`, `b` = 2 mm/N, `b/a` = 30 mm.
pub fn indentation(force: f64) -> f64 {
    let b = 2e-3;
    let a = b / 0.030;
    force * b / (1.0 + force * a)
}

/// A flat press of `indentation` (m) over the anatomy of `r`.
pub fn press(r: &Renderer, indentation: f64) -> SectionDeformation {
    let bone = r.anatomy().map_or(0.040, |a| a.femur_top());
    SectionDeformation::flat_press(indentation, r.config().probe_width, 1.5e-3, bone).unwrap()
}

/// The frame input of the section `d` under `force` (N) on the probe face
/// of `cfg` at time `time` (s), the probe centred (no pan).
pub fn press_input<'a>(
    cfg: &ImagingConfig,
    d: &'a SectionDeformation,
    force: f64,
    time: f64,
) -> FrameInput<'a> {
    FrameInput {
        deformation: d,
        probe_pressure: force / cfg.probe_area(),
        time,
        lateral_offset: 0.0,
    }
}

/// Renders `r` under `force` (N) at time `time` (s); returns the frame and the lumens.
pub fn render_force(r: &mut Renderer, force: f64, time: f64) -> (Vec<u8>, LumenReport) {
    let d = press(r, indentation(force));
    let input = press_input(r.config(), &d, force, time);
    let frame = r.render(&input).unwrap();
    let lumens = r.lumens(&input).unwrap().unwrap();
    (frame, lumens)
}

/// Linear intensity (relative) of a gray level under the configured dynamic range.
pub fn intensity(gray: u8, dynamic_range: f64) -> f64 {
    10f64.powf((gray as f64 / 255.0 * dynamic_range - dynamic_range) / 10.0)
}

/// Pixel `(column, row)` range of the rectangle `u ∈ [u0, u1]`, depth `[d0, d1]` (m).
pub fn region(
    cfg: &ImagingConfig,
    u: (f64, f64),
    d: (f64, f64),
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let col = |x: f64| {
        (((x + 0.5 * cfg.width) / cfg.pixel_width()).round().max(0.0) as usize).min(cfg.columns)
    };
    let row = |z: f64| ((z / cfg.pixel_depth()).round().max(0.0) as usize).min(cfg.rows);
    (col(u.0)..col(u.1), row(d.0)..row(d.1))
}

/// Mean linear intensity of a rectangle of the frame (dB).
pub fn mean_db(cfg: &ImagingConfig, frame: &[u8], u: (f64, f64), d: (f64, f64)) -> f64 {
    let (cols, rows) = region(cfg, u, d);
    let mut sum = 0.0;
    let mut n = 0;
    for i in rows {
        for j in cols.clone() {
            sum += intensity(frame[i * cfg.columns + j], cfg.dynamic_range);
            n += 1;
        }
    }
    assert!(n > 0, "empty region");
    10.0 * (sum / n as f64).log10()
}

/// The dark region connected to a lumen's reported centre
/// ([`dark_region`]).
pub struct DarkRegion {
    /// Pixels in the region.
    pub pixels: usize,
    /// Its extent `(width, height)` (m) over columns and rows; `None` if the
    /// centre is not dark.
    pub extent: Option<(f64, f64)>,
}

impl DarkRegion {
    /// The region's area (m²).
    pub fn area(&self, cfg: &ImagingConfig) -> f64 {
        self.pixels as f64 * cfg.pixel_width() * cfg.pixel_depth()
    }
}

/// The linear intensity `threshold_db` below the muscle beside the vessels
/// at `l`'s depth (lateral 12–19 mm, ± 3 mm): a lumen's dark threshold.
pub fn dark_limit(cfg: &ImagingConfig, frame: &[u8], l: &Lumen, threshold_db: f64) -> f64 {
    let muscle = mean_db(cfg, frame, (12e-3, 19e-3), (l.depth - 3e-3, l.depth + 3e-3));
    10f64.powf((muscle - threshold_db) / 10.0)
}

/// The frame's linear intensity averaged over the 5 × 5 pixels about
/// `(column j, row i)` (fewer at the edges).
pub fn smoothed_intensity(cfg: &ImagingConfig, frame: &[u8], j: usize, i: usize) -> f64 {
    let (w, h) = (cfg.columns, cfg.rows);
    let mut s = 0.0;
    let mut n = 0.0;
    for ii in i.saturating_sub(2)..(i + 3).min(h) {
        for jj in j.saturating_sub(2)..(j + 3).min(w) {
            s += intensity(frame[ii * w + jj], cfg.dynamic_range);
            n += 1.0;
        }
    }
    s / n
}

/// The dark region connected to `l`'s centre: the frame's intensity
/// averaged over 5 × 5 pixels, thresholded `threshold_db` below the muscle
/// beside the vessels at the same depth (lateral 12–19 mm, ± 3 mm), and
/// flood-filled from the centre inside a box of half-size `span` (m) about
/// it.
pub fn dark_region(
    cfg: &ImagingConfig,
    frame: &[u8],
    l: &Lumen,
    span: f64,
    threshold_db: f64,
) -> DarkRegion {
    let (w, h) = (cfg.columns, cfg.rows);
    let limit = dark_limit(cfg, frame, l, threshold_db);
    let smooth = |j: usize, i: usize| smoothed_intensity(cfg, frame, j, i);
    let (cols, rows) = region(
        cfg,
        (l.lateral - span, l.lateral + span),
        (l.depth - span, l.depth + span),
    );
    let seed = (
        ((l.lateral + 0.5 * cfg.width) / cfg.pixel_width()) as usize,
        (l.depth / cfg.pixel_depth()) as usize,
    );
    let mut seen = vec![false; w * h];
    let mut stack = vec![seed];
    let (mut j0, mut j1, mut i0, mut i1) = (usize::MAX, 0, usize::MAX, 0);
    let mut pixels = 0usize;
    while let Some((j, i)) = stack.pop() {
        if !cols.contains(&j) || !rows.contains(&i) || seen[i * w + j] {
            continue;
        }
        seen[i * w + j] = true;
        if smooth(j, i) >= limit {
            continue;
        }
        pixels += 1;
        (j0, j1, i0, i1) = (j0.min(j), j1.max(j), i0.min(i), i1.max(i));
        stack.extend([
            (j + 1, i),
            (j.wrapping_sub(1), i),
            (j, i + 1),
            (j, i.wrapping_sub(1)),
        ]);
    }
    let extent = (j0 != usize::MAX).then(|| {
        (
            (j1 - j0 + 1) as f64 * cfg.pixel_width(),
            (i1 - i0 + 1) as f64 * cfg.pixel_depth(),
        )
    });
    DarkRegion { pixels, extent }
}
