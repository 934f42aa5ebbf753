//! One exam in one coupling mode on the deterministic virtual clock
//! (`echothigh_runtime::virtual_clock`), reduced to what the experiments
//! measure, and the same exam in several modes side by side.

use anyhow::{Context, Result};
use echothigh_device::HapticDevice;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::virtual_clock::VirtualRun;
use rayon::prelude::*;

/// What one run of the exam gives the experiments, one entry per haptic tick.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeTrace {
    /// Coupling mode of the run.
    pub mode: CouplingMode,
    /// Haptic period (s).
    pub period: f64,
    /// Tick times (s).
    pub t: Vec<f64>,
    /// Rendered force magnitude, tissue units (N).
    pub force: Vec<f64>,
    /// Force written to the device during each tick (N, device units).
    pub device_force: Vec<[f64; 3]>,
    /// End-effector position at the start of each tick (m).
    pub device_position: Vec<[f64; 3]>,
    /// End-effector position after the last tick (m).
    pub final_position: [f64; 3],
    /// True while the hand holds a press (the exam's hold phases).
    pub holding: Vec<bool>,
    /// Exam phase code per tick (`echothigh_runtime::virtual_clock::phase_code`).
    pub phase: Vec<u8>,
    /// Local stiffness `k` sent by the physics at each step (N/m, tissue units).
    pub step_stiffness: Vec<f64>,
    /// Time of each physics step (s).
    pub step_t: Vec<f64>,
    /// Non-finite forces caught before the device.
    pub faults: u64,
}

/// The lower-case name of a mode (`buffer`, `hold`, `direct`).
pub fn mode_name(mode: CouplingMode) -> &'static str {
    match mode {
        CouplingMode::Buffer => "buffer",
        CouplingMode::Hold => "hold",
        CouplingMode::Direct => "direct",
    }
}

/// Runs `scenario` (its exam, hand, device, thigh and seed) in `mode` for
/// `scenario.run.duration` seconds on the virtual clock.
pub fn run_mode(scenario: &Scenario, mode: CouplingMode) -> Result<ModeTrace> {
    let mut s = scenario.clone();
    s.coupling.mode = mode;
    // The experiments' reference is the whole mesh at the haptic rate: the
    // virtual clock has no deadline for the active window to meet.
    s.coupling.direct_window = false;
    s.validate()
        .with_context(|| format!("scenario in {} mode", mode_name(mode)))?;
    let mut run =
        VirtualRun::new(&s).with_context(|| format!("building the {} run", mode_name(mode)))?;
    run.run_for(s.run.duration)
        .with_context(|| format!("running the {} exam", mode_name(mode)))?;
    let ticks = run.ticks();
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    Ok(ModeTrace {
        mode,
        period: s.coupling.haptic_period(),
        t: ticks.iter().map(|r| r.t).collect(),
        force: ticks.iter().map(|r| norm(r.force)).collect(),
        device_force: ticks.iter().map(|r| r.device_force).collect(),
        device_position: ticks.iter().map(|r| r.device).collect(),
        final_position: run.device().position().into(),
        holding: ticks.iter().map(|r| r.holding).collect(),
        phase: ticks.iter().map(|r| r.phase).collect(),
        step_stiffness: run.steps().iter().map(|r| r.stiffness).collect(),
        step_t: run.steps().iter().map(|r| r.t).collect(),
        faults: run.faults(),
    })
}

/// Runs `scenario` in each of `modes`, in parallel (each run is independent
/// and deterministic, so the result does not depend on the scheduling), in
/// the order given.
pub fn run_modes(scenario: &Scenario, modes: &[CouplingMode]) -> Result<Vec<ModeTrace>> {
    modes.par_iter().map(|&m| run_mode(scenario, m)).collect()
}

/// Runs one job per scenario variant and mode, in parallel; results in the
/// order of `jobs`.
pub fn run_jobs(jobs: &[(Scenario, CouplingMode)]) -> Result<Vec<ModeTrace>> {
    jobs.par_iter().map(|(s, m)| run_mode(s, *m)).collect()
}
