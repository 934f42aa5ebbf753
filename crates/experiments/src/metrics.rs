//! The force-quality measures of the paper's Fig. 4 (`DESIGN.md` §6), per
//! coupling mode, computed from a [`ModeTrace`] and the `direct` reference.
//!
//! All forces are magnitudes of the tissue force rendered each haptic tick
//! (N, tissue units), as in the paper's figure, except the device energy,
//! which uses the force actually written to the device (N, device units).

use super::spectrum::energy_above;
use super::trace::ModeTrace;
use serde::Serialize;

/// Below this magnitude (N) the rendered force counts as zero: the probe has
/// lost contact.
pub const ZERO_FORCE: f64 = 0.01;

/// Time skipped at the start of each hold before its peak-to-peak is taken
/// (s): the press's own settling is not an oscillation.
pub const HOLD_SETTLE: f64 = 0.1;

/// Cut-off of the spectral energy measure (Hz).
pub const SPECTRAL_CUTOFF: f64 = 30.0;

/// Relative peak-to-peak force oscillation during a hold at or above which a
/// mode trembles (the 20 %).
pub const TREMBLE_RATIO: f64 = 0.2;

/// Measures of one mode over one exam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModeMetrics {
    /// Peak force magnitude (N).
    pub peak_force: f64,
    /// Largest change of the force magnitude in one haptic tick (N).
    pub max_tick_change: f64,
    /// RMS of the tick-to-tick change of the force magnitude (N).
    pub rms_tick_change: f64,
    /// Contact losses during the hold phases: times the force fell to zero
    /// (below [`ZERO_FORCE`]) after being in contact in the same hold, while
    /// the hand keeps its press setpoint.
    pub hold_contact_losses: u32,
    /// Haptic ticks of the hold phases spent at zero force after contact.
    pub hold_zero_ticks: u32,
    /// Largest peak-to-peak force over a hold (after [`HOLD_SETTLE`]) divided
    /// by the mean force over the same window (dimensionless).
    pub hold_oscillation: f64,
    /// Energy of the force magnitude above [`SPECTRAL_CUTOFF`] (N²·s).
    pub energy_above_30hz: f64,
    /// RMS of the force magnitude's content above [`SPECTRAL_CUTOFF`],
    /// `√(energy / duration)` (N).
    pub rms_above_30hz: f64,
    /// RMS of the difference to the `direct` mode's force, tick by tick (N).
    pub rms_error: f64,
    /// Largest difference to the `direct` mode's force (N).
    pub peak_error: f64,
    /// `rms_error` over the `direct` mode's peak force (dimensionless).
    pub rms_error_rel: f64,
    /// Energy the device put into the user, `∫ f_device · v dt` (J), with
    /// `f_device` the force the device applies to the end-effector (and the
    /// hand holding it) and `v` the end-effector velocity. Positive: the
    /// device did net work on the user, which a passive virtual environment
    /// never does over an exam that starts and ends out of contact at rest;
    /// negative: the environment (tissue damping) absorbed energy. Exact for
    /// the zero-order-held device force: `Σ_k f_k · (p_{k+1} − p_k)`.
    pub device_energy: f64,
    /// Whether the mode trembles in the sense of the issue: a contact loss
    /// during a hold, or `hold_oscillation ≥` [`TREMBLE_RATIO`].
    pub trembles: bool,
}

/// Largest `|x_{k+1} − x_k|` and the RMS of `x_{k+1} − x_k` (units of `x`).
pub fn tick_changes(x: &[f64]) -> (f64, f64) {
    if x.len() < 2 {
        return (0.0, 0.0);
    }
    let (mut max, mut sq) = (0.0_f64, 0.0);
    for w in x.windows(2) {
        let d = w[1] - w[0];
        max = max.max(d.abs());
        sq += d * d;
    }
    (max, (sq / (x.len() - 1) as f64).sqrt())
}

/// RMS and peak of `x − reference` over their common length (units of `x`).
pub fn errors(x: &[f64], reference: &[f64]) -> (f64, f64) {
    let n = x.len().min(reference.len());
    if n == 0 {
        return (0.0, 0.0);
    }
    let (mut peak, mut sq) = (0.0_f64, 0.0);
    for (a, b) in x.iter().zip(reference) {
        let d = a - b;
        peak = peak.max(d.abs());
        sq += d * d;
    }
    ((sq / n as f64).sqrt(), peak)
}

/// The hold segments: maximal runs `[start, end)` of ticks with `holding`.
pub fn hold_segments(holding: &[bool]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &h) in holding.iter().enumerate() {
        match (h, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, holding.len()));
    }
    out
}

/// Contact losses and zero-force ticks in the hold segments of `force`
/// (see [`ModeMetrics::hold_contact_losses`]).
pub fn hold_losses(force: &[f64], holding: &[bool]) -> (u32, u32) {
    let (mut losses, mut zero_ticks) = (0, 0);
    for (s, e) in hold_segments(holding) {
        // `contact`: touched in this hold; `lost`: at zero since then.
        let (mut contact, mut lost) = (false, false);
        for &f in &force[s.min(force.len())..e.min(force.len())] {
            if f > ZERO_FORCE {
                contact = true;
                lost = false;
            } else if contact {
                if !lost {
                    losses += 1;
                    lost = true;
                }
                zero_ticks += 1;
            }
        }
    }
    (losses, zero_ticks)
}

/// Largest relative peak-to-peak over the hold segments, skipping
/// `settle_ticks` at the start of each; segments with a mean force at zero
/// (no contact) are ignored.
pub fn hold_oscillation(force: &[f64], holding: &[bool], settle_ticks: usize) -> f64 {
    let mut worst = 0.0_f64;
    for (s, e) in hold_segments(holding) {
        let e = e.min(force.len());
        let s = s + settle_ticks;
        if s + 1 >= e {
            continue;
        }
        let w = &force[s..e];
        let mean = w.iter().sum::<f64>() / w.len() as f64;
        if mean <= ZERO_FORCE {
            continue;
        }
        let (lo, hi) = w
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(f), hi.max(f))
            });
        worst = worst.max((hi - lo) / mean);
    }
    worst
}

/// `Σ_k f_k · (p_{k+1} − p_k)` (J) for device forces `f` (N) held over the
/// ticks and end-effector positions `p` (m), with `p_end` the position after
/// the last tick.
pub fn device_energy(force: &[[f64; 3]], position: &[[f64; 3]], p_end: [f64; 3]) -> f64 {
    let n = force.len().min(position.len());
    (0..n)
        .map(|k| {
            let next = if k + 1 < n { position[k + 1] } else { p_end };
            (0..3)
                .map(|i| force[k][i] * (next[i] - position[k][i]))
                .sum::<f64>()
        })
        .sum()
}

/// Every measure of `trace` against the `direct` reference force magnitudes.
pub fn measure(trace: &ModeTrace, reference: &[f64]) -> ModeMetrics {
    let f = &trace.force;
    let period = trace.period;
    let peak_force = f.iter().copied().fold(0.0, f64::max);
    let (max_tick_change, rms_tick_change) = tick_changes(f);
    let (hold_contact_losses, hold_zero_ticks) = hold_losses(f, &trace.holding);
    let settle = (HOLD_SETTLE / period).round() as usize;
    let hold_osc = hold_oscillation(f, &trace.holding, settle);
    let e_hf = energy_above(f, period, SPECTRAL_CUTOFF);
    let duration = f.len() as f64 * period;
    let (rms_error, peak_error) = errors(f, reference);
    let ref_peak = reference.iter().copied().fold(0.0, f64::max);
    ModeMetrics {
        peak_force,
        max_tick_change,
        rms_tick_change,
        hold_contact_losses,
        hold_zero_ticks,
        hold_oscillation: hold_osc,
        energy_above_30hz: e_hf,
        rms_above_30hz: if duration > 0.0 {
            (e_hf / duration).sqrt()
        } else {
            0.0
        },
        rms_error,
        peak_error,
        rms_error_rel: if ref_peak > 0.0 {
            rms_error / ref_peak
        } else {
            0.0
        },
        device_energy: device_energy(
            &trace.device_force,
            &trace.device_position,
            trace.final_position,
        ),
        trembles: hold_contact_losses > 0 || hold_osc >= TREMBLE_RATIO,
    }
}
