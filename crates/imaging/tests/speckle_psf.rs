//! Speckle statistics of a homogeneous medium and the PSF's resolution.

mod common;
use echothigh_imaging::*;

fn rest_input(d: &SectionDeformation) -> FrameInput<'_> {
    FrameInput {
        deformation: d,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    }
}

/// Envelope samples of a uniform phantom, decimated by about one speckle
/// cell (so that samples are nearly independent).
fn envelope_samples(density: f64, seed: u64) -> Vec<f64> {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::phantom(&cfg, &Phantom::Uniform { density, seed }).unwrap();
    let d = SectionDeformation::rest(1.0);
    r.render(&rest_input(&d)).unwrap();
    let mut v = Vec::new();
    for j in (8..cfg.columns - 8).step_by(6) {
        for i in (8..cfg.rows - 8).step_by(4) {
            v.push(r.envelope(j, i) as f64);
        }
    }
    v
}

fn mean_over_std(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    m / var.sqrt()
}

/// Kolmogorov–Smirnov distance between the samples and the Rayleigh law
/// with the maximum-likelihood scale `σ² = mean(x²)/2`.
fn rayleigh_ks(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let s2 = v.iter().map(|x| x * x).sum::<f64>() / (2.0 * n);
    let mut x = v.to_vec();
    x.sort_by(f64::total_cmp);
    x.iter()
        .enumerate()
        .map(|(i, &xi)| {
            let f = 1.0 - (-xi * xi / (2.0 * s2)).exp();
            (f - i as f64 / n).abs().max((f - (i + 1) as f64 / n).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn fully_developed_speckle_is_rayleigh() {
    let v = envelope_samples(ImagingConfig::default().scatterer_density, 11);
    let snr = mean_over_std(&v);
    assert!((snr - 1.91).abs() < 0.1, "mean/std = {snr}");
    // KS at the 1 % level: D < 1.63 / √n.
    let d = rayleigh_ks(&v);
    let crit = 1.63 / (v.len() as f64).sqrt();
    assert!(d < crit, "KS distance {d} >= {crit} (n = {})", v.len());
}

#[test]
fn sparse_scatterers_are_not_fully_developed() {
    // 0.5 per mm²: ≈ 0.2 scatterers per resolution cell.
    let v = envelope_samples(5e5, 11);
    let snr = mean_over_std(&v);
    assert!(snr < 1.6, "mean/std = {snr}");
    let d = rayleigh_ks(&v);
    assert!(
        d > 1.63 / (v.len() as f64).sqrt(),
        "sparse speckle passed the Rayleigh test: {d}"
    );
}

/// Full width at half maximum of a sampled profile (pixels), with the
/// half-maximum crossings interpolated linearly in log amplitude (exact for
/// a Gaussian between two samples on the same side).
fn fwhm(p: &[f64]) -> f64 {
    let (k, &m) = p
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    let half = 0.5 * m;
    let cross = |a: usize, b: usize| {
        let (la, lb) = (p[a].ln(), p[b].ln());
        a as f64 + (half.ln() - la) / (lb - la) * (b as f64 - a as f64)
    };
    let mut r = k;
    while p[r + 1] > half {
        r += 1;
    }
    let mut l = k;
    while p[l - 1] > half {
        l -= 1;
    }
    cross(r, r + 1) - cross(l, l - 1)
}

#[test]
fn psf_fwhm_matches_the_configured_resolution() {
    for (ax, lat) in [(0.4e-3, 0.8e-3), (0.6e-3, 1.2e-3), (0.3e-3, 0.5e-3)] {
        let cfg = ImagingConfig {
            axial_fwhm: ax,
            lateral_fwhm: lat,
            ..Default::default()
        };
        let (col, row) = (128, 192);
        // Slightly off the row centre: sub-pixel positions must not matter.
        let depth = (row as f64 + 0.5 + 0.3) * cfg.pixel_depth();
        let mut r = Renderer::phantom(&cfg, &Phantom::Points(vec![(col, depth)])).unwrap();
        let d = SectionDeformation::rest(1.0);
        r.render(&rest_input(&d)).unwrap();
        let lateral: Vec<f64> = (0..cfg.columns)
            .map(|j| r.envelope(j, row) as f64)
            .collect();
        let axial: Vec<f64> = (0..cfg.rows).map(|i| r.envelope(col, i) as f64).collect();
        let fx = fwhm(&lateral) * cfg.pixel_width();
        let fz = fwhm(&axial) * cfg.pixel_depth();
        assert!((fx / lat - 1.0).abs() < 0.1, "lateral FWHM {fx} vs {lat}");
        assert!((fz / ax - 1.0).abs() < 0.1, "axial FWHM {fz} vs {ax}");
    }
}

#[test]
fn a_point_moves_with_the_column_compression() {
    let cfg = ImagingConfig::default();
    let (col, depth) = (100, 0.030);
    let mut r = Renderer::phantom(&cfg, &Phantom::Points(vec![(col, depth)])).unwrap();
    let (s, bone) = (0.008, 0.040);
    let d = SectionDeformation::flat_press(s, 0.04, 1.5e-3, bone).unwrap();
    r.render(&rest_input(&d)).unwrap();
    let axial: Vec<f64> = (0..cfg.rows).map(|i| r.envelope(col, i) as f64).collect();
    let peak = axial
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0;
    // y = d + s (1 − d/B), imaged below the face at depth s.
    let expected = depth + s * (1.0 - depth / bone) - s;
    let got = (peak as f64 + 0.5) * cfg.pixel_depth();
    assert!(
        (got - expected).abs() <= cfg.pixel_depth(),
        "{got} vs {expected}"
    );
}
