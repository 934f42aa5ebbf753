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

/// Renders `r` under `force` (N) at time `time` (s); returns the frame and the lumens.
pub fn render_force(r: &mut Renderer, force: f64, time: f64) -> (Vec<u8>, LumenReport) {
    let d = press(r, indentation(force));
    let input = FrameInput {
        deformation: &d,
        probe_pressure: force / r.config().probe_area(),
        time,
        lateral_offset: 0.0,
    };
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
