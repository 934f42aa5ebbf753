//! The sampled-data stability argument behind the hand-damping sweep
//! (`DESIGN.md` §3, "Stability").
//!
//! A virtual spring of stiffness `K` (N/m) rendered through a zero-order
//! hold of period `T` (s) on a device with physical damping `b` (N·s/m) is
//! passive only if `b > K T / 2` (Colgate & Schenkel 1997, "Passivity of a
//! class of sampled-data systems: application to haptic interfaces",
//! J. Robotic Systems 14(1)). With a pure delay `τ` (s) before the hold, the
//! stability boundary is, for short delays and fast sampling, approximately
//! linear: `b > K (T/2 + τ)` (Gil, Sánchez, Hulin, Preusche & Hirzinger
//! 2009, "Stability boundary for haptic rendering: influence of damping and
//! delay", ASME J. Comput. Inf. Sci. Eng. 9(1)). The user's hand grips the
//! device, so its damping adds to the device's: `b = b_device + b_hand`.
//!
//! Without a buffer model the device displays the physics' force, which
//! changes with the probe's depth by the local stiffness `k` (N/m, tissue)
//! times the force scale `s`: `K = s k`, sampled at the physics period and
//! delayed by its compute time and the link's round trip. With the buffer
//! model the same `K` is rendered by the 1 kHz loop from the local model,
//! without delay inside the loop.

use super::metrics::ZERO_FORCE;
use super::sweep::SweepRow;
use super::trace::ModeTrace;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use serde::Serialize;

/// The predicted damping boundaries of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StabilityBound {
    /// Median local stiffness `k` sent by the physics during the holds (N/m, tissue).
    pub local_stiffness: f64,
    /// Tissue-to-device force scale `s` (dimensionless).
    pub force_scale: f64,
    /// Stiffness at the device, `K = s k` (N/m).
    pub device_stiffness: f64,
    /// Physics period, the hold's sampling period `T` (s).
    pub hold_period: f64,
    /// Delay before the hold: compute delay plus the link's round trip (s).
    pub hold_delay: f64,
    /// The device's own viscous friction (N·s/m).
    pub device_damping: f64,
    /// `K T / 2` for `hold` (N·s/m), Colgate–Schenkel without the delay.
    pub hold_passive_damping: f64,
    /// `K (T/2 + τ)` for `hold` (N·s/m), the delayed boundary.
    pub hold_critical_damping: f64,
    /// Hand damping needed by `hold`, `K (T/2 + τ) − b_device`, at least 0 (N·s/m).
    pub hold_critical_hand_damping: f64,
    /// Haptic period of `buffer` (s).
    pub buffer_period: f64,
    /// `K T / 2` for `buffer` at the haptic period (N·s/m).
    pub buffer_critical_damping: f64,
}

/// Median of the finite values (0 if none).
fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The boundaries for `scenario`, with the local stiffness measured on its
/// `direct` trace (one physics step per tick) during the holds in contact.
pub fn bound(scenario: &Scenario, direct: &ModeTrace) -> StabilityBound {
    let n = direct
        .step_stiffness
        .len()
        .min(direct.holding.len())
        .min(direct.force.len());
    let k = median(
        (0..n)
            .filter(|&i| direct.holding[i] && direct.force[i] > ZERO_FORCE)
            .map(|i| direct.step_stiffness[i])
            .collect(),
    );
    let s = scenario.device().force_scale;
    let big_k = s * k;
    let t = 1.0 / scenario.coupling.physics_rate;
    let tau = scenario.coupling.compute_delay * t + 2.0 * scenario.link.latency;
    let b_dev = scenario.device.viscous_friction;
    let crit = big_k * (t / 2.0 + tau);
    let tb = scenario.coupling.haptic_period();
    StabilityBound {
        local_stiffness: k,
        force_scale: s,
        device_stiffness: big_k,
        hold_period: t,
        hold_delay: tau,
        device_damping: b_dev,
        hold_passive_damping: big_k * t / 2.0,
        hold_critical_damping: crit,
        hold_critical_hand_damping: (crit - b_dev).max(0.0),
        buffer_period: tb,
        buffer_critical_damping: big_k * tb / 2.0,
    }
}

/// The observed boundary of `mode` in a damping sweep: the largest swept
/// hand damping at which it trembles (`None` if it never does).
pub fn largest_trembling(rows: &[SweepRow], mode: CouplingMode) -> Option<f64> {
    rows.iter()
        .filter(|r| r.mode == mode && r.metrics.trembles)
        .map(|r| r.value)
        .reduce(f64::max)
}

/// The argument written next to the damping sweep's plot (markdown).
pub fn markdown(b: &StabilityBound, rows: &[SweepRow]) -> String {
    let mut s = String::from("# Hand damping sweep: where `hold` trembles, and why\n\n");
    s.push_str(
        "A virtual spring of stiffness `K` rendered through a zero-order hold of period `T` on a device \
         with physical damping `b` is passive only if `b > K T / 2` (Colgate & Schenkel 1997). With a \
         delay `τ` before the hold, the stability boundary is approximately `b > K (T/2 + τ)` (Gil, \
         Sánchez, Hulin, Preusche & Hirzinger 2009). The hand grips the device, so its damping adds to \
         the device's: `b = b_device + b_hand`.\n\n",
    );
    s.push_str(&format!(
        "In this scenario the thigh's local stiffness during the holds is `k` = {:.0} N/m (median of the \
         physics' estimate, direct run), displayed through the force scale {:.2}: `K` = {:.0} N/m at the \
         device, whose own friction is {:.2} N·s/m.\n\n",
        b.local_stiffness, b.force_scale, b.device_stiffness, b.device_damping
    ));
    s.push_str(&format!(
        "- Without the buffer model (`hold`): `T` = {:.1} ms, `τ` = {:.1} ms (compute delay plus the \
         link's round trip). `K T / 2` = {:.2} N·s/m; with the delay `K (T/2 + τ)` = {:.2} N·s/m, i.e. \
         a hand damping above {:.2} N·s/m is needed.\n",
        b.hold_period * 1e3,
        b.hold_delay * 1e3,
        b.hold_passive_damping,
        b.hold_critical_damping,
        b.hold_critical_hand_damping
    ));
    let verdict = if b.buffer_critical_damping < b.device_damping {
        "below the device's own friction: passive for any hand damping ≥ 0".to_string()
    } else {
        format!(
            "above the device's own friction: a hand damping above {:.2} N·s/m is needed, and direct \
             coupling (also rendered at 1 kHz) needs it as well. `K` exceeds what the device renders \
             stably at 1 kHz; the cure is to clamp the rendered stiffness, not the coupling",
            b.buffer_critical_damping - b.device_damping
        )
    };
    s.push_str(&format!(
        "- With the buffer model (`buffer`): the 1 kHz loop renders `K` from the local model without \
         delay, `T` = {:.1} ms: `K T / 2` = {:.2} N·s/m, {verdict}.\n\n",
        b.buffer_period * 1e3,
        b.buffer_critical_damping
    ));
    s.push_str(
        "| hand damping (N·s/m) | hold: losses | hold: p-p/mean | buffer: losses | buffer: p-p/mean | \
         direct: losses | direct: p-p/mean |\n",
    );
    s.push_str("|---:|---:|---:|---:|---:|---:|---:|\n");
    let values: Vec<f64> = rows
        .iter()
        .filter(|r| r.mode == CouplingMode::Hold)
        .map(|r| r.value)
        .collect();
    for v in values {
        let get = |m: CouplingMode| {
            rows.iter()
                .find(|r| r.mode == m && r.value == v)
                .map(|r| r.metrics)
        };
        if let (Some(h), Some(bu), Some(d)) = (
            get(CouplingMode::Hold),
            get(CouplingMode::Buffer),
            get(CouplingMode::Direct),
        ) {
            s.push_str(&format!(
                "| {v} | {} | {:.1} % | {} | {:.1} % | {} | {:.1} % |\n",
                h.hold_contact_losses,
                h.hold_oscillation * 100.0,
                bu.hold_contact_losses,
                bu.hold_oscillation * 100.0,
                d.hold_contact_losses,
                d.hold_oscillation * 100.0
            ));
        }
    }
    let observed = |m| match largest_trembling(rows, m) {
        Some(v) => format!("trembles up to a hand damping of {v} N·s/m"),
        None => "never trembles over the swept range".to_string(),
    };
    s.push_str(&format!(
        "\nObserved (trembling: a contact loss in a hold, or a hold peak-to-peak ≥ 20 % of its mean): \
         `hold` {}; `buffer` {}; `direct` {}. Predicted boundary for `hold`: {:.2} N·s/m of hand damping.\n",
        observed(CouplingMode::Hold),
        observed(CouplingMode::Buffer),
        observed(CouplingMode::Direct),
        b.hold_critical_hand_damping
    ));
    s
}
