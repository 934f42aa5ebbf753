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
    /// The tick with the haptic queries (the previous real-time tick).
    pub with_queries: TickCpu,
    /// `with_queries / force_only` of the medians.
    pub median_ratio: f64,
    /// Largest `|F_a − F_b|` over the ticks (N; 0 expected).
    pub max_force_gap_n: f64,
    /// The force-only side's ticks over the period (the first 50).
    pub long_ticks: Vec<LongTick>,
}

/// Runs `ticks` ticks of each side of the built-in scenario (a run longer
/// than the exam holds the probe where the script ends).
pub fn compare_direct(ticks: usize) -> anyhow::Result<DirectCompare> {
    let mut s = Scenario::builtin()?;
    s.coupling.mode = CouplingMode::Direct;
    s.validate()?;
    let period = s.coupling.haptic_period();
    let scale = s.device().force_scale();
    let mut sides = Vec::new();
    for queries in [false, true] {
        let (_, source) = haptic_side_for(CouplingMode::Direct, &s)?;
        let physics = PhysicsSide::new(&s)?;
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
        max_force_gap_n: gap,
        long_ticks,
    })
}
