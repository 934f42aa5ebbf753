//! The attenuation of a column, one slope per segment between the
//! anatomy's breakpoints (`Anatomy::column_breakpoints`, read at each
//! segment's middle as the renderer's `column_loss` does), against a fine
//! sum of the tissue's own slope (`Anatomy::attenuation_at`).

use echothigh_imaging::*;

/// `∫₀^depth α dz` (dB/MHz; α in dB/(cm·MHz), z in cm) of the column `u`
/// (m) by the breakpoints: one slope per segment, read at its middle (the
/// last segment's middle 1 mm below its start, as `column_loss`).
fn by_breakpoints(a: &Anatomy, u: f64, depth: f64) -> f64 {
    let mut b = [0.0; MAX_BREAKPOINTS];
    let n = a.column_breakpoints(u, &mut b);
    let mut acc = 0.0;
    for i in 0..n {
        let next = if i + 1 < n { b[i + 1] } else { b[i] + 2e-3 };
        let alpha = a.attenuation_at(u, 0.5 * (b[i] + next));
        let end = if i + 1 < n { b[i + 1] } else { f64::INFINITY };
        let (z0, z1) = (b[i].max(0.0), end.min(depth));
        if z1 > z0 {
            acc += alpha * (z1 - z0) * 100.0;
        }
    }
    acc
}

/// The same integral by the midpoint rule over steps of `h` (m).
fn fine(a: &Anatomy, u: f64, depth: f64, h: f64) -> f64 {
    let steps = (depth / h).round() as usize;
    (0..steps)
        .map(|k| a.attenuation_at(u, (k as f64 + 0.5) * h) * h * 100.0)
        .sum()
}

#[test]
fn every_segment_of_a_column_attenuates_like_its_tissue() {
    // Columns every 0.25 mm across the 40 mm image, down to 38 mm (above
    // the femur's top, 39.8 mm at its centre: the breakpoints give the
    // cortex, not the marrow behind it), through the fascia lines and the
    // vessels. The fine sum's error: each of the ≲ 20 jumps of slope
    // (≤ 1.5 dB/(cm·MHz) in soft tissue) is resolved to a step of 1 µm,
    // ≤ ½ · 1.5 · 1e-4 dB/MHz each, ≤ 1.5e-3 dB/MHz in all. Required:
    // 2e-3 dB/MHz (0.03 dB round trip at 7.5 MHz). A segment of muscle
    // taking a fascia line's slope over its ≈ 13 mm errs by
    // 0.87 × 1.3 ≈ 1.1 dB/MHz (fascia 1.57 against muscle 0.7); fascia
    // lines without breakpoints, attenuating like muscle, by 0.087 dB/MHz
    // for two lines of 0.5 mm (0.01 with fascia at 0.8, what the old
    // breakpoints gave at u = −20 mm).
    for state in [VeinState::Healthy, VeinState::Acute] {
        let a = Anatomy::new(&AnatomyConfig::default(), state).unwrap();
        for k in -80..=80 {
            let u = k as f64 * 0.25e-3;
            let (x, y) = (by_breakpoints(&a, u, 38e-3), fine(&a, u, 38e-3, 1e-6));
            assert!(
                (x - y).abs() < 2e-3,
                "{state:?}, u = {:.2} mm: breakpoints {x:.4} vs fine {y:.4} dB/MHz",
                u * 1e3
            );
        }
    }
}
