//! `echothigh bench physics --compare`: a same-run A/B of the Newton
//! systems (issue 18): the block-sparse reference (`old`,
//! [`SystemForm::BlockSparse`]) against the edge form (`new`,
//! [`SystemForm::Edge`]). Two identical models take the same steps,
//! interleaved step by step (the order alternating, old–new then new–old,
//! so neither always runs on a warmer cache), each step timed in the
//! thread's CPU time; the report gives both medians, their ratio, and the
//! largest position gap between the two trajectories. On a shared machine
//! only the ratio is meaningful across runs.

use super::clock::{percentile, thread_cpu_us};
use super::physics_cases::{apply_patch_load, case_model, probe_patch, stage_medians, Scenario};
use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{
    ConfigError, ModelConfig, NoExtraForce, StepStats, StepTimings, SystemForm, ThighModel, Vec3,
};
use serde::Serialize;

/// One A/B case.
#[derive(Debug, Clone, Serialize)]
pub struct CompareReport {
    /// `press` (0–15 N at 1 Hz on the probe patch) or `contact` (the
    /// default mesh, probe pressed 10 mm, step plus haptic queries).
    pub case: &'static str,
    /// Nodes.
    pub nodes: usize,
    /// Measured steps of each form.
    pub steps: usize,
    /// Median thread CPU time per step of the block-sparse reference (µs).
    pub old_cpu_median_us: f64,
    /// Median thread CPU time per step of the edge form (µs).
    pub new_cpu_median_us: f64,
    /// `old / new` of the medians: the speed-up.
    pub ratio: f64,
    /// Steps per second of CPU time of the edge form, `1e6 / median`.
    pub new_cpu_steps_per_s: f64,
    /// Per-stage medians of the edge form (s, monotonic clock).
    pub new_stage_median_s: StepTimings,
    /// Per-stage medians of the reference (s, monotonic clock).
    pub old_stage_median_s: StepTimings,
    /// Largest `|x_new − x_old|∞` over nodes and steps (m).
    pub max_position_gap_m: f64,
    /// Mean PCG iterations per step, edge form / reference.
    pub cg_iterations_mean: [f64; 2],
}

/// Per-form measurements.
#[derive(Default)]
struct Side {
    cpu: Vec<f64>,
    stages: Vec<StepTimings>,
    cg: u64,
}

impl Side {
    fn record(&mut self, us: f64, s: &StepStats) {
        self.cpu.push(us);
        self.stages.push(s.timings);
        self.cg += u64::from(s.cg_iterations);
    }
}

fn gap(a: &ThighModel, b: &ThighModel) -> f64 {
    a.positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| (p - q).amax())
        .fold(0.0, f64::max)
}

fn report(
    case: &'static str,
    nodes: usize,
    mut new: Side,
    mut old: Side,
    max_gap: f64,
) -> CompareReport {
    let steps = new.cpu.len();
    new.cpu.sort_by(f64::total_cmp);
    old.cpu.sort_by(f64::total_cmp);
    let (n, o) = (percentile(&new.cpu, 0.5), percentile(&old.cpu, 0.5));
    CompareReport {
        case,
        nodes,
        steps,
        old_cpu_median_us: o,
        new_cpu_median_us: n,
        ratio: if n > 0.0 { o / n } else { 0.0 },
        new_cpu_steps_per_s: if n > 0.0 { 1e6 / n } else { 0.0 },
        new_stage_median_s: stage_medians(&new.stages),
        old_stage_median_s: stage_medians(&old.stages),
        max_position_gap_m: max_gap,
        cg_iterations_mean: [
            new.cg as f64 / steps.max(1) as f64,
            old.cg as f64 / steps.max(1) as f64,
        ],
    }
}

/// The press scenario on an `n_θ × n_z` mesh, both forms interleaved.
pub fn compare_press(
    n_theta: usize,
    n_z: usize,
    steps: usize,
    warmup: usize,
) -> Result<CompareReport, ConfigError> {
    let mut models = [
        case_model(Scenario::Press, n_theta, n_z)?,
        case_model(Scenario::Press, n_theta, n_z)?,
    ];
    models[1].set_system_form(SystemForm::BlockSparse);
    let h = models[0].config().integrator.time_step;
    let patch = probe_patch(&models[0]);
    let mut sides = [Side::default(), Side::default()];
    let mut max_gap = 0.0f64;
    for i in 0..warmup + steps {
        let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
        for k in order {
            let m = &mut models[k];
            let t = m.time();
            apply_patch_load(
                m,
                &patch,
                15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * t).cos()),
            );
            let c0 = thread_cpu_us();
            let s = m.step(h, &mut NoExtraForce);
            let us = thread_cpu_us() - c0;
            if i >= warmup {
                sides[k].record(us, &s);
            }
        }
        max_gap = max_gap.max(gap(&models[0], &models[1]));
    }
    let [new, old] = sides;
    Ok(report("press", models[0].node_count(), new, old, max_gap))
}

/// The default mesh with the probe pressed 10 mm (after a 0.5 s ramp) and
/// the haptic queries after every step, both forms interleaved; the time
/// of a step is the physics step plus its queries.
pub fn compare_contact(steps: usize) -> anyhow::Result<CompareReport> {
    let config = ModelConfig::default();
    let h = config.integrator.time_step;
    let top = config.thigh.semi_axis_y;
    let mut models = [ThighModel::new(&config)?, ThighModel::new(&config)?];
    models[1].set_system_form(SystemForm::BlockSparse);
    let mut contacts = [
        ProbeContact::new(&models[0], Probe::default(), ContactParams::default())?,
        ProbeContact::new(&models[1], Probe::default(), ContactParams::default())?,
    ];
    let pose = |d: f64| Probe::exam_pose(Vec3::new(0.0, top - d, 0.0));
    let ramp = 50;
    let mut sides = [Side::default(), Side::default()];
    let mut max_gap = 0.0f64;
    for i in 1..=ramp + steps {
        let depth = 0.010 * (i.min(ramp) as f64 / ramp as f64);
        let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
        for k in order {
            let c0 = thread_cpu_us();
            let s = contacts[k].step(&mut models[k], &pose(depth), h);
            let us = thread_cpu_us() - c0;
            if i > ramp {
                sides[k].record(us, &s.physics);
            }
        }
        max_gap = max_gap.max(gap(&models[0], &models[1]));
    }
    let [new, old] = sides;
    Ok(report("contact", models[0].node_count(), new, old, max_gap))
}
