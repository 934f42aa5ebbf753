//! Spectral energy of a sampled force above a cut-off frequency.
//!
//! For samples `x_n` (N) taken every `T` seconds, `n = 0..N`, the discrete
//! Fourier transform `X_k = Σ_n x_n e^{−2πi kn/N}` satisfies Parseval's
//! identity `Σ_n x_n² = (1/N) Σ_k |X_k|²`, so the signal's energy
//! `∫ x² dt ≈ T Σ_n x_n²` (N²·s) splits over frequencies as
//! `(T/N) Σ_k |X_k|²`. Bin `k` stands for the frequency
//! `f_k = min(k, N − k) / (N T)` (Hz; the negative frequencies fold onto the
//! positive ones), and the energy above `f_c` is the sum over `f_k > f_c`.
//!
//! No window is applied: the experiments' exams start and end out of contact
//! (force exactly zero), so the record is its own periodic extension and
//! there is no leakage from the ends.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// Energy of `x` (N, sampled every `period` s) at frequencies strictly above
/// `cutoff` (Hz), in N²·s (see the module docs). Returns 0 for fewer than two
/// samples or a non-positive period.
pub fn energy_above(x: &[f64], period: f64, cutoff: f64) -> f64 {
    let n = x.len();
    if n < 2 || period.is_nan() || period <= 0.0 {
        return 0.0;
    }
    let mut buf: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    FftPlanner::<f64>::new()
        .plan_fft_forward(n)
        .process(&mut buf);
    let span = n as f64 * period;
    let sum: f64 = buf
        .iter()
        .enumerate()
        .filter(|(k, _)| (*k).min(n - *k) as f64 / span > cutoff)
        .map(|(_, c)| c.norm_sqr())
        .sum();
    sum * period / n as f64
}

/// Total energy `T Σ x_n²` (N²·s) of `x` sampled every `period` s.
pub fn energy(x: &[f64], period: f64) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>() * period
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(freq: f64, amp: f64, n: usize, period: f64) -> Vec<f64> {
        (0..n)
            .map(|i| amp * (2.0 * std::f64::consts::PI * freq * i as f64 * period).sin())
            .collect()
    }

    /// A 50 Hz sine of amplitude A over D seconds carries A² D / 2 (N²·s),
    /// all of it above 30 Hz; a 10 Hz sine carries none above 30 Hz.
    #[test]
    fn sine_energy_is_where_its_frequency_is() {
        let (t, n) = (1e-3, 2000);
        let hi = sine(50.0, 2.0, n, t);
        let e = energy_above(&hi, t, 30.0);
        assert!((e - 4.0 * 2.0 / 2.0).abs() < 1e-9, "{e}");
        let lo = sine(10.0, 2.0, n, t);
        assert!(energy_above(&lo, t, 30.0) < 1e-18);
    }

    /// Parseval: with a cut-off below every non-zero frequency, the energy
    /// above it is the total energy minus the mean's share.
    #[test]
    fn parseval_holds_for_an_arbitrary_signal() {
        let t = 1e-3;
        let x: Vec<f64> = (0..1000)
            .map(|i| ((i * 37 % 101) as f64).sqrt() - 3.0)
            .collect();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let dc = mean * mean * x.len() as f64 * t;
        let above = energy_above(&x, t, 0.5);
        assert!((above + dc - energy(&x, t)).abs() < 1e-9 * energy(&x, t));
    }

    /// A zero-order hold of a slow sine at 100 Hz puts energy above 30 Hz
    /// (the staircase's steps); the smooth sine does not.
    #[test]
    fn staircase_has_high_frequency_energy() {
        let (t, n) = (1e-3, 4000);
        let smooth = sine(1.0, 5.0, n, t);
        let held: Vec<f64> = (0..n).map(|i| smooth[i - i % 10]).collect();
        assert!(energy_above(&smooth, t, 30.0) < 1e-6);
        assert!(energy_above(&held, t, 30.0) > 1e-3);
    }
}
