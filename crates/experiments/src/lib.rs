//! Experiments on the running system (issue 6): the paper's Fig. 4 — the
//! force magnitude during an exam with the buffer model, without it (the
//! physics' force held between steps) and with direct coupling — with its
//! measures, and sweeps of the physics rate, the link latency and the hand's
//! damping. Everything runs on the deterministic virtual clock
//! (`echothigh_runtime::virtual_clock`), so the numbers do not depend on the
//! machine's load and the same seed gives the same `metrics.json`.
//!
//! - [`scenario`]: the default fig4 scenario (`scenarios/fig4.toml`, embedded);
//! - [`trace`]: one exam in one mode, reduced to what is measured;
//! - [`spectrum`], [`metrics`]: the measures;
//! - [`fig4`]: the three modes, `force.csv`, `fig4.png|svg`, `metrics.json`, the table;
//! - [`sweep`], [`stability`]: the sweeps and the Colgate–Schenkel argument;
//! - [`plot`]: figures (plotters), including a run's force plot;
//! - [`sheet`]: contact sheets of B-mode frames with their labels.

pub mod fig4;
pub mod metrics;
pub mod plot;
pub mod scenario;
pub mod sheet;
pub mod spectrum;
pub mod stability;
pub mod sweep;
pub mod trace;

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};
use sweep::SweepKind;

/// Where and what to run.
#[derive(clap::Args, Debug, Clone)]
pub struct CommonArgs {
    /// Scenario TOML (default: the embedded `scenarios/fig4.toml`).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Output directory (default: runs/<experiment>-<unix time>).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Arguments of a sweep.
#[derive(clap::Args, Debug, Clone)]
pub struct SweepArgs {
    /// Scenario and output directory.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Comma-separated values to sweep (Hz, ms or N·s/m; default: the issue's).
    #[arg(long, value_delimiter = ',')]
    pub values: Option<Vec<f64>>,
}

/// `echothigh experiment ...`
#[derive(clap::Subcommand, Debug, Clone)]
#[command(
    after_help = "Examples:\n  echothigh experiment fig4 --out runs/fig4\n  \
echothigh experiment sweep-rate --values 25,50,100,200,500\n  echothigh experiment sweep-damping --out runs/damping"
)]
pub enum ExperimentCommand {
    /// The paper's Fig. 4: buffer, hold and direct on the same exam, with metrics and plots.
    Fig4(CommonArgs),
    /// Physics rate (25–500 Hz) against the RMS error to direct and the contact losses.
    SweepRate(SweepArgs),
    /// One-way link latency (0–50 ms) against the RMS error to direct and the contact losses.
    SweepLatency(SweepArgs),
    /// Hand damping against trembling, with the Colgate–Schenkel argument (`stability.md`).
    SweepDamping(SweepArgs),
}

fn out_dir(arg: &Option<PathBuf>, name: &str) -> PathBuf {
    arg.clone()
        .unwrap_or_else(|| echothigh_runtime::summary::default_out(name))
}

/// Runs the fig4 experiment on the scenario of `path` (or the embedded one)
/// and writes it into `dir`; returns the table.
pub fn run_fig4(path: Option<&Path>, dir: &Path) -> Result<String> {
    let s = scenario::load_fig4(path)?;
    let result = fig4::fig4(&s)?;
    fig4::write_fig4(dir, &s, &result)
}

/// Runs a sweep and writes it into `dir` (for the damping sweep, also
/// `stability.md`); returns a short report.
pub fn run_sweep(
    kind: SweepKind,
    path: Option<&Path>,
    values: Option<&[f64]>,
    dir: &Path,
) -> Result<String> {
    let s = scenario::load_fig4(path)?;
    let defaults = kind.default_values();
    let values = values.unwrap_or(&defaults);
    if values.is_empty() {
        bail!("--values: at least one value is needed");
    }
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        bail!("--values: {v} is not a finite number");
    }
    let result = sweep::sweep(&s, kind, values)?;
    sweep::write_sweep(dir, kind, &result.rows)?;
    let mut report = format!("{} written to {}\n", kind.name(), dir.display());
    if kind == SweepKind::Damping {
        let base = s.hand.damping;
        let closest = result
            .directs
            .iter()
            .min_by(|a, b| (a.0 - base).abs().total_cmp(&(b.0 - base).abs()))
            .map(|(_, t)| t);
        if let Some(direct) = closest {
            let b = stability::bound(&s, direct);
            let md = stability::markdown(&b, &result.rows);
            std::fs::write(dir.join("stability.md"), &md).map_err(|e| {
                anyhow::anyhow!("writing {}: {e}", dir.join("stability.md").display())
            })?;
            report.push_str(&md);
        }
    }
    Ok(report)
}

/// Runs the command.
pub fn run(cmd: ExperimentCommand) -> Result<()> {
    let text = match &cmd {
        ExperimentCommand::Fig4(a) => {
            let dir = out_dir(&a.out, "fig4");
            let tab = run_fig4(a.scenario.as_deref(), &dir)?;
            format!("fig4 written to {}\n\n{tab}", dir.display())
        }
        ExperimentCommand::SweepRate(a) => sweep_cmd(SweepKind::Rate, a)?,
        ExperimentCommand::SweepLatency(a) => sweep_cmd(SweepKind::Latency, a)?,
        ExperimentCommand::SweepDamping(a) => sweep_cmd(SweepKind::Damping, a)?,
    };
    println!("{text}");
    Ok(())
}

fn sweep_cmd(kind: SweepKind, a: &SweepArgs) -> Result<String> {
    let dir = out_dir(&a.common.out, kind.name());
    run_sweep(
        kind,
        a.common.scenario.as_deref(),
        a.values.as_deref(),
        &dir,
    )
}
