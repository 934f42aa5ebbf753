//! `echothigh run`: the main job. Runs a scripted compression exam with the
//! simulated hand and device and writes a run directory:
//! `haptic.csv` (1 kHz trace), `physics.csv` (physics trace), `summary.json`,
//! `force.png` and the effective `scenario.toml`.

use super::device_arg::DeviceArg;
use anyhow::{Context, Result};
use echothigh_experiments::plot::plot_force;
use echothigh_runtime::deploy::{
    run_threads, run_threads_on, run_virtual_streamed, summarize, RunEnd, RunOutput,
};
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::recorder::{Recording, Streams};
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::signals::stop_on_signals;
use echothigh_runtime::summary::Summary;
use echothigh_runtime::trace::{PhysicsRecord, TickRecord};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// How to deploy the run.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Deployment {
    /// Real-time threads of this process (physics, link, 1 kHz haptic loop).
    Threads,
    /// Deterministic virtual clock in one thread (runs as fast as it can).
    Virtual,
}

/// Arguments of `echothigh run`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  echothigh run\n  echothigh run --scenario my.toml --out runs/exam1\n  \
echothigh run --mode hold --duration 5\n  echothigh run --deployment virtual"
)]
pub struct Args {
    /// Scenario TOML (default: the built-in exam).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Output directory (default: runs/run-<unix time>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Deployment.
    #[arg(long, value_enum, default_value_t = Deployment::Threads)]
    pub deployment: Deployment,
    /// Override the coupling mode of the scenario.
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Override the run duration (s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// The device the haptic loop drives.
    #[command(flatten)]
    pub device: super::device_arg::DeviceArgs,
}

/// Coupling mode on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeArg {
    /// Buffer model (the paper's method).
    Buffer,
    /// Physics force held between steps (no buffer model).
    Hold,
    /// Physics at the haptic rate.
    Direct,
}

impl From<ModeArg> for CouplingMode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Buffer => CouplingMode::Buffer,
            ModeArg::Hold => CouplingMode::Hold,
            ModeArg::Direct => CouplingMode::Direct,
        }
    }
}

/// Loads the scenario and applies the command-line overrides.
pub fn load_scenario(
    path: Option<&Path>,
    mode: Option<ModeArg>,
    duration: Option<f64>,
) -> Result<Scenario> {
    let mut s = Scenario::load(path)?;
    if let Some(m) = mode {
        s.coupling.mode = m.into();
    }
    if let Some(d) = duration {
        s.run.duration = d;
    }
    s.validate().context("after command-line overrides")?;
    Ok(s)
}

pub use echothigh_runtime::summary::default_out;

/// Rows a run of `scenario` writes (haptic ticks and physics steps), for
/// the free-space check.
pub fn expected_rows(scenario: &Scenario) -> u64 {
    let c = &scenario.coupling;
    (scenario.run.duration * (c.haptic_rate + c.physics_rate)).ceil() as u64
}

/// The coupling mode's name as the files write it.
pub fn mode_name(scenario: &Scenario) -> String {
    format!("{:?}", scenario.coupling.mode).to_lowercase()
}

/// Writes the effective scenario (first, so that an interrupted run still
/// says what it ran).
pub fn write_scenario(dir: &Path, scenario: &Scenario) -> Result<()> {
    let path = dir.join("scenario.toml");
    let toml = toml::to_string(scenario).context("serializing the scenario")?;
    std::fs::write(&path, toml).with_context(|| format!("writing {}", path.display()))
}

/// Writes `summary.json` and `force.png` from the recorded trace; returns
/// the summary.
pub fn finish_run(
    dir: &Path,
    scenario: &Scenario,
    deployment: &str,
    ticks: &[TickRecord],
    steps: &[PhysicsRecord],
    out: &RunOutput,
) -> Result<()> {
    let summary = summarize(scenario, deployment, ticks, steps, &out.stats, out.end);
    let path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary)?;
    std::fs::write(&path, json + "\n").with_context(|| format!("writing {}", path.display()))?;
    plot_force(&dir.join("force.png"), &summary.mode, ticks, steps)?;
    report(dir, &summary);
    echothigh_runtime::integrity::check_finite(ticks, steps)
        .with_context(|| format!("the run diverged (data written to {})", dir.display()))?;
    verdict(dir, &summary)
}

fn report(dir: &Path, s: &Summary) {
    println!("run written to {}", dir.display());
    // Direct coupling steps the physics inside every tick: there is no
    // physics loop whose steps to count (the count read "0 physics steps").
    let physics = if s.mode == "direct" {
        format!(
            "the physics stepped in every tick ({:.1} Hz)",
            s.physics_rate
        )
    } else {
        format!(
            "{} physics steps at {:.1} Hz",
            s.physics_steps, s.physics_rate
        )
    };
    println!(
        "mode {} ({}): {} ticks at {:.0} Hz, {} missed deadlines; {physics}; \
         peak force {:.2} N (device {:.2} N)",
        s.mode,
        s.deployment,
        s.ticks,
        s.haptic_rate,
        s.missed_deadlines,
        s.peak_force,
        s.peak_device_force
    );
    if s.tick_cpu.count > 0 {
        let us = |x: f64| x * 1e6;
        println!(
            "tick thread-CPU median {:.0} µs, p99 {:.0} µs, max {:.0} µs (wall {:.0} / {:.0} / {:.0} µs); \
             {} of the missed deadlines had a tick over the period in thread-CPU time",
            us(s.tick_cpu.median),
            us(s.tick_cpu.p99),
            us(s.tick_cpu.max),
            us(s.tick_compute.median),
            us(s.tick_compute.p99),
            us(s.tick_compute.max),
            s.missed_over_budget
        );
    }
}

/// A run that diverged, lost its peer or was interrupted exits non-zero,
/// saying so (its data is written).
fn verdict(dir: &Path, s: &Summary) -> Result<()> {
    if s.non_finite {
        anyhow::bail!(
            "the run diverged: NaN or infinite values in {} (see summary.json)",
            dir.display()
        );
    }
    match s.end {
        RunEnd::Completed => Ok(()),
        RunEnd::PeerLost => anyhow::bail!(
            "the physics went silent during the run; the force was faded out (data written to {})",
            dir.display()
        ),
        RunEnd::Interrupted => anyhow::bail!(
            "interrupted at t = {:.3} s; every sample up to then is in {}",
            s.duration,
            dir.display()
        ),
    }
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), args.mode, args.duration)?;
    let chosen = args.device.chosen(scenario.device.kind);
    if args.deployment == Deployment::Virtual && chosen != DeviceArg::Simulated {
        anyhow::bail!(
            "device {:?} (from --device or the scenario's [device] kind) needs a real-time run: drop --deployment virtual",
            chosen
        );
    }
    // The device first: a missing driver is said before any file is made.
    let device = args.device.open(scenario.device.kind)?;
    // A real device's own peak force sets the patient's force scale.
    let mut scenario = scenario;
    if let Some(d) = &device {
        scenario.set_device_peak(d.max_force())?;
    }
    let dir = args.out.clone().unwrap_or_else(|| default_out("run"));
    let stop = stop_on_signals()?;
    let d = scenario.run.duration;
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:40}] {percent:>3}% {elapsed}")
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .progress_chars("=> "),
    );
    bar.set_message(format!("{:?} coupling, {d:.1} s exam", scenario.coupling.mode).to_lowercase());
    match args.deployment {
        Deployment::Virtual => {
            // Streamed like the real-time runs: the directory checked and
            // the files opened before the run, each 0.1 s of simulated time
            // written as it is made.
            let (recording, mut ticks, mut steps) = Recording::create(
                &dir,
                &mode_name(&scenario),
                Streams::BOTH,
                expected_rows(&scenario),
                stop.clone(),
            )?;
            write_scenario(&dir, &scenario)?;
            let out = run_virtual_streamed(
                &scenario,
                &stop,
                |f| bar.set_position((f * 1000.0) as u64),
                &mut ticks,
                &mut steps,
            );
            bar.finish_and_clear();
            drop((ticks, steps));
            let recorded = recording.finish();
            let out = out?;
            let recorded = recorded?;
            finish_run(
                &dir,
                &scenario,
                "virtual",
                &recorded.ticks,
                &recorded.steps,
                &out,
            )
        }
        Deployment::Threads => {
            let (recording, ticks, steps) = Recording::create(
                &dir,
                &mode_name(&scenario),
                Streams::BOTH,
                expected_rows(&scenario),
                stop.clone(),
            )?;
            write_scenario(&dir, &scenario)?;
            let done = Arc::new(AtomicBool::new(false));
            let (b, dn) = (bar.clone(), done.clone());
            let ticker = std::thread::spawn(move || {
                let t0 = std::time::Instant::now();
                while !dn.load(Ordering::Relaxed) {
                    b.set_position(((t0.elapsed().as_secs_f64() / d).min(1.0) * 1000.0) as u64);
                    std::thread::sleep(Duration::from_millis(100));
                }
            });
            let out = match device {
                Some(d) => run_threads_on(&scenario, stop, ticks, steps, d),
                None => run_threads(&scenario, stop, ticks, steps),
            };
            done.store(true, Ordering::Relaxed);
            let _ = ticker.join();
            bar.finish_and_clear();
            // The recorder is finished on every path: what it holds is written.
            let recorded = recording.finish();
            let out = out?;
            let recorded = recorded?;
            finish_run(
                &dir,
                &scenario,
                "threads",
                &recorded.ticks,
                &recorded.steps,
                &out,
            )
        }
    }
}
