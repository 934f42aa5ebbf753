//! The three ways to run the system: deterministic virtual clock (one
//! thread), real-time threads of one process (the default), and the two
//! processes `physics-server` / `haptic-client` (see `crate::cmd::net`).

use super::client::{run_client, ClientConfig, ClientEnd, LoopParts};
use super::haptic_side::haptic_side_for;
use super::physics_loop::{physics_loop, Clock, PhysicsReport};
use super::physics_side::PhysicsSide;
use super::recorder::RecordSink;
use super::summary::{median, Summary};
use super::tick::TickDevice;
use super::trace::{force_magnitudes, PhysicsRecord, TickRecord};
use super::virtual_clock::VirtualRun;
use crate::live::CouplingMode;
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_device::{ExamScript, SimulatedDevice, SimulatedHand};
use echothigh_haptics::TimingSummary;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunEnd {
    /// The planned duration elapsed.
    Completed,
    /// The physics went silent: the force was faded out and the run stopped.
    PeerLost,
    /// Stopped from outside before its end (SIGINT, SIGTERM, a recorder that
    /// could not write).
    Interrupted,
}

/// What a run counted, besides its records.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunStats {
    /// Ticks that missed their deadline (0 on the virtual clock).
    pub missed_deadlines: u64,
    /// Physics rate achieved (Hz).
    pub physics_rate: f64,
    /// Non-finite values caught before the device.
    pub faults: u64,
    /// Datagrams dropped by the link (malformed, duplicated, stale).
    pub link_dropped: u64,
    /// Records the recorder's rings could not take (0 unless the disk stalled for seconds).
    pub dropped_records: u64,
    /// The haptic loop's timing (zeros on the virtual clock).
    pub loop_timing: TimingSummary,
}

/// Where a run's records end up.
pub struct RunOutput {
    /// 1 kHz trace (empty when streamed to a recorder).
    pub ticks: Vec<TickRecord>,
    /// Physics trace (empty when streamed to a recorder).
    pub steps: Vec<PhysicsRecord>,
    /// What the run counted.
    pub stats: RunStats,
    /// Why it ended.
    pub end: RunEnd,
}

/// Builds the scripted device of a scenario.
pub fn scripted_device(scenario: &Scenario) -> Result<SimulatedDevice> {
    let script = ExamScript::new(scenario.exam_script_config()?).map_err(anyhow::Error::msg)?;
    let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
    SimulatedDevice::with_hand(scenario.device(), hand).map_err(anyhow::Error::msg)
}

/// Runs the scenario on the deterministic virtual clock, as fast as it
/// can, calling `progress` with the fraction done every 0.1 s of simulated
/// time; `stop` ends it early (between those chunks). The trace is kept in
/// memory and returned.
pub fn run_virtual(
    scenario: &Scenario,
    stop: &AtomicBool,
    progress: impl FnMut(f64),
) -> Result<RunOutput> {
    run_virtual_with(scenario, stop, progress, None)
}

/// [`run_virtual`], streaming the trace: every 0.1 s of simulated time the
/// chunk's records go to `ticks` and `steps` (the recorder's rings, waiting
/// for room: nothing is dropped), and the returned output holds no records.
pub fn run_virtual_streamed(
    scenario: &Scenario,
    stop: &AtomicBool,
    progress: impl FnMut(f64),
    ticks: &mut RecordSink<TickRecord>,
    steps: &mut RecordSink<PhysicsRecord>,
) -> Result<RunOutput> {
    run_virtual_with(scenario, stop, progress, Some((ticks, steps)))
}

type Sinks<'a> = (
    &'a mut RecordSink<TickRecord>,
    &'a mut RecordSink<PhysicsRecord>,
);

fn run_virtual_with(
    scenario: &Scenario,
    stop: &AtomicBool,
    mut progress: impl FnMut(f64),
    mut sinks: Option<Sinks<'_>>,
) -> Result<RunOutput> {
    let mut run = VirtualRun::new(scenario)?;
    let d = scenario.run.duration;
    let chunk: f64 = 0.1;
    let mut t = 0.0;
    let mut end = RunEnd::Completed;
    let mut n_steps = 0usize;
    let mut hand_over = |run: &mut VirtualRun, n_steps: &mut usize| {
        if let Some((ticks, steps)) = sinks.as_mut() {
            run.drain_trace(|tr, st| {
                tr.iter().for_each(|r| ticks.push_wait(*r));
                st.iter().for_each(|r| steps.push_wait(*r));
                *n_steps += st.len();
            });
        }
    };
    while t < d - 1e-9 {
        if stop.load(Ordering::Relaxed) {
            end = RunEnd::Interrupted;
            break;
        }
        let step = chunk.min(d - t);
        let r = run.run_for(step);
        // What was computed is kept, the chunk that failed included.
        hand_over(&mut run, &mut n_steps);
        r?;
        t += step;
        progress(t / d);
    }
    let (a, b) = run.link_stats();
    let faults = run.faults();
    let (ticks, steps) = run.take_trace();
    n_steps += steps.len();
    let stats = RunStats {
        missed_deadlines: 0,
        physics_rate: n_steps as f64 / t.max(1e-9),
        faults,
        link_dropped: a.rejected() + b.rejected(),
        dropped_records: 0,
        loop_timing: TimingSummary::default(),
    };
    Ok(RunOutput {
        ticks,
        steps,
        stats,
        end,
    })
}

/// Runs the scenario as real-time threads of this process (physics, link,
/// 1 kHz haptic loop) for its duration or until `stop` is set. The records
/// go to `ticks` and `steps` (memory or the recorder's rings). Every thread
/// is joined on every path.
pub fn run_threads(
    scenario: &Scenario,
    stop: Arc<AtomicBool>,
    ticks: RecordSink<TickRecord>,
    steps: RecordSink<PhysicsRecord>,
) -> Result<RunOutput> {
    let device = scripted_device(scenario)?;
    run_threads_on(scenario, stop, ticks, steps, device)
}

/// [`run_threads`] on a given device: a real one (`--device NAME`, a
/// person's hand instead of the scenario's exam script) or a simulated one.
pub fn run_threads_on<D: TickDevice + Send + 'static>(
    scenario: &Scenario,
    stop: Arc<AtomicBool>,
    ticks: RecordSink<TickRecord>,
    mut steps: RecordSink<PhysicsRecord>,
    device: D,
) -> Result<RunOutput> {
    let c = &scenario.coupling;
    let (sink, source) = haptic_side_for(c.mode, scenario)?;
    let scale = scenario.device().force_scale();
    let config = ClientConfig {
        loop_config: &scenario.haptics.runner,
        duration: scenario.run.duration,
        peer_timeout: c.peer_timeout,
        stop: stop.clone(),
        orientation: scenario.probe_orientation()?,
    };
    if c.mode == CouplingMode::Direct {
        let physics = PhysicsSide::new(scenario)?;
        let parts = LoopParts {
            device,
            source,
            scale,
            direct_physics: Some(physics),
        };
        let report = run_client(None, sink, parts, config, ticks)?;
        return Ok(RunOutput {
            stats: RunStats {
                missed_deadlines: report.timing.missed_deadlines,
                // Direct coupling steps the physics every tick: its rate is
                // the haptic rate achieved ([`summarize`] computes it).
                physics_rate: 0.0,
                faults: report.faults,
                link_dropped: 0,
                dropped_records: report.dropped,
                loop_timing: report.timing,
            },
            end: client_end(report.end),
            ticks: report.ticks,
            steps: Vec::new(),
        });
    }
    let (haptic_end, mut physics_end) = scenario.in_process_link();
    let mut physics = PhysicsSide::new(scenario)?;
    let physics_stop = Arc::new(AtomicBool::new(false));
    let ps = physics_stop.clone();
    let rate = c.physics_rate;
    let realtime = scenario.haptics.runner.realtime_priority;
    let physics_thread = std::thread::Builder::new()
        .name("physics".into())
        .spawn(
            move || -> Result<(PhysicsReport, RecordSink<PhysicsRecord>)> {
                crate::physics_loop::request_physics_priority(realtime);
                let report = physics_loop(
                    &mut physics,
                    &mut physics_end,
                    Clock::start(),
                    &ps,
                    rate,
                    f64::INFINITY,
                    &mut steps,
                )?;
                Ok((report, steps))
            },
        )
        .context("starting the physics thread")?;
    let parts = LoopParts {
        device,
        source,
        scale,
        direct_physics: None,
    };
    let client = run_client(Some(Box::new(haptic_end)), sink, parts, config, ticks);
    physics_stop.store(true, Ordering::Relaxed);
    let physics = physics_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the physics thread panicked"));
    let report = client?;
    let (preport, steps) = physics??;
    Ok(RunOutput {
        stats: RunStats {
            missed_deadlines: report.timing.missed_deadlines,
            physics_rate: preport.rate,
            faults: report.faults,
            link_dropped: report.link.rejected(),
            dropped_records: report.dropped + steps.dropped(),
            loop_timing: report.timing,
        },
        end: client_end(report.end),
        ticks: report.ticks,
        steps: steps.into_records(),
    })
}

/// The run's end from the client's.
pub fn client_end(end: ClientEnd) -> RunEnd {
    match end {
        ClientEnd::Completed => RunEnd::Completed,
        ClientEnd::PeerLost => RunEnd::PeerLost,
        ClientEnd::Interrupted => RunEnd::Interrupted,
    }
}

/// The summary of a run from its records and counters.
pub fn summarize(
    scenario: &Scenario,
    deployment: &str,
    ticks: &[TickRecord],
    steps: &[PhysicsRecord],
    stats: &RunStats,
    end: RunEnd,
) -> Summary {
    let duration = scenario.run.duration;
    let f = force_magnitudes(ticks);
    let peak = f.iter().copied().fold(0.0, f64::max);
    let peak_dev = ticks
        .iter()
        .map(|r| {
            (r.device_force[0].powi(2) + r.device_force[1].powi(2) + r.device_force[2].powi(2))
                .sqrt()
        })
        .fold(0.0, f64::max);
    let span = match (ticks.first(), ticks.last()) {
        (Some(a), Some(b)) if b.t > a.t => b.t - a.t,
        _ => duration,
    };
    let compute: Vec<f64> = steps.iter().map(|s| s.compute_time).collect();
    let haptic_rate = if span > 0.0 {
        (ticks.len().saturating_sub(1)) as f64 / span
    } else {
        0.0
    };
    Summary {
        mode: format!("{:?}", scenario.coupling.mode).to_lowercase(),
        deployment: deployment.into(),
        duration: span,
        ticks: ticks.len() as u64,
        missed_deadlines: stats.missed_deadlines,
        missed_over_budget: stats.loop_timing.missed_over_budget,
        tick_compute: stats.loop_timing.compute,
        tick_cpu: stats.loop_timing.compute_cpu,
        realtime_priority: stats.loop_timing.realtime_priority,
        haptic_rate,
        physics_steps: steps.len() as u64,
        physics_rate: if scenario.coupling.mode == CouplingMode::Direct {
            haptic_rate
        } else {
            stats.physics_rate
        },
        physics_step_median: median(&compute),
        peak_force: peak,
        peak_device_force: peak_dev,
        contact_ticks: f.iter().filter(|&&x| x > 1e-9).count() as u64,
        limited_steps: steps.iter().map(|s| u64::from(s.limited)).sum(),
        faults: stats.faults,
        link_dropped: stats.link_dropped,
        dropped_records: stats.dropped_records,
        end,
        non_finite: non_finite(ticks, steps),
    }
}

/// True if any recorded number is NaN or infinite: the run diverged, and
/// says so (its command exits non-zero).
pub fn non_finite(ticks: &[TickRecord], steps: &[PhysicsRecord]) -> bool {
    let bad = |v: &[f64]| v.iter().any(|x| !x.is_finite());
    ticks.iter().any(|r| {
        bad(&r.device) || bad(&r.proxy) || bad(&r.force) || bad(&r.device_force) || !r.t.is_finite()
    }) || steps
        .iter()
        .any(|r| bad(&r.probe) || bad(&r.force) || bad(&r.gradient) || !r.stiffness.is_finite())
}
