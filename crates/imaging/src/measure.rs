//! Measurements of the rendered PSF on the standard point phantom: axial
//! and lateral FWHM, peak echo (focal gain) and side-lobe pedestal per depth.

use crate::config::ImagingConfig;
use crate::deformation::SectionDeformation;
use crate::error::ImagingError;
use crate::render::{FrameInput, Phantom, Renderer};
use serde::Serialize;

/// Depths of the point targets of the standard phantom (m).
pub const POINT_DEPTHS: [f64; 4] = [0.010, 0.020, 0.030, 0.040];

/// The PSF measured at one depth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PsfAtDepth {
    /// Depth of the point (m).
    pub depth_m: f64,
    /// Axial FWHM of the envelope (m).
    pub axial_fwhm_m: f64,
    /// Lateral FWHM of the envelope at the peak's row (m).
    pub lateral_fwhm_m: f64,
    /// Peak envelope before attenuation and TGC, relative to a unit point
    /// at the transmit focus (dB).
    pub peak_db: f64,
    /// Highest envelope of the peak's row at least two lateral FWHM and at
    /// most 5 mm from the peak, relative to the peak (dB): the side lobes
    /// and the edge-wave pedestal.
    pub side_lobe_db: f64,
}

/// The PSF report of `echothigh psf`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PsfReport {
    /// Transmit focus (m).
    pub transmit_focus_m: f64,
    /// Per depth, [`POINT_DEPTHS`].
    pub depths: Vec<PsfAtDepth>,
    /// Peak at the depth nearest the focus minus the larger peak of the
    /// shallowest and deepest points (dB).
    pub focal_gain_db: f64,
}

/// Full width at half maximum (in samples) of the peak at index `k` of a
/// non-negative profile, the crossings interpolated linearly in log
/// amplitude (exact for a Gaussian between two samples on the same side).
/// `None` if the profile does not fall below half on both sides.
pub fn fwhm_samples(p: &[f64], k: usize) -> Option<f64> {
    let half = 0.5 * p[k];
    let cross = |a: usize, b: usize| {
        let (la, lb) = (p[a].max(1e-300).ln(), p[b].max(1e-300).ln());
        a as f64 + (half.ln() - la) / (lb - la) * (b as f64 - a as f64)
    };
    let mut r = k;
    while p.get(r + 1).is_some_and(|&v| v > half) {
        r += 1;
    }
    let mut l = k;
    while l > 0 && p[l - 1] > half {
        l -= 1;
    }
    if r + 1 >= p.len() || l == 0 {
        return None;
    }
    Some(cross(r, r + 1) - cross(l, l - 1))
}

/// The column of the image's axis used by the point phantom.
pub fn axis_column(cfg: &ImagingConfig) -> usize {
    cfg.columns / 2
}

/// Renders the standard point phantom of `cfg` and measures its PSF.
pub fn measure_psf(cfg: &ImagingConfig) -> Result<PsfReport, ImagingError> {
    let col = axis_column(cfg);
    let depths: Vec<f64> = POINT_DEPTHS
        .iter()
        .copied()
        .filter(|&d| d < cfg.depth - 2e-3)
        .collect();
    let points = depths.iter().map(|&d| (col, d)).collect();
    let mut r = Renderer::phantom(cfg, &Phantom::Points(points))?;
    let rest = SectionDeformation::rest(1.0);
    r.render(&FrameInput {
        deformation: &rest,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    })?;
    let (dx, dz) = (cfg.pixel_width(), cfg.pixel_depth());
    let axial: Vec<f64> = (0..cfg.rows).map(|i| r.envelope(col, i) as f64).collect();
    let mut out = Vec::new();
    for &d in &depths {
        // Peak within ±2 mm of the target's row.
        let c = d / dz;
        let lo = (c - 2e-3 / dz).max(1.0) as usize;
        let hi = ((c + 2e-3 / dz) as usize).min(cfg.rows - 2);
        let i = (lo..=hi)
            .max_by(|&a, &b| axial[a].total_cmp(&axial[b]))
            .unwrap_or(lo);
        let lateral: Vec<f64> = (0..cfg.columns).map(|j| r.envelope(j, i) as f64).collect();
        let fail = |what| ImagingError::Input {
            field: "phantom.points",
            reason: what,
        };
        let fz = fwhm_samples(&axial, i).ok_or(fail("axial profile without a half-maximum"))?;
        let fx =
            fwhm_samples(&lateral, col).ok_or(fail("lateral profile without a half-maximum"))?;
        let near = (2.0 * fx).ceil() as usize;
        let far = (5e-3 / dx) as usize;
        let side = (0..cfg.columns)
            .filter(|&j| (near..=far).contains(&j.abs_diff(col)))
            .map(|j| lateral[j])
            .fold(0.0f64, f64::max);
        out.push(PsfAtDepth {
            depth_m: d,
            axial_fwhm_m: fz * dz,
            lateral_fwhm_m: fx * dx,
            peak_db: 20.0 * axial[i].log10(),
            side_lobe_db: 20.0 * (side / lateral[col]).max(1e-10).log10(),
        });
    }
    let focus = cfg.beam.transmit_focus;
    let at_focus = out
        .iter()
        .min_by(|a, b| {
            (a.depth_m - focus)
                .abs()
                .total_cmp(&(b.depth_m - focus).abs())
        })
        .map_or(0.0, |p| p.peak_db);
    let ends = match (out.first(), out.last()) {
        (Some(a), Some(b)) => a.peak_db.max(b.peak_db),
        _ => 0.0,
    };
    Ok(PsfReport {
        transmit_focus_m: focus,
        depths: out,
        focal_gain_db: at_focus - ends,
    })
}
