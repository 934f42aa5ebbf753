//! The JSON summary of a run and its force plot.

use super::trace::{force_magnitudes, PhysicsRecord, TickRecord};
use crate::plot::{Figure, Panel, Series, PALETTE};
use anyhow::Result;
use serde::Serialize;
use std::path::Path;

/// Figures that describe a run (written as `summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Coupling mode.
    pub mode: String,
    /// Deployment: `virtual` (deterministic clock), `threads` or `processes`.
    pub deployment: String,
    /// Simulated duration (s).
    pub duration: f64,
    /// Haptic ticks run.
    pub ticks: u64,
    /// Ticks whose compute or wake-up missed the 1 ms deadline (0 on the virtual clock).
    pub missed_deadlines: u64,
    /// Haptic rate achieved (Hz).
    pub haptic_rate: f64,
    /// Physics steps run.
    pub physics_steps: u64,
    /// Physics rate achieved (Hz): steps over simulated (virtual) or wall (real-time) time.
    pub physics_rate: f64,
    /// Median wall-clock compute time of a physics step (s).
    pub physics_step_median: f64,
    /// Peak rendered force magnitude, tissue units (N).
    pub peak_force: f64,
    /// Peak device force magnitude (N).
    pub peak_device_force: f64,
    /// Ticks with non-zero force.
    pub contact_ticks: u64,
    /// Times the asymptote limiter acted over the run.
    pub limited_steps: u64,
    /// Non-finite values caught before reaching the device.
    pub faults: u64,
    /// Datagrams dropped as malformed, duplicated or stale (link statistics).
    pub link_dropped: u64,
}

/// Median of a slice (0 for an empty one).
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return 0.0;
    }
    v[v.len() / 2]
}

/// Writes the force magnitude over time as a PNG: the rendered force and the
/// physics' own contact force.
pub fn plot_force(
    path: &Path,
    mode: &str,
    ticks: &[TickRecord],
    physics: &[PhysicsRecord],
) -> Result<()> {
    let f = force_magnitudes(ticks);
    let rendered: Vec<(f64, f64)> = ticks.iter().zip(&f).map(|(r, f)| (r.t, *f)).collect();
    let phys: Vec<(f64, f64)> = physics
        .iter()
        .map(|r| {
            (
                r.t,
                (r.force[0].powi(2) + r.force[1].powi(2) + r.force[2].powi(2)).sqrt(),
            )
        })
        .collect();
    let fig = Figure::new(vec![Panel {
        title: format!("Force magnitude ({mode} coupling)"),
        x_label: "time (s)".into(),
        y_label: "force (N, tissue)".into(),
        series: vec![
            Series::line("rendered (1 kHz)", rendered, PALETTE[0]),
            Series::line("physics contact force", phys, PALETTE[1]).dashed(),
        ],
        ..Default::default()
    }]);
    fig.save_png(path)
}
