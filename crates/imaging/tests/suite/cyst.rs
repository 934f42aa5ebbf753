//! The anechoic cyst phantom on the displayed image (issue 21): filled by
//! clutter, noise and side lobes to −45..−25 dB, not clipped black, and a
//! contrast-to-noise ratio near the speckle-limited bound.

use echothigh_imaging::*;

/// Linear amplitude (relative) of a displayed gray level.
fn amplitude(g: u8, dr: f64) -> f64 {
    10f64.powf((g as f64 / 255.0 * dr - dr) / 20.0)
}

#[test]
fn cyst_contrast_and_cnr() {
    let cfg = ImagingConfig::default();
    let (depth, radius) = (0.020, 0.004);
    let mut r = Renderer::phantom(
        &cfg,
        &Phantom::Cyst {
            density: cfg.scatterer_density,
            seed: 5,
            depth,
            radius,
        },
    )
    .unwrap();
    let d = SectionDeformation::rest(1.0);
    let frame = r
        .render(&FrameInput {
            deformation: &d,
            probe_pressure: 0.0,
            time: 0.0,
            lateral_offset: 0.0,
        })
        .unwrap();
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    let mut black = 0usize;
    for i in 0..cfg.rows {
        let z = (i as f64 + 0.5) * cfg.pixel_depth();
        for j in 0..cfg.columns {
            let x = r.column_lateral(j);
            let rho = x.hypot(z - depth);
            let g = frame[i * cfg.columns + j];
            if rho < 0.75 * radius {
                inside.push(amplitude(g, cfg.dynamic_range));
                black += usize::from(g == 0);
            } else if (z - depth).abs() < 0.75 * radius
                && (1.4 * radius..2.4 * radius).contains(&rho)
            {
                outside.push(amplitude(g, cfg.dynamic_range));
            }
        }
    }
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let p = v.iter().map(|a| a * a).sum::<f64>() / n;
        let var = v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m, var.sqrt(), p)
    };
    let (mi, si, pi) = stats(&inside);
    let (mo, so, po) = stats(&outside);
    let contrast_db = 10.0 * (pi / po).log10();
    assert!(
        (-45.0..=-25.0).contains(&contrast_db),
        "cyst contrast {contrast_db} dB"
    );
    let clipped = black as f64 / inside.len() as f64;
    assert!(
        clipped < 0.2,
        "{:.0} % of the cyst clipped black",
        clipped * 100.0
    );
    // Speckle-limited CNR of two Rayleigh regions of intensity ratio C:
    // (1 − √C) / (0.5227 √(1 + C)), 0.5227 = σ/μ of a Rayleigh envelope
    // (Smith, Wagner et al. 1983: CNR → 1.91 for an anechoic target).
    let c = pi / po;
    let bound = (1.0 - c.sqrt()) / (0.5227 * (1.0 + c).sqrt());
    let cnr = (mo - mi) / (so * so + si * si).sqrt();
    assert!(
        (cnr / bound - 1.0).abs() < 0.2,
        "CNR {cnr} vs bound {bound} (contrast {contrast_db} dB)"
    );
}
