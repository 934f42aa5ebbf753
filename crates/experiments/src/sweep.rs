//! Sweeps of one parameter of the fig4 scenario (physics rate, one-way link
//! latency, hand damping) against the measures of `buffer` and `hold`, with
//! `direct` as the reference: where the buffer model's advantage starts and
//! ends, which the paper does not show.

use super::metrics::{measure, ModeMetrics};
use super::trace::{mode_name, run_jobs, ModeTrace};
use crate::plot::{Figure, Panel, Series};
use anyhow::{Context, Result};
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use echothigh_table::RowWriter;
use std::path::Path;

/// The parameter a sweep varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SweepKind {
    /// `coupling.physics_rate` (Hz) of `buffer` and `hold`.
    Rate,
    /// `link.latency`, one way (values in ms).
    Latency,
    /// `hand.damping` (N·s/m).
    Damping,
}

/// One measured point of a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepRow {
    /// Parameter value, in the unit of [`SweepKind::unit`].
    pub value: f64,
    /// Coupling mode.
    pub mode: CouplingMode,
    /// Measures against the `direct` run of the same parameter value.
    pub metrics: ModeMetrics,
}

impl SweepKind {
    /// Short name, also the file stem (`sweep-rate`, ...).
    pub fn name(self) -> &'static str {
        match self {
            SweepKind::Rate => "sweep-rate",
            SweepKind::Latency => "sweep-latency",
            SweepKind::Damping => "sweep-damping",
        }
    }

    /// CSV column of the parameter, with its unit.
    pub fn column(self) -> &'static str {
        match self {
            SweepKind::Rate => "physics_rate_hz",
            SweepKind::Latency => "latency_ms",
            SweepKind::Damping => "hand_damping_ns_per_m",
        }
    }

    /// Unit of the values.
    pub fn unit(self) -> &'static str {
        match self {
            SweepKind::Rate => "Hz",
            SweepKind::Latency => "ms",
            SweepKind::Damping => "N·s/m",
        }
    }

    /// Axis label.
    pub fn x_label(self) -> &'static str {
        match self {
            SweepKind::Rate => "physics rate (Hz)",
            SweepKind::Latency => "one-way link latency (ms)",
            SweepKind::Damping => "hand damping (N·s/m)",
        }
    }

    /// The values: 25–500 Hz, 0–50 ms; damping across the human range
    /// (2–10 N·s/m) and beyond, past the boundary of `hold`.
    pub fn default_values(self) -> Vec<f64> {
        match self {
            SweepKind::Rate => vec![25.0, 50.0, 100.0, 200.0, 500.0],
            SweepKind::Latency => vec![0.0, 5.0, 20.0, 50.0],
            SweepKind::Damping => vec![0.0, 2.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 80.0],
        }
    }

    /// Sets the parameter of `s` to `value` (unit of [`Self::unit`]).
    pub fn apply(self, s: &mut Scenario, value: f64) {
        match self {
            SweepKind::Rate => s.coupling.physics_rate = value,
            SweepKind::Latency => s.link.latency = value * 1e-3,
            SweepKind::Damping => s.hand.damping = value,
        }
    }

    /// Whether the `direct` reference changes with the parameter (the hand
    /// does; the physics rate and the link do not: `direct` steps the physics
    /// every tick, without the link).
    pub fn changes_direct(self) -> bool {
        self == SweepKind::Damping
    }
}

/// A sweep's measures and its `direct` reference runs.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// Per value: buffer, hold, direct.
    pub rows: Vec<SweepRow>,
    /// The `direct` runs with the parameter value they ran at (one, at the
    /// first value, when the parameter does not change `direct`).
    pub directs: Vec<(f64, ModeTrace)>,
}

/// Runs `buffer` and `hold` at every value, and `direct` once or (when the
/// parameter changes it) at every value, all in parallel; measures each
/// against its `direct`.
pub fn sweep(base: &Scenario, kind: SweepKind, values: &[f64]) -> Result<Sweep> {
    // Per value: the job indices of its buffer, hold and direct runs.
    let mut jobs = Vec::new();
    let mut index = Vec::with_capacity(values.len());
    for &v in values {
        let mut s = base.clone();
        kind.apply(&mut s, v);
        s.validate()
            .with_context(|| format!("{} at {v} {}", kind.name(), kind.unit()))?;
        let first = jobs.len();
        jobs.push((s.clone(), CouplingMode::Buffer));
        jobs.push((s.clone(), CouplingMode::Hold));
        let direct = if kind.changes_direct() || first == 0 {
            jobs.push((s, CouplingMode::Direct));
            first + 2
        } else {
            2
        };
        index.push((v, first, direct));
    }
    let traces = run_jobs(&jobs)?;
    let mut rows = Vec::with_capacity(3 * values.len());
    for &(value, first, direct) in &index {
        let reference = &traces[direct].force;
        for (mode, trace) in [
            (CouplingMode::Buffer, &traces[first]),
            (CouplingMode::Hold, &traces[first + 1]),
            (CouplingMode::Direct, &traces[direct]),
        ] {
            rows.push(SweepRow {
                value,
                mode,
                metrics: measure(trace, reference),
            });
        }
    }
    let mut directs = Vec::new();
    for (i, ((_, mode), trace)) in jobs.iter().zip(traces).enumerate() {
        if *mode == CouplingMode::Direct {
            let value = index.iter().find(|x| x.2 == i).map_or(f64::NAN, |x| x.0);
            directs.push((value, trace));
        }
    }
    Ok(Sweep { rows, directs })
}

/// Writes the rows as CSV.
pub fn write_sweep_csv(path: &Path, kind: SweepKind, rows: &[SweepRow]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = RowWriter::new(std::io::BufWriter::new(file));
    let mut write = || -> std::io::Result<()> {
        w.record([
            kind.column(),
            "mode",
            "rms_error_n",
            "rms_error_rel",
            "peak_error_n",
            "hold_contact_losses",
            "hold_zero_ticks",
            "hold_oscillation",
            "max_tick_change_n",
            "rms_tick_change_n",
            "energy_above_30hz_n2s",
            "device_energy_j",
            "peak_force_n",
            "trembles",
        ])?;
        for r in rows {
            let m = &r.metrics;
            let f = |v: f64| format!("{v:.6}");
            w.record([
                r.value.to_string(),
                mode_name(r.mode).to_string(),
                f(m.rms_error),
                f(m.rms_error_rel),
                f(m.peak_error),
                m.hold_contact_losses.to_string(),
                m.hold_zero_ticks.to_string(),
                f(m.hold_oscillation),
                f(m.max_tick_change),
                f(m.rms_tick_change),
                f(m.energy_above_30hz),
                f(m.device_energy),
                f(m.peak_force),
                u8::from(m.trembles).to_string(),
            ])?;
        }
        w.flush()
    };
    write().with_context(|| format!("writing {}", path.display()))
}

fn curve(
    rows: &[SweepRow],
    mode: CouplingMode,
    y: impl Fn(&ModeMetrics) -> f64,
) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.mode == mode)
        .map(|r| (r.value, y(&r.metrics)))
        .collect()
}

fn panel(
    kind: SweepKind,
    rows: &[SweepRow],
    title: &str,
    y_label: &str,
    y: impl Fn(&ModeMetrics) -> f64 + Copy,
) -> Panel {
    let mut series = vec![
        Series::line(
            "with buffer model",
            curve(rows, CouplingMode::Buffer, y),
            super::fig4::COLORS[0],
        ),
        Series::line(
            "without buffer model (held)",
            curve(rows, CouplingMode::Hold, y),
            super::fig4::COLORS[1],
        ),
    ];
    if kind.changes_direct() {
        series.push(
            Series::line(
                "direct",
                curve(rows, CouplingMode::Direct, y),
                super::fig4::COLORS[2],
            )
            .dashed(),
        );
    }
    Panel {
        title: title.into(),
        x_label: kind.x_label().into(),
        y_label: y_label.into(),
        series,
        ..Default::default()
    }
}

/// The sweep's figure: RMS error to `direct`, contact losses during the
/// holds, and the holds' relative peak-to-peak force.
pub fn sweep_figure(kind: SweepKind, rows: &[SweepRow]) -> Figure {
    Figure::new(vec![
        panel(
            kind,
            rows,
            "RMS error against direct coupling",
            "RMS error (% of peak force)",
            |m| m.rms_error_rel * 100.0,
        ),
        panel(
            kind,
            rows,
            "Contact losses during the holds",
            "contact losses (count)",
            |m| f64::from(m.hold_contact_losses),
        ),
        panel(
            kind,
            rows,
            "Force oscillation during the holds",
            "peak-to-peak / mean (%)",
            |m| m.hold_oscillation * 100.0,
        ),
    ])
}

/// Writes `<name>.csv`, `<name>.png` and `<name>.svg` into `dir`.
pub fn write_sweep(dir: &Path, kind: SweepKind, rows: &[SweepRow]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    write_sweep_csv(&dir.join(format!("{}.csv", kind.name())), kind, rows)?;
    let fig = sweep_figure(kind, rows);
    fig.save_png(&dir.join(format!("{}.png", kind.name())))?;
    fig.save_svg(&dir.join(format!("{}.svg", kind.name())))?;
    Ok(())
}
