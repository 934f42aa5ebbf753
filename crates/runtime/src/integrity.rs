//! The last check of a run's outputs: a run whose traces hold a NaN or an
//! infinity diverged, whatever else it reports, and must not end as a
//! success (issue 20: `[hand] stiffness = 1e308` wrote NaN device positions
//! from the first tick and exited 0 with "run written").

use crate::trace::{PhysicsRecord, TickRecord};
use anyhow::{bail, Result};

/// The first non-finite value of a record, as `(column, value)`.
fn first_bad<'a>(cols: impl IntoIterator<Item = (&'a str, f64)>) -> Option<(&'a str, f64)> {
    cols.into_iter().find(|(_, v)| !v.is_finite())
}

fn xyz(prefix: &str, v: [f64; 3]) -> [(String, f64); 3] {
    [
        (format!("{prefix}_x"), v[0]),
        (format!("{prefix}_y"), v[1]),
        (format!("{prefix}_z"), v[2]),
    ]
}

/// Checks every number of `haptic.csv` and `physics.csv` for finiteness
/// (except the distance's +∞, "no surface");
/// the error names the file, the column, the row (1-based, after the
/// header) and its time. `O(rows)`, run once after the run.
pub fn check_finite(ticks: &[TickRecord], steps: &[PhysicsRecord]) -> Result<()> {
    for (row, r) in ticks.iter().enumerate() {
        let mut cols: Vec<(String, f64)> =
            vec![("t".into(), r.t), ("model_age".into(), r.model_age)];
        for (name, v) in [
            ("device", r.device),
            ("proxy", r.proxy),
            ("force", r.force),
            ("device_force", r.device_force),
        ] {
            cols.extend(xyz(name, v));
        }
        if let Some((c, v)) = first_bad(cols.iter().map(|(c, v)| (c.as_str(), *v))) {
            bail!(
                "haptic.csv row {} (t = {} s): {c} = {v} is not finite",
                row + 1,
                r.t
            );
        }
    }
    for (row, r) in steps.iter().enumerate() {
        // D = +∞ is the physics' "no surface under the probe" (the probe
        // off the thigh's side), a valid value; NaN and −∞ are not.
        if r.distance.is_nan() || r.distance == f64::NEG_INFINITY {
            let (row, t, d) = (row + 1, r.t, r.distance);
            bail!("physics.csv row {row} (t = {t} s): distance = {d} is not a distance");
        }
        let mut cols: Vec<(String, f64)> =
            vec![("t".into(), r.t), ("stiffness".into(), r.stiffness)];
        for (name, v) in [("probe", r.probe), ("grad", r.gradient), ("force", r.force)] {
            cols.extend(xyz(name, v));
        }
        if let Some((c, v)) = first_bad(cols.iter().map(|(c, v)| (c.as_str(), *v))) {
            bail!(
                "physics.csv row {} (t = {} s): {c} = {v} is not finite",
                row + 1,
                r.t
            );
        }
    }
    Ok(())
}
