//! Benchmark scenarios of the physics step behind `echothigh bench physics`
//! (timed with `std::time::Instant` and the thread's CPU clock, no I/O).
//!
//! Scenarios, all with the default tissue and integrator, `h` = 10 ms,
//! starting at rest:
//! - `free`: gravity on (−9.81 m/s² along y); the thigh sags under its own
//!   weight and oscillates (damped): free motion with no external force.
//! - `load`: gravity off, a constant inward nodal load of 10 N in total
//!   spread over the nodes under a 40 × 10 mm patch on the anterior line at
//!   mid-length (at least the nearest node and its two θ-neighbours):
//!   Newton and PCG work while the skin is pushed in and settles.
//! - `press`: the same patch with a load `15 N · ½(1 − cos 2π f t)` at
//!   f = 1 Hz: the tissue is never at rest (a probe pressing and releasing).
//!
//! Every case tells the model where the probe is (the patch's centre,
//! `ThighModel::set_focus`): with the active window (issue 18,
//! [`run_case_windowed`]) only the nodes around it are integrated.

use super::clock::{percentile, thread_cpu_us};
use echothigh_model::{
    ConfigError, ModelConfig, NoExtraForce, StepTimings, ThighModel, Vec3, WindowParams,
};
use serde::Serialize;
use std::time::Instant;

/// Which load a benchmark case applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scenario {
    /// Gravity, no external load.
    Free,
    /// Constant 10 N on the probe patch.
    Load,
    /// 0–15 N at 1 Hz on the probe patch.
    Press,
}

impl Scenario {
    /// All scenarios.
    pub const ALL: [Scenario; 3] = [Scenario::Free, Scenario::Load, Scenario::Press];
}

/// Mesh sizes `(n_θ, n_z, measured steps)`: ≈ 500, 1 000 (the default mesh),
/// 2 000, 8 000, 10 000 and 32 000 nodes, with cells ≈ 1.5 : 1 to 1 : 1.
pub const SIZES: [(usize, usize, usize); 6] = [
    (32, 16, 400),
    (48, 21, 400),
    (64, 32, 200),
    (128, 63, 60),
    (128, 79, 50),
    (256, 125, 15),
];

/// Timings and solver counts of one case.
#[derive(Debug, Clone, Serialize)]
pub struct CaseReport {
    /// Scenario.
    pub scenario: Scenario,
    /// Nodes (`n_theta · n_z`).
    pub nodes: usize,
    /// Nodes around.
    pub n_theta: usize,
    /// Rings along z.
    pub n_z: usize,
    /// Measured steps (after warm-up).
    pub steps: usize,
    /// Time step (s).
    pub h: f64,
    /// Median time per step (µs).
    pub median_us: f64,
    /// 90th percentile time per step (µs).
    pub p90_us: f64,
    /// Mean time per step (µs).
    pub mean_us: f64,
    /// Slowest step (µs).
    pub max_us: f64,
    /// Steps per second, `1e6 / mean_us`.
    pub steps_per_s: f64,
    /// Median thread CPU time per step (µs): per-core cost, insensitive to
    /// other processes on a shared machine (0 where not available).
    pub cpu_median_us: f64,
    /// 90th percentile thread CPU time per step (µs).
    pub cpu_p90_us: f64,
    /// Steps per second of CPU time, `1e6 / mean CPU µs`.
    pub cpu_steps_per_s: f64,
    /// Mean PCG iterations per step (all Newton iterations).
    pub cg_iterations_mean: f64,
    /// Most PCG iterations in one step.
    pub cg_iterations_max: u32,
    /// Mean Newton iterations (linear solves) per step.
    pub newton_iterations_mean: f64,
    /// Total asymptote-limiter activations.
    pub limited_total: u32,
    /// Fraction of steps whose Newton met its tolerance.
    pub converged_fraction: f64,
    /// Median over the measured steps of each stage's time (s, monotonic
    /// wall clock; see [`StepTimings`]).
    pub stage_median_s: StepTimings,
    /// The active window's radius (m), if the case ran with one.
    pub window_radius_m: Option<f64>,
    /// Nodes integrated implicitly at the last step (all free nodes
    /// without a window).
    pub integrated_nodes: usize,
}

/// Per-stage medians (s) of a run's step timings.
pub fn stage_medians(timings: &[StepTimings]) -> StepTimings {
    let mut column = Vec::with_capacity(timings.len());
    let mut median = |get: fn(&StepTimings) -> f64| {
        column.clear();
        column.extend(timings.iter().map(get));
        column.sort_by(f64::total_cmp);
        percentile(&column, 0.5)
    };
    StepTimings {
        broad_phase: median(|t| t.broad_phase),
        forces: median(|t| t.forces),
        assembly: median(|t| t.assembly),
        pcg: median(|t| t.pcg),
        stiffness_solve: median(|t| t.stiffness_solve),
        distance_query: median(|t| t.distance_query),
        step_fraction: median(|t| t.step_fraction),
        contact: median(|t| t.contact),
        window: median(|t| t.window),
    }
}

/// Builds the model of a case (default parameters, `n_θ × n_z`, gravity for `Free`).
pub fn case_model(
    scenario: Scenario,
    n_theta: usize,
    n_z: usize,
) -> Result<ThighModel, ConfigError> {
    let mut config = ModelConfig::default();
    config.thigh.n_theta = n_theta;
    config.thigh.n_z = n_z;
    if scenario == Scenario::Free {
        config.tissue.gravity = [0.0, -9.81, 0.0];
    }
    ThighModel::new(&config)
}

/// Nodes under a 40 × 10 mm patch (40 mm around θ, 10 mm along z) centred
/// on the anterior line at mid-length; at least the nearest node and its two
/// θ-neighbours.
pub fn probe_patch(model: &ThighModel) -> Vec<usize> {
    let mesh = model.mesh();
    let centre = mesh.rest_positions()[mesh.node_at(std::f64::consts::FRAC_PI_2, 0.0)];
    let mut nodes: Vec<usize> = (0..mesh.node_count())
        .filter(|&k| {
            let p = mesh.rest_positions()[k];
            (p.x - centre.x).abs() <= 0.020 && (p.z - centre.z).abs() <= 0.005 && p.y > 0.0
        })
        .collect();
    if nodes.len() < 3 {
        let (it, iz) = mesh.grid_index(mesh.node_at(std::f64::consts::FRAC_PI_2, 0.0));
        nodes = [mesh.n_theta() - 1, 0, 1]
            .iter()
            .map(|d| mesh.node_index(it + d, iz))
            .collect();
    }
    nodes
}

/// Sets an inward load of `total` newtons spread evenly over `patch`.
pub fn apply_patch_load(model: &mut ThighModel, patch: &[usize], total: f64) {
    let normals: Vec<Vec3> = patch
        .iter()
        .map(|&k| model.mesh().rest_normals()[k])
        .collect();
    let share = total / patch.len() as f64;
    let ext = model.external_forces_mut();
    for (&k, n) in patch.iter().zip(&normals) {
        ext[k] = -n * share;
    }
}

/// Runs `warmup` then `steps` timed steps of a case.
pub fn run_case(
    scenario: Scenario,
    n_theta: usize,
    n_z: usize,
    steps: usize,
    warmup: usize,
) -> Result<CaseReport, ConfigError> {
    run_case_windowed(scenario, (n_theta, n_z), None, steps, warmup)
}

/// [`run_case`], with the active window of radius `window` (m, margin
/// 10 mm) if given (issue 18).
pub fn run_case_windowed(
    scenario: Scenario,
    (n_theta, n_z): (usize, usize),
    window: Option<f64>,
    steps: usize,
    warmup: usize,
) -> Result<CaseReport, ConfigError> {
    let mut model = case_model(scenario, n_theta, n_z)?;
    if let Some(radius) = window {
        let mut config = model.config().clone();
        config.integrator.window = WindowParams {
            enabled: true,
            radius,
            margin: 0.01,
        };
        model = ThighModel::new(&config)?;
    }
    let h = model.config().integrator.time_step;
    let patch = probe_patch(&model);
    let focus =
        model.mesh().rest_positions()[model.mesh().node_at(std::f64::consts::FRAC_PI_2, 0.0)];
    let load = |model: &mut ThighModel, t: f64| match scenario {
        Scenario::Free => {}
        Scenario::Load => apply_patch_load(model, &patch, 10.0),
        Scenario::Press => {
            let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * t).cos());
            apply_patch_load(model, &patch, f);
        }
    };
    let mut times = Vec::with_capacity(steps);
    let mut cpu = Vec::with_capacity(steps);
    let mut stages = Vec::with_capacity(steps);
    let (mut cg, mut cg_max, mut newton, mut limited, mut converged) = (0u64, 0u32, 0u64, 0u32, 0);
    for i in 0..warmup + steps {
        let t = model.time();
        load(&mut model, t);
        let (start, cpu_start) = (Instant::now(), thread_cpu_us());
        model.set_focus(&focus);
        let s = model.step(h, &mut NoExtraForce);
        let (elapsed, cpu_elapsed) = (
            start.elapsed().as_secs_f64() * 1e6,
            thread_cpu_us() - cpu_start,
        );
        if i >= warmup {
            times.push(elapsed);
            cpu.push(cpu_elapsed);
            stages.push(s.timings);
            cg += u64::from(s.cg_iterations);
            cg_max = cg_max.max(s.cg_iterations);
            newton += u64::from(s.newton_iterations);
            limited += s.limited;
            converged += usize::from(s.converged);
        }
    }
    let n = times.len().max(1) as f64;
    let mean = times.iter().sum::<f64>() / n;
    times.sort_by(f64::total_cmp);
    let cpu_mean = cpu.iter().sum::<f64>() / n;
    cpu.sort_by(f64::total_cmp);
    Ok(CaseReport {
        scenario,
        nodes: model.node_count(),
        n_theta,
        n_z,
        steps,
        h,
        median_us: percentile(&times, 0.5),
        p90_us: percentile(&times, 0.9),
        mean_us: mean,
        max_us: times.last().copied().unwrap_or(0.0),
        steps_per_s: if mean > 0.0 { 1e6 / mean } else { 0.0 },
        cpu_median_us: percentile(&cpu, 0.5),
        cpu_p90_us: percentile(&cpu, 0.9),
        cpu_steps_per_s: if cpu_mean > 0.0 { 1e6 / cpu_mean } else { 0.0 },
        cg_iterations_mean: cg as f64 / n,
        cg_iterations_max: cg_max,
        newton_iterations_mean: newton as f64 / n,
        limited_total: limited,
        converged_fraction: converged as f64 / n,
        stage_median_s: stage_medians(&stages),
        window_radius_m: window,
        integrated_nodes: model.window().map_or_else(
            || model.fixed().iter().filter(|&&f| !f).count(),
            |w| w.core_count(),
        ),
    })
}
