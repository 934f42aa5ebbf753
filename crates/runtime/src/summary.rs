//! The JSON summary of a run, and where runs are written by default.

use echothigh_haptics::Percentiles;
use serde::Serialize;
use std::path::PathBuf;

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
    /// Of those, the ticks whose thread-CPU time alone exceeded the period:
    /// too long a computation; the others waited for the CPU (preempted or
    /// woken late on a busy machine) or were skipped after a late tick.
    pub missed_over_budget: u64,
    /// Wall-clock compute time of a haptic tick (s; over the loop's timing
    /// ring, the last 65 536 ticks by default; zeros on the virtual clock).
    pub tick_compute: Percentiles,
    /// Thread-CPU time of a haptic tick (s; same ticks): in `direct`
    /// coupling, the physics step's own cost per tick.
    pub tick_cpu: Percentiles,
    /// Whether the haptic loop's thread got real-time (FIFO) priority; without
    /// it a busy machine's other processes preempt the tick.
    pub realtime_priority: bool,
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
    /// Records the recorder could not take (the disk stalled for seconds); 0 normally.
    pub dropped_records: u64,
    /// Why the run ended: `completed`, `interrupted` (SIGINT, SIGTERM, a
    /// write error: the files hold everything up to then) or `peer_lost`.
    pub end: crate::deploy::RunEnd,
    /// True if a recorded value is NaN or infinite (the run diverged).
    pub non_finite: bool,
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

/// Default output directory of a run or experiment: `runs/<prefix>-<unix time>`.
pub fn default_out(prefix: &str) -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    PathBuf::from("runs").join(format!("{prefix}-{secs}"))
}
