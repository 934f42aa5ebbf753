//! `echothigh bench physics --compare`: a same-run A/B of the physics step
//! (issue 18): the default system (`new`: the edge form on SIMD kernels,
//! [`Kernels::Simd`]) against a baseline (`old`): the same edge form on the
//! previous scalar kernels ([`Baseline::Scalar`], [`Kernels::Scalar`]) or
//! the block-sparse reference ([`Baseline::BlockSparse`],
//! [`SystemForm::BlockSparse`]), or the haptic queries' previous
//! implementation ([`Baseline::ReferenceQueries`], [`QueryPath::Reference`]).
//! Two identical models take the same steps,
//! interleaved step by step (the order alternating, old–new then new–old,
//! so neither always runs on a warmer cache), each step timed in the
//! thread's CPU time; the report gives both medians, their ratio, and the
//! largest position gap between the two trajectories. On a shared machine
//! only the ratio is meaningful across runs.

use super::clock::{percentile, thread_cpu_us};
use super::physics_cases::{apply_patch_load, case_model, probe_patch, stage_medians, Scenario};
use echothigh_contact::{ContactParams, Probe, ProbeContact, QueryPath};
use echothigh_model::{
    ConfigError, Kernels, ModelConfig, NoExtraForce, StepStats, StepTimings, SystemForm,
    ThighModel, Vec3,
};
use serde::Serialize;

/// What the default system is compared against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Baseline {
    /// The edge form on the scalar kernels (the implementation before the
    /// SIMD kernels).
    Scalar,
    /// The block-sparse matrix and its PCG (the reference before the edge form).
    BlockSparse,
    /// The default system with the haptic queries' previous implementation
    /// ([`QueryPath::Reference`]: matrix-free `K w` after the stiffness
    /// solve, the signed distance at every sample, the broad-phase grid
    /// rebuilt from scratch); only the contact case differs, the press
    /// cases run the same code on both sides.
    ReferenceQueries,
}

impl Baseline {
    /// Sets `model` up as this baseline.
    pub fn apply(self, model: &mut ThighModel) {
        match self {
            Baseline::Scalar => model.set_kernels(Kernels::Scalar),
            Baseline::BlockSparse => model.set_system_form(SystemForm::BlockSparse),
            Baseline::ReferenceQueries => {}
        }
    }

    /// Sets the contact's queries up as this baseline.
    pub fn apply_contact(self, contact: &mut ProbeContact) {
        if self == Baseline::ReferenceQueries {
            contact.set_query_path(QueryPath::Reference);
        }
    }
}

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
    /// Median thread CPU time per step of the baseline (µs; with the
    /// contact case, the step plus its queries).
    pub old_cpu_median_us: f64,
    /// Median thread CPU time per step of the default system (µs).
    pub new_cpu_median_us: f64,
    /// `old / new` of the medians: the speed-up.
    pub ratio: f64,
    /// Steps per second of CPU time of the default system, `1e6 / median`.
    pub new_cpu_steps_per_s: f64,
    /// Contact case: median thread CPU time of the physics step alone and
    /// of the haptic queries alone, default system then baseline (µs).
    pub step_and_queries_cpu_median_us: Option<[[f64; 2]; 2]>,
    /// Per-stage medians of the default system (s, monotonic clock).
    pub new_stage_median_s: StepTimings,
    /// Per-stage medians of the baseline (s, monotonic clock).
    pub old_stage_median_s: StepTimings,
    /// Largest `|x_new − x_old|∞` over nodes and steps (m).
    pub max_position_gap_m: f64,
    /// Mean PCG iterations per step, default system / baseline.
    pub cg_iterations_mean: [f64; 2],
    /// Contact case: how the probe moved while measured.
    pub motion: Option<ContactMotion>,
    /// Contact case: measured steps whose stiffness query returned its warm
    /// start checked matrix-free, with no assembly
    /// ([`echothigh_contact::QueryStats::stiffness_unassembled`]), default
    /// system then baseline.
    pub stiffness_unassembled: Option<[u64; 2]>,
}

/// How the probe moves in the contact case of `--compare`, after its 0.5 s
/// ramp to 10 mm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum ContactMotion {
    /// Held 10 mm in.
    Held,
    /// Pressing and releasing between 10 and 0 mm at 1 Hz
    /// (`d = 5 mm · (1 + cos 2π t)`): the stiffness query's warm start
    /// rarely passes its stop test while the probe moves.
    Moving,
}

impl ContactMotion {
    /// Indentation (m) at `t` (s) after the ramp.
    pub fn depth(self, t: f64) -> f64 {
        match self {
            ContactMotion::Held => 0.010,
            ContactMotion::Moving => 0.005 * (1.0 + (std::f64::consts::TAU * t).cos()),
        }
    }
}

/// Per-form measurements.
#[derive(Default)]
struct Side {
    cpu: Vec<f64>,
    unassembled: u64,
    step_cpu: Vec<f64>,
    query_cpu: Vec<f64>,
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
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        percentile(v, 0.5)
    };
    let (n, o) = (median(&mut new.cpu), median(&mut old.cpu));
    let split = (!new.step_cpu.is_empty()).then(|| {
        [
            [median(&mut new.step_cpu), median(&mut new.query_cpu)],
            [median(&mut old.step_cpu), median(&mut old.query_cpu)],
        ]
    });
    CompareReport {
        case,
        nodes,
        steps,
        old_cpu_median_us: o,
        new_cpu_median_us: n,
        ratio: if n > 0.0 { o / n } else { 0.0 },
        new_cpu_steps_per_s: if n > 0.0 { 1e6 / n } else { 0.0 },
        step_and_queries_cpu_median_us: split,
        new_stage_median_s: stage_medians(&new.stages),
        old_stage_median_s: stage_medians(&old.stages),
        max_position_gap_m: max_gap,
        cg_iterations_mean: [
            new.cg as f64 / steps.max(1) as f64,
            old.cg as f64 / steps.max(1) as f64,
        ],
        motion: None,
        stiffness_unassembled: split.map(|_| [new.unassembled, old.unassembled]),
    }
}

/// The press scenario on an `n_θ × n_z` mesh, both systems interleaved.
pub fn compare_press(
    n_theta: usize,
    n_z: usize,
    steps: usize,
    warmup: usize,
    baseline: Baseline,
) -> Result<CompareReport, ConfigError> {
    let mut models = [
        case_model(Scenario::Press, n_theta, n_z)?,
        case_model(Scenario::Press, n_theta, n_z)?,
    ];
    baseline.apply(&mut models[1]);
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

/// The default mesh with the probe pressed 10 mm (after a 0.5 s ramp),
/// then held or moving ([`ContactMotion`]), and the haptic queries after
/// every step, both systems interleaved; the time of a step is the physics
/// step plus its queries (each also apart).
pub fn compare_contact(
    steps: usize,
    baseline: Baseline,
    motion: ContactMotion,
) -> anyhow::Result<CompareReport> {
    let config = ModelConfig::default();
    let h = config.integrator.time_step;
    let top = config.thigh.semi_axis_y;
    let mut models = [ThighModel::new(&config)?, ThighModel::new(&config)?];
    baseline.apply(&mut models[1]);
    let mut contacts = [
        ProbeContact::new(&models[0], Probe::default(), ContactParams::default())?,
        ProbeContact::new(&models[1], Probe::default(), ContactParams::default())?,
    ];
    baseline.apply_contact(&mut contacts[1]);
    let pose = |d: f64| Probe::exam_pose(Vec3::new(0.0, top - d, 0.0));
    let ramp = 50;
    let mut sides = [Side::default(), Side::default()];
    let mut max_gap = 0.0f64;
    for i in 1..=ramp + steps {
        let depth = if i <= ramp {
            0.010 * (i as f64 / ramp as f64)
        } else {
            motion.depth((i - ramp) as f64 * h)
        };
        let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
        for k in order {
            // ProbeContact::step is advance then sample, timed apart.
            let c0 = thread_cpu_us();
            let (mut s, _) = contacts[k].advance(&mut models[k], &pose(depth), h);
            let c1 = thread_cpu_us();
            let (_, query) = contacts[k].sample(&mut models[k]);
            let c2 = thread_cpu_us();
            s.timings.accumulate(&query.timings);
            if i > ramp {
                sides[k].record(c2 - c0, &s);
                sides[k].step_cpu.push(c1 - c0);
                sides[k].query_cpu.push(c2 - c1);
                sides[k].unassembled += u64::from(query.stiffness_unassembled);
            }
        }
        max_gap = max_gap.max(gap(&models[0], &models[1]));
    }
    let [new, old] = sides;
    let mut r = report("contact", models[0].node_count(), new, old, max_gap);
    r.motion = Some(motion);
    Ok(r)
}
