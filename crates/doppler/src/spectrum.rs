//! One spectral line: the Doppler power spectrum of the last `N` slow-time
//! samples (Hann window, FFT), and what is read off it.
//!
//! Bins are in FFT order: bin `k` is `k · prf / N` for `k < N/2` and
//! `(k − N) · prf / N` above, so the frequency axis spans `[−prf/2, prf/2)`
//! and a shift beyond `prf/2` wraps to the other side (aliasing).

use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// A spectral line's power per bin, with the planner's FFT and scratch
/// (allocated once).
pub struct Spectrum {
    fft: Arc<dyn Fft<f32>>,
    window: Vec<f32>,
    buf: Vec<Complex<f32>>,
    scratch: Vec<Complex<f32>>,
    /// Power per bin (FFT order), of the last [`Spectrum::compute`].
    pub power: Vec<f32>,
    prf: f64,
}

impl std::fmt::Debug for Spectrum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Spectrum")
            .field("n", &self.power.len())
            .field("prf", &self.prf)
            .finish()
    }
}

impl Spectrum {
    /// A spectrum of `n` bins at pulse repetition frequency `prf` (Hz).
    pub fn new(n: usize, prf: f64) -> Spectrum {
        let fft = FftPlanner::new().plan_fft_forward(n);
        let scratch = vec![Complex::default(); fft.get_inplace_scratch_len()];
        // Periodic Hann window, normalized to unit mean power so that a
        // tone's bin power does not depend on N's window loss.
        let w: Vec<f32> = (0..n)
            .map(|i| (0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos()) as f32)
            .collect();
        let norm = (w.iter().map(|x| x * x).sum::<f32>() / n as f32).sqrt();
        Spectrum {
            fft,
            window: w.iter().map(|x| x / norm).collect(),
            buf: vec![Complex::default(); n],
            scratch,
            power: vec![0.0; n],
            prf,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.power.len()
    }

    /// Whether there are no bins (never: N ≥ 16).
    pub fn is_empty(&self) -> bool {
        self.power.is_empty()
    }

    /// Frequency (Hz) of bin `k`.
    pub fn frequency(&self, k: usize) -> f64 {
        let n = self.len();
        let k = if k < n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        k * self.prf / n as f64
    }

    /// Computes the power of `samples` (`N` of them, oldest first; the
    /// ring is read from `start`). Allocates nothing.
    pub fn compute(&mut self, ring: &[Complex<f32>], start: usize) {
        let n = self.len();
        for i in 0..n {
            self.buf[i] = ring[(start + i) % n] * self.window[i];
        }
        self.fft
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        let scale = 1.0 / n as f32;
        for (p, b) in self.power.iter_mut().zip(&self.buf) {
            *p = b.norm_sqr() * scale;
        }
    }

    /// Power-weighted mean frequency (Hz) of the line (the first moment).
    pub fn mean_frequency(&self) -> f64 {
        let (mut s, mut w) = (0.0, 0.0);
        for (k, &p) in self.power.iter().enumerate() {
            s += self.frequency(k) * p as f64;
            w += p as f64;
        }
        if w > 0.0 {
            s / w
        } else {
            0.0
        }
    }

    /// Frequency (Hz) of the strongest bin.
    pub fn peak_frequency(&self) -> f64 {
        let k = self
            .power
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(k, _)| k);
        self.frequency(k)
    }

    /// The envelope (maximum) frequency (Hz): the frequency of largest
    /// magnitude, on the side of the mean, below which `fraction` (e.g.
    /// 0.95) of that side's power lies (the percentile method of
    /// maximum-frequency estimation, Marasek & Nowicki, UMB 1994).
    pub fn max_frequency(&self, fraction: f64) -> f64 {
        let n = self.len();
        let positive = self.mean_frequency() >= 0.0;
        let bins = |i: usize| if positive { i } else { (n - i) % n };
        let total: f64 = (0..n / 2).map(|i| self.power[bins(i)] as f64).sum();
        if total <= 0.0 {
            return 0.0;
        }
        let mut acc = 0.0;
        for i in 0..n / 2 {
            acc += self.power[bins(i)] as f64;
            if acc >= fraction * total {
                return self.frequency(bins(i));
            }
        }
        self.frequency(bins(n / 2 - 1))
    }

    /// Total power of the line.
    pub fn total_power(&self) -> f64 {
        self.power.iter().map(|&p| p as f64).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A complex tone on bin 10 puts its power there (Hann leakage only to
    /// the neighbours) and the frequency axis is `k prf / N`; a tone beyond
    /// prf/2 lands at `f − prf` (aliasing by construction of the DFT).
    #[test]
    fn tone_lands_on_its_bin() {
        let (n, prf) = (128, 4000.0);
        let mut s = Spectrum::new(n, prf);
        for f in [312.5, -937.5, 2000.0 + 312.5] {
            let ring: Vec<Complex<f32>> = (0..n)
                .map(|i| {
                    Complex::from_polar(1.0, (std::f64::consts::TAU * f * i as f64 / prf) as f32)
                })
                .collect();
            s.compute(&ring, 0);
            let expect = if f >= prf / 2.0 { f - prf } else { f };
            assert!((s.peak_frequency() - expect).abs() < 1e-9, "{f}");
            // Hann: the main lobe (3 bins) holds all the power of a bin-centred tone.
            assert!((s.mean_frequency() - expect).abs() < 1e-3 * prf);
        }
    }
}
