//! Wall (clutter) filters on slow-time IQ.
//!
//! - [`HighPass`]: a second-order Butterworth high-pass biquad (bilinear
//!   transform, RBJ cookbook coefficients) run continuously on the PW
//!   stream. Hand-written: the recurrence is six lines, and the crates that
//!   offer it (`biquad`) filter real samples only, while this runs on
//!   complex IQ (the same real coefficients applied to both parts).
//! - [`regression_filter`]: the order-1 polynomial regression filter of a
//!   colour ensemble (removes the mean and the linear trend of the
//!   ensemble: Kadi & Loupas, IEEE TUFFC 1995; Bjærum et al., IEEE TUFFC
//!   2002), a projection with no start-up transient.

use rustfft::num_complex::Complex;

/// Second-order Butterworth high-pass on complex samples.
#[derive(Debug, Clone, Copy)]
pub struct HighPass {
    b: [f64; 3],
    a: [f64; 2],
    x: [Complex<f64>; 2],
    y: [Complex<f64>; 2],
}

impl HighPass {
    /// Cut-off `fc` (Hz, −3 dB) at sample rate `fs` (Hz); `fc` in (0, fs/2).
    pub fn new(fc: f64, fs: f64) -> HighPass {
        let w = std::f64::consts::TAU * fc / fs;
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let alpha = w.sin() / (2.0 * q);
        let cw = w.cos();
        let a0 = 1.0 + alpha;
        HighPass {
            b: [
                (1.0 + cw) / 2.0 / a0,
                -(1.0 + cw) / a0,
                (1.0 + cw) / 2.0 / a0,
            ],
            a: [-2.0 * cw / a0, (1.0 - alpha) / a0],
            x: [Complex::default(); 2],
            y: [Complex::default(); 2],
        }
    }

    /// Filters one sample.
    pub fn step(&mut self, x: Complex<f64>) -> Complex<f64> {
        let y = self.b[0] * x + self.b[1] * self.x[0] + self.b[2] * self.x[1]
            - self.a[0] * self.y[0]
            - self.a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }

    /// Magnitude response at `f` (Hz) for sample rate `fs`:
    /// `|H| = (f/fc)² / √(1 + (f/fc)⁴)` in the prewarped frequency.
    pub fn gain(fc: f64, fs: f64, f: f64) -> f64 {
        let warp = |f: f64| (std::f64::consts::PI * f / fs).tan();
        let r = warp(f) / warp(fc);
        r * r / (1.0 + r.powi(4)).sqrt()
    }
}

/// Order-1 regression filter in place over an ensemble `x` of `m ≥ 3`
/// samples: subtracts the least-squares line `α + β (k − k̄)`.
pub fn regression_filter(x: &mut [Complex<f32>]) {
    let m = x.len();
    if m < 2 {
        return;
    }
    let kbar = (m as f32 - 1.0) / 2.0;
    let mut mean = Complex::<f32>::default();
    let mut slope = Complex::<f32>::default();
    let mut sxx = 0.0f32;
    for (k, v) in x.iter().enumerate() {
        let d = k as f32 - kbar;
        mean += *v;
        slope += *v * d;
        sxx += d * d;
    }
    mean /= m as f32;
    slope /= sxx;
    for (k, v) in x.iter_mut().enumerate() {
        *v -= mean + slope * (k as f32 - kbar);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A complex tone through the biquad settles to the analytic gain
    /// (prewarped Butterworth, −3 dB at fc): checked at fc, 4 fc and
    /// fc / 4 to 1e-3 after 4000 samples of settling (poles at radius
    /// < 0.95 for these settings, so the transient is < 1e-80).
    #[test]
    fn biquad_matches_butterworth_gain() {
        let (fc, fs) = (100.0, 4000.0);
        for f in [fc, 4.0 * fc, 0.25 * fc] {
            let mut h = HighPass::new(fc, fs);
            let mut amp = 0.0;
            for n in 0..6000 {
                let ph = std::f64::consts::TAU * f * n as f64 / fs;
                let y = h.step(Complex::new(ph.cos(), ph.sin()));
                if n > 4000 {
                    amp = y.norm();
                }
            }
            let g = HighPass::gain(fc, fs, f);
            assert!((amp - g).abs() < 1e-3, "f {f}: {amp} vs {g}");
        }
        assert!((HighPass::gain(fc, fs, fc) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    }

    /// The regression filter removes a constant plus a ramp exactly
    /// (float32 rounding: < 1e-5 on unit amplitudes) and keeps most of a
    /// tone at a quarter of the sample rate.
    #[test]
    fn regression_removes_lines() {
        let mut x: Vec<Complex<f32>> = (0..8)
            .map(|k| Complex::new(3.0 + 0.5 * k as f32, -1.0 + 0.25 * k as f32))
            .collect();
        regression_filter(&mut x);
        assert!(x.iter().all(|v| v.norm() < 1e-5));
        let mut y: Vec<Complex<f32>> = (0..8)
            .map(|k| Complex::from_polar(1.0, std::f32::consts::FRAC_PI_2 * k as f32))
            .collect();
        regression_filter(&mut y);
        let p: f32 = y.iter().map(|v| v.norm_sqr()).sum::<f32>() / 8.0;
        assert!(p > 0.7, "power kept {p}");
    }
}
