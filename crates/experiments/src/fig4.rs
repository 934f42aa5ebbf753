//! The paper's Fig. 4: the same scripted exam in `buffer`, `hold` (no
//! buffer model) and `direct` modes on the virtual clock, the force
//! magnitude of each, and their measures ([`ModeMetrics`]).
//!
//! Files written by [`write_fig4`]: `force.csv` (t and the three force
//! magnitudes at 1 kHz), `fig4.png` and `fig4.svg` (the three modes
//! overlaid, and a panel zoomed on the first press), `metrics.json`,
//! `table.md` (the printed table) and the effective `scenario.toml`.

use super::metrics::{measure, ModeMetrics};
use super::trace::{mode_name, run_modes, ModeTrace};
use crate::plot::{Figure, Panel, Series};
use anyhow::{bail, Context, Result};
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use echothigh_table::RowWriter;
use serde::Serialize;
use std::path::Path;

/// The modes of the figure, in the order of the traces and the table.
pub const MODES: [CouplingMode; 3] = [
    CouplingMode::Buffer,
    CouplingMode::Hold,
    CouplingMode::Direct,
];

/// Plot colours: buffer blue, hold red, direct black (dashed).
pub const COLORS: [(u8, u8, u8); 3] = [(31, 119, 180), (214, 39, 40), (20, 20, 20)];

/// The measures of the three modes and what they were measured on
/// (written as `metrics.json`; identical for identical scenarios and seeds).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fig4Metrics {
    /// Seed of the run (`run.seed`).
    pub seed: u64,
    /// Exam duration (s).
    pub duration: f64,
    /// Physics rate of `buffer` and `hold` (Hz).
    pub physics_rate: f64,
    /// Haptic rate, also the physics rate of `direct` (Hz).
    pub haptic_rate: f64,
    /// One-way link latency (s).
    pub latency: f64,
    /// Hand damping (N·s/m).
    pub hand_damping: f64,
    /// The buffer model (paper §4).
    pub buffer: ModeMetrics,
    /// No buffer model: the physics' force held between steps.
    pub hold: ModeMetrics,
    /// Physics at the haptic rate (the reference).
    pub direct: ModeMetrics,
}

/// The traces of the three modes (order of [`MODES`]) and their measures.
#[derive(Debug, Clone)]
pub struct Fig4Result {
    /// Traces: buffer, hold, direct.
    pub traces: Vec<ModeTrace>,
    /// Measures.
    pub metrics: Fig4Metrics,
}

impl Fig4Metrics {
    /// The measures of `mode`.
    pub fn of(&self, mode: CouplingMode) -> &ModeMetrics {
        match mode {
            CouplingMode::Buffer => &self.buffer,
            CouplingMode::Hold => &self.hold,
            CouplingMode::Direct => &self.direct,
        }
    }
}

/// Measures the three traces (buffer, hold, direct) of `scenario`.
pub fn measure_all(scenario: &Scenario, traces: &[ModeTrace]) -> Result<Fig4Metrics> {
    let [b, h, d] = traces else {
        bail!(
            "expected the buffer, hold and direct traces, got {}",
            traces.len()
        )
    };
    let reference = &d.force;
    Ok(Fig4Metrics {
        seed: scenario.run.seed,
        duration: scenario.run.duration,
        physics_rate: scenario.coupling.physics_rate,
        haptic_rate: scenario.coupling.haptic_rate,
        latency: scenario.link.latency,
        hand_damping: scenario.hand.damping,
        buffer: measure(b, reference),
        hold: measure(h, reference),
        direct: measure(d, reference),
    })
}

/// Runs the exam of `scenario` in the three modes and measures them.
pub fn fig4(scenario: &Scenario) -> Result<Fig4Result> {
    let traces = run_modes(scenario, &MODES)?;
    let metrics = measure_all(scenario, &traces)?;
    Ok(Fig4Result { traces, metrics })
}

/// The table of the measures (markdown).
pub fn table(m: &Fig4Metrics) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "Physics {:.0} Hz, haptics {:.0} Hz, one-way latency {:.0} ms, hand damping {} N·s/m, {:.1} s exam, seed {}.\n\n",
        m.physics_rate,
        m.haptic_rate,
        m.latency * 1e3,
        m.hand_damping,
        m.duration,
        m.seed
    ));
    s.push_str(
        "| mode | peak force (N) | max 1-tick change (N) | RMS tick change (N) | hold contact losses | \
         hold p-p / mean | energy > 30 Hz (N²·s) | RMS error vs direct (N) | RMS error (% peak) | \
         peak error (N) | device energy into user (J) |\n",
    );
    s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for mode in MODES {
        let x = m.of(mode);
        s.push_str(&format!(
            "| {} | {:.2} | {:.3} | {:.4} | {} | {:.1} % | {:.4} | {:.3} | {:.1} % | {:.2} | {:+.4} |\n",
            mode_name(mode),
            x.peak_force,
            x.max_tick_change,
            x.rms_tick_change,
            x.hold_contact_losses,
            x.hold_oscillation * 100.0,
            x.energy_above_30hz,
            x.rms_error,
            x.rms_error_rel * 100.0,
            x.peak_error,
            x.device_energy
        ));
    }
    s
}

/// The time window (s) of the first press and the start of the hold that
/// follows it, from the phase codes of `trace`; the whole run if it has no
/// press.
pub fn press_window(trace: &ModeTrace) -> (f64, f64) {
    let whole = (0.0, trace.t.last().copied().unwrap_or(1.0));
    let Some(start) = trace.phase.iter().position(|&p| p == 1) else {
        return whole;
    };
    let hold = trace.phase[start..]
        .iter()
        .position(|&p| p != 1)
        .map_or(trace.t.len() - 1, |i| start + i);
    let t0 = (trace.t[start] - 0.1).max(0.0);
    let t1 = (trace.t[hold] + 0.4).min(whole.1);
    (t0, t1)
}

fn series(traces: &[ModeTrace], window: Option<(f64, f64)>) -> Vec<Series> {
    traces
        .iter()
        .zip(COLORS)
        .map(|(tr, color)| {
            let pts: Vec<(f64, f64)> =
                tr.t.iter()
                    .zip(&tr.force)
                    .filter(|(t, _)| window.is_none_or(|(a, b)| **t >= a && **t <= b))
                    .map(|(&t, &f)| (t, f))
                    .collect();
            let name = match tr.mode {
                CouplingMode::Buffer => "with buffer model".to_string(),
                CouplingMode::Hold => "without buffer model (force held)".to_string(),
                CouplingMode::Direct => "direct (physics at 1 kHz)".to_string(),
            };
            let s = Series::line(name, pts, color);
            if tr.mode == CouplingMode::Direct {
                s.dashed()
            } else {
                s
            }
        })
        .collect()
}

/// The figure: the whole exam, and the first press zoomed.
pub fn figure(result: &Fig4Result) -> Figure {
    let m = &result.metrics;
    let window = result.traces.get(2).map_or((0.0, m.duration), press_window);
    let y_label = "force magnitude (N, tissue)".to_string();
    Figure::new(vec![
        Panel {
            title: format!(
                "Fig. 4: force during the exam (physics {:.0} Hz, haptics {:.0} Hz)",
                m.physics_rate, m.haptic_rate
            ),
            x_label: "time (s)".into(),
            y_label: y_label.clone(),
            series: series(&result.traces, None),
            ..Default::default()
        },
        Panel {
            title: "Zoom on the first press and the start of its hold".into(),
            x_label: "time (s)".into(),
            y_label,
            series: series(&result.traces, Some(window)),
            x_range: Some(window),
            ..Default::default()
        },
    ])
}

/// Writes `force.csv`: `t` (s) and the force magnitude of each mode (N).
pub fn write_force_csv(path: &Path, traces: &[ModeTrace]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = RowWriter::new(std::io::BufWriter::new(file));
    let mut write = || -> std::io::Result<()> {
        let mut header = vec!["t".to_string()];
        header.extend(traces.iter().map(|t| mode_name(t.mode).to_string()));
        header.extend(["phase".to_string(), "holding".to_string()]);
        w.record(header)?;
        let n = traces.iter().map(|t| t.force.len()).min().unwrap_or(0);
        let first = traces.first();
        for k in 0..n {
            let mut row = vec![format!("{:.3}", first.map_or(0.0, |t| t.t[k]))];
            row.extend(traces.iter().map(|tr| format!("{:.6}", tr.force[k])));
            let (phase, holding) = first.map_or((255, false), |t| (t.phase[k], t.holding[k]));
            row.extend([phase.to_string(), u8::from(holding).to_string()]);
            w.record(row)?;
        }
        w.flush()
    };
    write().with_context(|| format!("writing {}", path.display()))
}

/// Writes every file of the experiment into `dir` (created if needed) and
/// returns the table.
pub fn write_fig4(dir: &Path, scenario: &Scenario, result: &Fig4Result) -> Result<String> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    write_force_csv(&dir.join("force.csv"), &result.traces)?;
    let json = serde_json::to_string_pretty(&result.metrics).context("serializing the metrics")?;
    std::fs::write(dir.join("metrics.json"), json + "\n").context("writing metrics.json")?;
    let tab = table(&result.metrics);
    std::fs::write(dir.join("table.md"), &tab).context("writing table.md")?;
    let toml = toml::to_string(scenario).context("serializing the scenario")?;
    std::fs::write(dir.join("scenario.toml"), toml).context("writing scenario.toml")?;
    let fig = figure(result);
    fig.save_png(&dir.join("fig4.png"))?;
    fig.save_svg(&dir.join("fig4.svg"))?;
    Ok(tab)
}
