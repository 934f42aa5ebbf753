//! `echothigh bench physics --direct-ticks N`: a same-run A/B of the
//! `direct` coupling's haptic tick (issue 18) on the built-in scenario (the
//! whole-leg mesh, its scripted exam): the real-time tick, which steps the
//! physics and renders its force ([`HapticTick::set_direct_queries`] off),
//! against the tick as it was, which also ran the haptic queries (`D`, `∇D`
//! and the stiffness solve) every tick. Two identical ticks, each with its
//! own scripted device and physics, run unpaced and interleaved tick by tick
//! (the order alternating), each tick timed in the thread's CPU time; the
//! forces of the two must agree to the bit (the queries only read the
//! model), which the report checks.
//!
//! With `--direct-window R` the second tick is instead the force-only tick
//! whose physics integrates only the active window of radius `R` m (what
//! `run --mode direct` runs, `coupling.direct_window`): its forces then
//! differ by the window's error, and the report gives the largest gap.

use super::clock::{percentile, thread_cpu_us};
use echothigh_model::StepTimings;
use echothigh_runtime::deploy::scripted_device;
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::tick::{HapticTick, TickObserver};
use echothigh_runtime::trace::PhysicsRecord;
use echothigh_transport::ProbeMsg;
use serde::Serialize;

/// Thread-CPU statistics of one side's ticks (µs).
#[derive(Debug, Clone, Serialize)]
pub struct TickCpu {
    /// Median.
    pub median_us: f64,
    /// 99th percentile (nearest rank).
    pub p99_us: f64,
    /// Largest.
    pub max_us: f64,
    /// Ticks whose CPU time alone exceeded the 1 kHz period.
    pub over_period: usize,
    /// Of those, the ticks whose Newton solve ran to its iteration cap
    /// (`integrator.newton_max_iterations`) without converging.
    pub over_period_newton_capped: usize,
}

/// A tick of the force-only side whose CPU time exceeded the period: what
/// its physics step did.
#[derive(Debug, Clone, Serialize)]
pub struct LongTick {
    /// Tick index.
    pub tick: usize,
    /// Thread-CPU time of the tick (µs).
    pub cpu_us: f64,
    /// Newton iterations of its step.
    pub newton_iterations: u32,
    /// PCG iterations of its step.
    pub cg_iterations: u32,
    /// Per-stage wall time of its step (s).
    pub stages: StepTimings,
}

/// Sees the tick's physics step.
#[derive(Default)]
struct LastStep(Option<PhysicsRecord>);

impl TickObserver for LastStep {
    fn on_physics_step(&mut self, _: &PhysicsSide, _: &ProbeMsg, step: &PhysicsRecord) {
        self.0 = Some(*step);
    }
}

impl TickCpu {
    /// From `(CPU µs, Newton iterations)` per tick.
    fn of(ticks: &[(f64, u32)], period_us: f64, newton_cap: u32) -> Self {
        let mut v: Vec<f64> = ticks.iter().map(|t| t.0).collect();
        v.sort_by(f64::total_cmp);
        let over = || ticks.iter().filter(|t| t.0 > period_us);
        TickCpu {
            median_us: percentile(&v, 0.5),
            p99_us: percentile(&v, 0.99),
            max_us: v.last().copied().unwrap_or(0.0),
            over_period: over().count(),
            over_period_newton_capped: over().filter(|t| t.1 >= newton_cap).count(),
        }
    }
}

/// The A/B's report.
#[derive(Debug, Clone, Serialize)]
pub struct DirectCompare {
    /// Nodes of the built-in scenario's mesh.
    pub nodes: usize,
    /// Ticks of each side.
    pub ticks: usize,
    /// The real-time tick: physics and force only.
    pub force_only: TickCpu,
    /// The other tick: with the haptic queries (the previous real-time
    /// tick), or force-only on the active window (`window_radius_m` > 0).
    pub with_queries: TickCpu,
    /// The other tick's active window radius (m; 0: none).
    pub window_radius_m: f64,
    /// Newton iterations of the other tick's steps, summed.
    pub other_newton_iterations: u64,
    /// Newton iterations of the force-only tick's steps, summed.
    pub force_only_newton_iterations: u64,
    /// `with_queries / force_only` of the medians.
    pub median_ratio: f64,
    /// Largest `|F_a − F_b|` over the ticks (N; 0 expected with the queries).
    pub max_force_gap_n: f64,
    /// The force-only side's ticks over the period (the first 50).
    pub long_ticks: Vec<LongTick>,
    /// Median over the force-only side's ticks in contact of each stage of
    /// the physics step (wall time, µs; [`StepTimings::NAMES`] order), and
    /// of the ticks' thread-CPU time: where an ordinary tick's time goes.
    pub contact_stage_medians_us: Vec<(String, f64)>,
}

/// The other tick's physics: without a window it runs the queries.
#[derive(Debug, Clone, Copy, Default)]
pub struct OtherTick {
    /// Active window radius (m; 0: no window, the queries instead).
    pub window_radius_m: f64,
}

impl OtherTick {
    /// True if the other tick is the tick with the queries.
    pub fn queries(&self) -> bool {
        self.window_radius_m == 0.0
    }
}

/// Runs `ticks` ticks of each side of the built-in scenario (a run longer
/// than the exam holds the probe where the script ends).
pub fn compare_direct(ticks: usize, o: OtherTick) -> anyhow::Result<DirectCompare> {
    let mut s = Scenario::builtin()?;
    s.coupling.mode = CouplingMode::Direct;
    // The reference side steps the whole mesh (the option's window is the
    // other side's, when asked for).
    s.coupling.direct_window = false;
    s.validate()?;
    let period = s.coupling.haptic_period();
    let scale = s.device().force_scale();
    let mut sides = Vec::new();
    for other in [false, true] {
        let queries = other && o.queries();
        let mut side = s.clone();
        if other {
            if o.window_radius_m > 0.0 {
                side.coupling.direct_window = true;
                side.integrator.window.radius = o.window_radius_m;
                side.integrator.window.margin =
                    side.integrator.window.margin.min(o.window_radius_m);
            }
            side.validate()?;
        }
        let (_, source) = haptic_side_for(CouplingMode::Direct, &side)?;
        let physics = PhysicsSide::new(&side)?;
        let mut tick = HapticTick::new(scripted_device(&s)?, source, scale, Some(physics), period);
        tick.set_orientation(s.probe_orientation()?);
        tick.set_direct_queries(queries);
        sides.push(tick);
    }
    let nodes = sides[0]
        .direct_physics()
        .map_or(0, |p| p.model().node_count());
    let mut cpu = [Vec::with_capacity(ticks), Vec::with_capacity(ticks)];
    let mut gap = 0.0f64;
    let mut last = LastStep::default();
    let mut long_ticks = Vec::new();
    let mut contact_stages: Vec<[f64; 10]> = Vec::with_capacity(ticks);
    for i in 0..ticks {
        let now = i as f64 * period;
        let order = if i % 2 == 0 { [0, 1] } else { [1, 0] };
        let mut force = [echothigh_haptics::Vec3::zeros(); 2];
        for k in order {
            let c0 = thread_cpu_us();
            let r = sides[k].tick(now, &mut last)?;
            let us = thread_cpu_us() - c0;
            let step = last.0.take().unwrap_or_default();
            cpu[k].push((us, step.newton_iterations));
            if k == 0 && step.stages.contact > 0.0 {
                let mut row = [0.0; 10];
                row[..9].copy_from_slice(&step.stages.values().map(|v| v * 1e6));
                row[9] = us;
                contact_stages.push(row);
            }
            if k == 0 && us > period * 1e6 && long_ticks.len() < 50 {
                long_ticks.push(LongTick {
                    tick: i,
                    cpu_us: us,
                    newton_iterations: step.newton_iterations,
                    cg_iterations: step.cg_iterations,
                    stages: step.stages,
                });
            }
            force[k] = r.force;
        }
        gap = gap.max((force[0] - force[1]).norm());
    }
    let newton = |c: &[(f64, u32)]| c.iter().map(|t| u64::from(t.1)).sum::<u64>();
    let (force_only_newton_iterations, other_newton_iterations) =
        (newton(&cpu[0]), newton(&cpu[1]));
    let [a, b] = cpu;
    let (period_us, cap) = (period * 1e6, s.integrator.newton_max_iterations);
    let force_only = TickCpu::of(&a, period_us, cap);
    let with_queries = TickCpu::of(&b, period_us, cap);
    Ok(DirectCompare {
        nodes,
        ticks,
        median_ratio: with_queries.median_us / force_only.median_us.max(1e-9),
        force_only,
        with_queries,
        window_radius_m: o.window_radius_m,
        other_newton_iterations,
        force_only_newton_iterations,
        max_force_gap_n: gap,
        long_ticks,
        contact_stage_medians_us: stage_medians(&contact_stages),
    })
}

/// Median of each column of `rows` (the nine stages, then the tick's CPU).
fn stage_medians(rows: &[[f64; 10]]) -> Vec<(String, f64)> {
    let names = StepTimings::NAMES.iter().copied().chain(["tick_cpu"]);
    names
        .enumerate()
        .map(|(c, name)| {
            let mut col: Vec<f64> = rows.iter().map(|r| r[c]).collect();
            col.sort_by(f64::total_cmp);
            (name.to_string(), percentile(&col, 0.5))
        })
        .collect()
}
