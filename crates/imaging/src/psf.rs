//! The pulse-echo point spread function in complex baseband, as tables.
//!
//! The RF echo of a point scatterer at depth `d` is a Gaussian-modulated
//! cosine `g_x(x) g_z(z − d) cos(2 k₀ (z − d))`, `k₀ = 2π f₀ / c`, with
//! Gaussian envelopes of standard deviations `σ_x = FWHM_x / 2.3548` and
//! `σ_z = FWHM_z / 2.3548`. Demodulated at `f₀` (complex baseband, I/Q), its
//! contribution at depth `z` is `g_x g_z(z − d) e^{−i 2 k₀ d}` up to a phase
//! `e^{i 2 k₀ z}` common to every scatterer, which the envelope `|IQ|`
//! ignores. The baseband needs no carrier sampling: a few taps per
//! scatterer at the image's own pixel pitch.

use crate::config::{ImagingConfig, FWHM_PER_SIGMA};
use std::f64::consts::PI;

/// Sub-pixel positions of the axial Gaussian table.
pub(crate) const AXIAL_SUBSTEPS: usize = 64;
/// Entries of the phase table (one turn).
pub(crate) const PHASE_STEPS: usize = 4096;

/// Precomputed PSF tables of one image geometry.
#[derive(Debug, Clone)]
pub(crate) struct PsfTables {
    /// Axial taps on each side of a scatterer (`⌈3 σ_z / Δz⌉`, ≥ 1).
    pub axial_half: usize,
    /// `axial[q · 2K + k]`: `g_z` at row offset `k − K + 1 − q/64` (pixels).
    pub axial: Vec<f32>,
    /// `lateral[k]`: `g_x((k − H) Δx)`, `k = 0..2H`.
    pub lateral: Vec<f32>,
    /// `phase[i] = e^{−i 2π i / 4096}` as `[re, im]`.
    pub phase: Vec<[f32; 2]>,
    /// Phase-table index per metre of depth: `2 k₀ / (2π) · 4096`.
    pub phase_per_metre: f64,
    /// Mean echo intensity of muscle (0 dB, unit scatterer power) at the
    /// default density: `ρ Δx σ_z √π Σ_k g_x[k]²` (envelope² units).
    pub muscle_intensity: f64,
}

impl PsfTables {
    /// Tables for `cfg` (assumed validated).
    pub fn new(cfg: &ImagingConfig) -> Self {
        let dx = cfg.pixel_width();
        let dz = cfg.pixel_depth();
        let sx = cfg.lateral_fwhm / FWHM_PER_SIGMA / dx;
        let sz = cfg.axial_fwhm / FWHM_PER_SIGMA / dz;
        let k = ((3.0 * sz).ceil() as usize).max(1);
        let h = ((3.0 * sx).ceil() as usize).max(1);
        let mut axial = Vec::with_capacity(AXIAL_SUBSTEPS * 2 * k);
        for q in 0..AXIAL_SUBSTEPS {
            let frac = q as f64 / AXIAL_SUBSTEPS as f64;
            for t in 0..2 * k {
                let off = t as f64 - k as f64 + 1.0 - frac;
                axial.push((-(off * off) / (2.0 * sz * sz)).exp() as f32);
            }
        }
        let lateral: Vec<f32> = (0..=2 * h)
            .map(|t| {
                let off = t as f64 - h as f64;
                (-(off * off) / (2.0 * sx * sx)).exp() as f32
            })
            .collect();
        let phase = (0..PHASE_STEPS)
            .map(|i| {
                let a = -2.0 * PI * i as f64 / PHASE_STEPS as f64;
                [a.cos() as f32, a.sin() as f32]
            })
            .collect();
        let k0 = 2.0 * PI * cfg.center_frequency / cfg.sound_speed;
        let lateral_energy: f64 = lateral.iter().map(|&g| (g as f64).powi(2)).sum();
        let sigma_z = cfg.axial_fwhm / FWHM_PER_SIGMA;
        PsfTables {
            axial_half: k,
            axial,
            lateral,
            phase,
            phase_per_metre: 2.0 * k0 / (2.0 * PI) * PHASE_STEPS as f64,
            muscle_intensity: cfg.scatterer_density * dx * sigma_z * PI.sqrt() * lateral_energy,
        }
    }
}

/// `log₂ x`, with `x` floored at 1e-30 (silence maps to −99.7, far below
/// any displayed dynamic range).
#[inline]
pub(crate) fn safe_log2(x: f32) -> f32 {
    x.max(1e-30).log2()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_of_silence_is_finite() {
        assert!(safe_log2(0.0).is_finite() && safe_log2(0.0) < -99.0);
        assert_eq!(safe_log2(8.0), 3.0);
    }

    #[test]
    fn tables_peak_at_one_and_are_symmetric() {
        let t = PsfTables::new(&ImagingConfig::default());
        let h = t.lateral.len() / 2;
        assert_eq!(t.lateral[h], 1.0);
        for k in 0..h {
            assert_eq!(t.lateral[k], t.lateral[2 * h - k]);
        }
        let k = t.axial_half;
        // q = 0 (scatterer on a row centre): tap K − 1 is the peak.
        assert_eq!(t.axial[k - 1], 1.0);
        let p = t.phase[PHASE_STEPS / 4];
        assert!(p[0].abs() < 1e-6 && (p[1] + 1.0).abs() < 1e-6);
    }
}
