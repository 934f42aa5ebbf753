//! The spectral display: baseline and scale of the scrolling spectrogram.
//!
//! The scale is the PRF (the displayed span is always `prf`, ±prf/2 about
//! the baseline, i.e. ± the Nyquist velocity); the baseline `b` in
//! (−1, 1) moves the zero line so that the span is
//! `[−(1 − b) prf/2, (1 + b) prf/2)`: an aliased shift `f − prf` is drawn
//! back at `f` when `f` fits in the moved span (as a scanner's baseline
//! shift "unwraps" aliasing). Rows run from the top of the span
//! (row 0) down; intensities are log-compressed over `dynamic_range` dB
//! below a reference power.

use crate::spectrum::Spectrum;

/// Baseline and grey map of the spectral display.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralDisplay {
    /// Baseline shift in (−1, 1): 0 centred, > 0 more room for positive shifts.
    pub baseline: f64,
    /// Displayed dynamic range (dB).
    pub dynamic_range: f64,
}

impl Default for SpectralDisplay {
    fn default() -> Self {
        SpectralDisplay {
            baseline: 0.0,
            dynamic_range: 40.0,
        }
    }
}

impl SpectralDisplay {
    /// The displayed frequency span `[lo, hi)` (Hz) at `prf`.
    pub fn span(&self, prf: f64) -> (f64, f64) {
        let b = self.baseline.clamp(-0.99, 0.99);
        (-(1.0 - b) * 0.5 * prf, (1.0 + b) * 0.5 * prf)
    }

    /// `f` (Hz) wrapped into the displayed span.
    pub fn unwrap(&self, f: f64, prf: f64) -> f64 {
        let (lo, _) = self.span(prf);
        lo + (f - lo).rem_euclid(prf)
    }

    /// The row (0 at the top) of frequency `f` in a column of `rows`.
    pub fn row_of(&self, f: f64, prf: f64, rows: usize) -> usize {
        let (_, hi) = self.span(prf);
        let x = (hi - self.unwrap(f, prf)) / prf * rows as f64;
        (x.floor().max(0.0) as usize).min(rows - 1)
    }

    /// Draws `spectrum` as one column of `out.len()` grey levels, the bin
    /// nearest each row's frequency, 255 at `reference` power and 0 at
    /// `dynamic_range` dB below. Allocates nothing.
    pub fn column(&self, spectrum: &Spectrum, prf: f64, reference: f64, out: &mut [u8]) {
        let rows = out.len();
        let n = spectrum.len();
        let (_, hi) = self.span(prf);
        for (r, px) in out.iter_mut().enumerate() {
            let f = hi - (r as f64 + 0.5) / rows as f64 * prf;
            let k = ((f / prf * n as f64).round() as i64).rem_euclid(n as i64) as usize;
            let p = spectrum.power[k] as f64;
            let db = 10.0 * (p.max(1e-30) / reference.max(1e-30)).log10();
            *px = (255.0 * (1.0 + db / self.dynamic_range)).clamp(0.0, 255.0) as u8;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Baseline 0: the span is ±prf/2; a shift of 0.6 prf is drawn at
    /// −0.4 prf (aliased); with the baseline at 0.5 the span is
    /// [−prf/4, 3prf/4) and the same shift is drawn where it belongs.
    #[test]
    fn baseline_unwraps_aliasing() {
        let prf = 1000.0;
        let d = SpectralDisplay::default();
        assert_eq!(d.span(prf), (-500.0, 500.0));
        assert!((d.unwrap(600.0, prf) + 400.0).abs() < 1e-9);
        let d = SpectralDisplay {
            baseline: 0.5,
            ..Default::default()
        };
        assert!((d.unwrap(600.0, prf) - 600.0).abs() < 1e-9);
        assert!((d.unwrap(-400.0, prf) - 600.0).abs() < 1e-9);
        assert_eq!(d.row_of(749.0, prf, 100), 0);
        assert_eq!(d.row_of(0.0, prf, 100), 75);
    }
}
