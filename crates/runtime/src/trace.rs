//! What a run records: one [`TickRecord`] per haptic tick (1 kHz) and one
//! [`PhysicsRecord`] per physics step, written as CSV, plus a JSON
//! [`Summary`]. Buffers are preallocated for the whole run by the caller, so
//! recording in the real-time loop never allocates and never drops a row.

use anyhow::{Context, Result};
use echothigh_model::StepTimings;
use echothigh_table::RowWriter;
use serde::Serialize;
use std::io::Write;
use std::path::Path;

/// One haptic tick. Positions in m (thigh frame), forces in N.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct TickRecord {
    /// Time (s).
    pub t: f64,
    /// Device end-effector position (m).
    pub device: [f64; 3],
    /// Proxy position (m); equals the device position in `hold` and `direct` modes.
    pub proxy: [f64; 3],
    /// Force rendered, in tissue units (N).
    pub force: [f64; 3],
    /// Force written to the device after the force scale (N).
    pub device_force: [f64; 3],
    /// Age of the newest physics information used for this tick (s).
    pub model_age: f64,
    /// Exam phase index of the simulated hand (see `echothigh_device`), or 255 when none.
    pub phase: u8,
    /// True when the hand holds a press (the exam's `hold` phase).
    pub holding: bool,
}

/// One physics step.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct PhysicsRecord {
    /// Physics time at the start of the step (s).
    pub t: f64,
    /// Probe reference point used for the step (m).
    pub probe: [f64; 3],
    /// Distance sent to the haptic side (m).
    pub distance: f64,
    /// Its gradient (unit).
    pub gradient: [f64; 3],
    /// Local stiffness (N/m).
    pub stiffness: f64,
    /// Net contact force on the probe (N).
    pub force: [f64; 3],
    /// Newton iterations of the step.
    pub newton_iterations: u32,
    /// CG iterations of the step (all Newton iterations).
    pub cg_iterations: u32,
    /// Times the asymptote limiter acted.
    pub limited: u32,
    /// Wall-clock compute time of the step (s); 0 on the virtual clock.
    pub compute_time: f64,
    /// Time of each stage of the step and of its haptic queries (s,
    /// monotonic clock; see [`StepTimings`]): measured on every clock, the
    /// virtual one included, since the step's computation is real.
    pub stages: StepTimings,
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Writes the header of `haptic.csv`.
pub fn write_tick_header(w: &mut RowWriter<impl Write>, _mode: &str) -> std::io::Result<()> {
    w.record([
        "t",
        "device_x",
        "device_y",
        "device_z",
        "proxy_x",
        "proxy_y",
        "proxy_z",
        "force_x",
        "force_y",
        "force_z",
        "force",
        "device_force_x",
        "device_force_y",
        "device_force_z",
        "model_age",
        "phase",
        "holding",
        "mode",
    ])
}

/// Writes one row of `haptic.csv` (`mode`: the coupling mode's name):
/// positions to 0.1 µm, forces to 10 µN, times to 0.1 ms.
pub fn write_tick_row(
    w: &mut RowWriter<impl Write>,
    r: &TickRecord,
    mode: &str,
) -> std::io::Result<()> {
    let m = |v: f64| format!("{v:.7}");
    let n = |v: f64| format!("{v:.5}");
    w.record([
        format!("{:.4}", r.t),
        m(r.device[0]),
        m(r.device[1]),
        m(r.device[2]),
        m(r.proxy[0]),
        m(r.proxy[1]),
        m(r.proxy[2]),
        n(r.force[0]),
        n(r.force[1]),
        n(r.force[2]),
        n(norm(r.force)),
        n(r.device_force[0]),
        n(r.device_force[1]),
        n(r.device_force[2]),
        format!("{:.4}", r.model_age),
        r.phase.to_string(),
        u8::from(r.holding).to_string(),
        mode.to_string(),
    ])
}

/// Writes the header of `physics.csv`: the step's values, then one column
/// per stage of [`StepTimings`], named `{stage}_s` (seconds).
pub fn write_physics_header(w: &mut RowWriter<impl Write>) -> std::io::Result<()> {
    let mut h: Vec<String> = [
        "t",
        "probe_x",
        "probe_y",
        "probe_z",
        "distance",
        "grad_x",
        "grad_y",
        "grad_z",
        "stiffness",
        "force_x",
        "force_y",
        "force_z",
        "force",
        "newton_iterations",
        "cg_iterations",
        "limited",
        "compute_time",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    h.extend(StepTimings::NAMES.iter().map(|n| format!("{n}_s")));
    w.record(h)
}

/// Writes one row of `physics.csv`.
pub fn write_physics_row(w: &mut RowWriter<impl Write>, r: &PhysicsRecord) -> std::io::Result<()> {
    let m = |v: f64| format!("{v:.7}");
    let g = |v: f64| format!("{v:.6}");
    let n = |v: f64| format!("{v:.5}");
    let mut row = vec![
        format!("{:.4}", r.t),
        m(r.probe[0]),
        m(r.probe[1]),
        m(r.probe[2]),
        m(r.distance),
        g(r.gradient[0]),
        g(r.gradient[1]),
        g(r.gradient[2]),
        format!("{:.3}", r.stiffness),
        n(r.force[0]),
        n(r.force[1]),
        n(r.force[2]),
        n(norm(r.force)),
        r.newton_iterations.to_string(),
        r.cg_iterations.to_string(),
        r.limited.to_string(),
        format!("{:.6}", r.compute_time),
    ];
    // Stage times to the nanosecond (the monotonic clock's resolution).
    row.extend(r.stages.values().iter().map(|v| format!("{v:.9}")));
    w.record(row)
}

/// Writes the 1 kHz trace as CSV (a whole trace at once; runs stream theirs
/// through [`crate::recorder`]).
pub fn write_ticks(path: &Path, mode: &str, rows: &[TickRecord]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = RowWriter::new(std::io::BufWriter::new(file));
    let mut write = || -> std::io::Result<()> {
        write_tick_header(&mut w, mode)?;
        for r in rows {
            write_tick_row(&mut w, r, mode)?;
        }
        w.flush()
    };
    write().with_context(|| format!("writing {}", path.display()))
}

/// Writes the physics trace as CSV (a whole trace at once).
pub fn write_physics(path: &Path, rows: &[PhysicsRecord]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = RowWriter::new(std::io::BufWriter::new(file));
    let mut write = || -> std::io::Result<()> {
        write_physics_header(&mut w)?;
        for r in rows {
            write_physics_row(&mut w, r)?;
        }
        w.flush()
    };
    write().with_context(|| format!("writing {}", path.display()))
}

/// Force magnitude of each tick (N).
pub fn force_magnitudes(rows: &[TickRecord]) -> Vec<f64> {
    rows.iter().map(|r| norm(r.force)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `physics.csv` carries the step's stage times: one `{stage}_s` column
    /// per [`StepTimings`] stage, each row as many fields as the header,
    /// and the times read back to the printed nanosecond (|error| ≤ 0.5 ns,
    /// half the last printed digit).
    #[test]
    fn physics_rows_carry_the_stage_times() {
        let stages = StepTimings {
            broad_phase: 1.25e-5,
            forces: 3.5e-5,
            assembly: 2.1e-4,
            pcg: 4.75e-4,
            stiffness_solve: 1.5e-4,
            distance_query: 7.0e-6,
            step_fraction: 2.5e-6,
            contact: 3.0e-5,
            window: 4.5e-6,
        };
        let r = PhysicsRecord {
            t: 0.5,
            stiffness: 650.0,
            stages,
            ..PhysicsRecord::default()
        };
        let mut out = Vec::new();
        {
            let mut w = RowWriter::new(&mut out);
            write_physics_header(&mut w).unwrap();
            write_physics_row(&mut w, &r).unwrap();
            w.flush().unwrap();
        }
        let table = echothigh_table::Table::parse(&String::from_utf8(out).unwrap()).unwrap();
        let row = &table.rows()[0];
        for (name, want) in StepTimings::NAMES.iter().zip(stages.values()) {
            let column: &'static str = format!("{name}_s").leak();
            let got = row.number(table.column(column).unwrap(), column).unwrap();
            assert!((got - want).abs() <= 0.5e-9, "{column}: {got} vs {want}");
        }
        // Every header column has its field: a short row is an error.
        let last = table.column("window_s").unwrap();
        assert!(row.number(last, "window_s").is_ok());
    }
}
