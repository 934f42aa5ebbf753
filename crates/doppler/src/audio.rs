//! The Doppler sound: each spectral line synthesized back to a stretch of
//! audio (amplitude √P per bin, a random phase per bin, inverse FFT), the
//! stretches Hann-windowed and overlap-added at the line hop, at the PRF
//! as sample rate. Forward flow (positive shifts) goes to the left
//! channel, reverse flow to the right, as on scanners; each channel is the
//! real part of its one-sided analytic signal, so a line holding one shift
//! `f_d` sounds at `|f_d|` Hz.
//!
//! The overlap-add is normalized by the running sum of the windows at
//! each output sample (precomputed for the steady state), so a stationary
//! spectrum gives a stationary level whatever the hop.

use std::sync::Arc;

use crate::spectrum::Spectrum;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// Overlap-add synthesizer of the Doppler sound.
pub struct AudioSynth {
    ifft: Arc<dyn Fft<f32>>,
    n: usize,
    hop: usize,
    window: Vec<f32>,
    norm: Vec<f32>,
    fwd: Vec<Complex<f32>>,
    rev: Vec<Complex<f32>>,
    scratch: Vec<Complex<f32>>,
    acc: Vec<[f32; 2]>,
    rng: ChaCha8Rng,
}

impl std::fmt::Debug for AudioSynth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AudioSynth")
            .field("n", &self.n)
            .field("hop", &self.hop)
            .finish()
    }
}

impl AudioSynth {
    /// A synthesizer for lines of `n` bins every `hop` samples (`1 ≤ hop ≤ n`).
    pub fn new(n: usize, hop: usize, seed: u64) -> AudioSynth {
        let hop = hop.clamp(1, n);
        let ifft = FftPlanner::new().plan_fft_inverse(n);
        let window: Vec<f32> = (0..n)
            .map(|i| {
                (0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / n as f64).cos()) as f32
            })
            .collect();
        let norm = (0..hop)
            .map(|j| {
                (j..n)
                    .step_by(hop)
                    .map(|i| window[i])
                    .sum::<f32>()
                    .max(1e-6)
            })
            .collect();
        AudioSynth {
            scratch: vec![Complex::default(); ifft.get_inplace_scratch_len()],
            ifft,
            n,
            hop,
            window,
            norm,
            fwd: vec![Complex::default(); n],
            rev: vec![Complex::default(); n],
            acc: vec![[0.0; 2]; n],
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// Samples each line adds.
    pub fn hop(&self) -> usize {
        self.hop
    }

    /// Adds one line and writes the `hop` finished stereo samples
    /// (`[forward, reverse]`) into `out`. Allocates nothing.
    pub fn push(&mut self, line: &Spectrum, out: &mut [[f32; 2]]) {
        let n = self.n;
        for k in 0..n {
            let a = line.power[k].max(0.0).sqrt();
            let ph = self.rng.gen_range(0.0..std::f32::consts::TAU);
            let z = Complex::from_polar(a, ph);
            let f = line.frequency(k);
            self.fwd[k] = if f > 0.0 { z } else { Complex::default() };
            // Reverse flow: its negative bins moved to the mirrored
            // positive bins (heard at the same pitch).
            let mirror = (n - k) % n;
            self.rev[mirror] = if f < 0.0 { z } else { Complex::default() };
        }
        self.ifft
            .process_with_scratch(&mut self.fwd, &mut self.scratch);
        self.ifft
            .process_with_scratch(&mut self.rev, &mut self.scratch);
        let scale = 1.0 / (n as f32).sqrt();
        for i in 0..n {
            let w = self.window[i] * scale;
            self.acc[i][0] += self.fwd[i].re * w;
            self.acc[i][1] += self.rev[i].re * w;
        }
        for (j, o) in out.iter_mut().take(self.hop).enumerate() {
            let g = 1.0 / self.norm[j];
            *o = [self.acc[j][0] * g, self.acc[j][1] * g];
        }
        self.acc.copy_within(self.hop.., 0);
        for a in &mut self.acc[n - self.hop..] {
            *a = [0.0; 2];
        }
    }
}
