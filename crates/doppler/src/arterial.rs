//! The triphasic femoral arterial waveform: forward flow in systole, a
//! reversal in early diastole, a small late-diastolic forward wave, then
//! rest (Persson et al., J Cardiovasc Surg 1981; the PSV of Jager et al.
//! 1985, see [`crate::physiology`]).
//!
//! Shape (a modelling choice after the published femoral spectra; the
//! reversal of a normal femoral artery is about a third of the systolic
//! peak, e.g. Hwang, Ultrasonography 2017, Fig. 4): within one cardiac
//! period `T`, the centreline velocity relative to the PSV is
//! `g(0.14 T, 0.045 T) − 0.30 g(0.32 T, 0.05 T) + 0.12 g(0.50 T, 0.07 T)`,
//! `g(μ, σ) = exp(−(t − μ)²/(2σ²))`.

/// Centreline velocity of the artery relative to its PSV at time `t` (s)
/// for heart rate `hr` (Hz): 1 at the systolic peak, ≈ −0.30 at the
/// early-diastolic reversal.
pub fn triphasic(t: f64, hr: f64) -> f64 {
    let period = 1.0 / hr;
    let x = t.rem_euclid(period) / period;
    let g = |mu: f64, sigma: f64| (-(x - mu).powi(2) / (2.0 * sigma * sigma)).exp();
    g(0.14, 0.045) - 0.30 * g(0.32, 0.05) + 0.12 * g(0.50, 0.07)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The waveform is triphasic: its maximum is the PSV (1, up to the
    /// other terms' tails, < 1e-3 there), it reverses by 0.30 ± 0.02 of
    /// the PSV in early diastole (the reversal term's own amplitude, less
    /// the tails of the forward terms), and it is periodic at the heart rate.
    #[test]
    fn triphasic_shape_and_period() {
        let hr = 1.2;
        let n = 2000;
        let vals: Vec<f64> = (0..n)
            .map(|i| triphasic(i as f64 / (n as f64 * hr), hr))
            .collect();
        let max = vals.iter().cloned().fold(f64::MIN, f64::max);
        let min = vals.iter().cloned().fold(f64::MAX, f64::min);
        assert!((max - 1.0).abs() < 1e-2, "PSV {max}");
        assert!((min + 0.30).abs() < 0.02, "reversal {min}");
        let sign_changes = vals
            .windows(2)
            .filter(|w| (w[0] > 0.0) != (w[1] > 0.0))
            .count();
        assert!(sign_changes >= 2, "forward, reverse, forward");
        let t = 0.37;
        assert!((triphasic(t, hr) - triphasic(t + 1.0 / hr, hr)).abs() < 1e-12);
    }
}
