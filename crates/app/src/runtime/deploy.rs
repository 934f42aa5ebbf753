//! The three ways to run the system: deterministic virtual clock (one
//! thread), real-time threads of one process (the default), and the two
//! processes `physics-server` / `haptic-client` (see `crate::cmd::net`).

use super::client::{run_client, ClientEnd, LoopParts};
use super::haptic_side::haptic_side_for;
use super::physics_loop::{physics_loop, Clock, PhysicsReport};
use super::physics_side::PhysicsSide;
use super::summary::{median, Summary};
use super::trace::{force_magnitudes, PhysicsRecord, TickRecord};
use super::virtual_clock::VirtualRun;
use crate::live::CouplingMode;
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_device::{ExamScript, SimulatedDevice, SimulatedHand};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Where a run's records end up.
pub struct RunOutput {
    /// 1 kHz trace.
    pub ticks: Vec<TickRecord>,
    /// Physics trace.
    pub steps: Vec<PhysicsRecord>,
    /// Summary figures.
    pub summary: Summary,
    /// True if the run stopped early because the physics went silent.
    pub peer_lost: bool,
}

/// Builds the scripted device of a scenario.
pub fn scripted_device(scenario: &Scenario) -> Result<SimulatedDevice> {
    let script = ExamScript::new(scenario.exam.clone()).map_err(anyhow::Error::msg)?;
    let hand = SimulatedHand::scripted(scenario.hand, script).map_err(anyhow::Error::msg)?;
    SimulatedDevice::with_hand(scenario.device, hand).map_err(anyhow::Error::msg)
}

/// Runs the scenario on the deterministic virtual clock.
pub fn run_virtual(scenario: &Scenario, mut progress: impl FnMut(f64)) -> Result<RunOutput> {
    let mut run = VirtualRun::new(scenario)?;
    let d = scenario.run.duration;
    let chunk: f64 = 0.1;
    let mut t = 0.0;
    while t < d - 1e-9 {
        let step = chunk.min(d - t);
        run.run_for(step)?;
        t += step;
        progress(t / d);
    }
    let (a, b) = run.link_stats();
    let limited = run.steps.iter().map(|s| u64::from(s.limited)).sum();
    let summary = summarize(
        scenario,
        "virtual",
        &run.ticks,
        &run.steps,
        0,
        d,
        run.steps.len() as f64 / d,
        run.faults(),
        a.duplicate + a.stale + a.malformed + b.duplicate + b.stale + b.malformed,
        limited,
    );
    Ok(RunOutput {
        ticks: std::mem::take(&mut run.ticks),
        steps: std::mem::take(&mut run.steps),
        summary,
        peer_lost: false,
    })
}

/// Runs the scenario in real time as threads of this process.
pub fn run_threads(scenario: &Scenario) -> Result<RunOutput> {
    let c = &scenario.coupling;
    let duration = scenario.run.duration;
    let device = scripted_device(scenario)?;
    let (sink, source) = haptic_side_for(c.mode, scenario)?;
    let scale = scenario.device.force_scale();
    if c.mode == CouplingMode::Direct {
        let physics = PhysicsSide::new(scenario)?;
        let parts = LoopParts {
            device,
            source,
            scale,
            direct_physics: Some(physics),
        };
        let report = run_client(
            None,
            sink,
            parts,
            &scenario.haptics.runner,
            duration,
            c.peer_timeout,
        )?;
        let summary = summarize(
            scenario,
            "threads",
            &report.ticks,
            &[],
            report.timing.missed_deadlines,
            duration,
            c.haptic_rate,
            report.faults,
            0,
            0,
        );
        return Ok(RunOutput {
            ticks: report.ticks,
            steps: Vec::new(),
            summary,
            peer_lost: false,
        });
    }
    let (haptic_end, mut physics_end) = scenario.in_process_link();
    let mut physics = PhysicsSide::new(scenario)?;
    let stop = Arc::new(AtomicBool::new(false));
    let physics_stop = stop.clone();
    let rate = c.physics_rate;
    let n_steps = (duration * rate * 1.5) as usize + 16;
    let physics_thread = std::thread::Builder::new()
        .name("physics".into())
        .spawn(move || -> Result<(PhysicsReport, Vec<PhysicsRecord>)> {
            let mut records = Vec::with_capacity(n_steps);
            let report = physics_loop(
                &mut physics,
                &mut physics_end,
                Clock::start(),
                &physics_stop,
                rate,
                f64::INFINITY,
                &mut records,
            )?;
            Ok((report, records))
        })
        .context("starting the physics thread")?;
    let parts = LoopParts {
        device,
        source,
        scale,
        direct_physics: None,
    };
    let client = run_client(
        Some(Box::new(haptic_end)),
        sink,
        parts,
        &scenario.haptics.runner,
        duration,
        c.peer_timeout,
    );
    stop.store(true, Ordering::Relaxed);
    let (preport, steps) = physics_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the physics thread panicked"))??;
    let report = client?;
    let limited = steps.iter().map(|s| u64::from(s.limited)).sum();
    let summary = summarize(
        scenario,
        "threads",
        &report.ticks,
        &steps,
        report.timing.missed_deadlines,
        duration,
        preport.rate,
        report.faults,
        report.link.duplicate + report.link.stale + report.link.malformed,
        limited,
    );
    Ok(RunOutput {
        ticks: report.ticks,
        steps,
        summary,
        peer_lost: report.end == ClientEnd::PeerLost,
    })
}

/// Builds the summary of a run.
#[allow(clippy::too_many_arguments)]
pub fn summarize(
    scenario: &Scenario,
    deployment: &str,
    ticks: &[TickRecord],
    steps: &[PhysicsRecord],
    missed: u64,
    duration: f64,
    physics_rate: f64,
    faults: u64,
    link_dropped: u64,
    limited: u64,
) -> Summary {
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
    Summary {
        mode: format!("{:?}", scenario.coupling.mode).to_lowercase(),
        deployment: deployment.into(),
        duration: span,
        ticks: ticks.len() as u64,
        missed_deadlines: missed,
        haptic_rate: if span > 0.0 {
            (ticks.len().saturating_sub(1)) as f64 / span
        } else {
            0.0
        },
        physics_steps: steps.len() as u64,
        physics_rate,
        physics_step_median: median(&compute),
        peak_force: peak,
        peak_device_force: peak_dev,
        contact_ticks: f.iter().filter(|&&x| x > 1e-9).count() as u64,
        limited_steps: limited,
        faults,
        link_dropped,
    }
}
