//! `echothigh run`: the main job. Runs a scripted compression exam with the
//! simulated hand and device and writes a run directory:
//! `haptic.csv` (1 kHz trace), `physics.csv` (physics trace), `summary.json`,
//! `force.png` and the effective `scenario.toml`.

use crate::live::CouplingMode;
use crate::runtime::deploy::{run_threads, run_virtual, RunOutput};
use crate::runtime::summary::plot_force;
use crate::runtime::trace::{write_physics, write_ticks};
use crate::scenario::Scenario;
use anyhow::{Context, Result};
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

/// Default run directory.
pub fn default_out(prefix: &str) -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    PathBuf::from("runs").join(format!("{prefix}-{secs}"))
}

/// Writes a run's files into `dir`.
pub fn write_run(dir: &Path, scenario: &Scenario, out: &RunOutput) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mode = out.summary.mode.clone();
    write_ticks(&dir.join("haptic.csv"), &mode, &out.ticks)?;
    write_physics(&dir.join("physics.csv"), &out.steps)?;
    let json = serde_json::to_string_pretty(&out.summary)?;
    std::fs::write(dir.join("summary.json"), json + "\n").context("writing summary.json")?;
    let toml = toml::to_string(scenario).context("serializing the scenario")?;
    std::fs::write(dir.join("scenario.toml"), toml).context("writing scenario.toml")?;
    plot_force(&dir.join("force.png"), &mode, &out.ticks, &out.steps)?;
    Ok(())
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), args.mode, args.duration)?;
    let dir = args.out.clone().unwrap_or_else(|| default_out("run"));
    let d = scenario.run.duration;
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:40}] {percent:>3}% {elapsed}")
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .progress_chars("=> "),
    );
    bar.set_message(format!("{:?} coupling, {d:.1} s exam", scenario.coupling.mode).to_lowercase());
    let out = match args.deployment {
        Deployment::Virtual => run_virtual(&scenario, |f| bar.set_position((f * 1000.0) as u64))?,
        Deployment::Threads => {
            let done = Arc::new(AtomicBool::new(false));
            let (b, dn) = (bar.clone(), done.clone());
            let ticker = std::thread::spawn(move || {
                let t0 = std::time::Instant::now();
                while !dn.load(Ordering::Relaxed) {
                    b.set_position(((t0.elapsed().as_secs_f64() / d).min(1.0) * 1000.0) as u64);
                    std::thread::sleep(Duration::from_millis(100));
                }
            });
            let r = run_threads(&scenario);
            done.store(true, Ordering::Relaxed);
            let _ = ticker.join();
            r?
        }
    };
    bar.finish_and_clear();
    write_run(&dir, &scenario, &out)?;
    super::integrity::check_finite(&out.ticks, &out.steps)
        .with_context(|| format!("the run diverged (data written to {})", dir.display()))?;
    let s = &out.summary;
    println!("run written to {}", dir.display());
    println!(
        "mode {} ({}): {} ticks at {:.0} Hz, {} missed deadlines; {} physics steps at {:.1} Hz; \
         peak force {:.2} N (device {:.2} N)",
        s.mode,
        s.deployment,
        s.ticks,
        s.haptic_rate,
        s.missed_deadlines,
        s.physics_steps,
        s.physics_rate,
        s.peak_force,
        s.peak_device_force
    );
    if out.peer_lost {
        anyhow::bail!(
            "the physics went silent during the run; the force was faded out (data written)"
        );
    }
    Ok(())
}
