//! The exam script's configuration (`[exam]` in the scenario TOML).
//!
//! ```toml
//! [exam]
//! start = [0.0, 0.092, -0.01]          # initial hand setpoint (m, thigh frame)
//! skin_point = [0.0, 0.072, -0.01]     # a point on the skin at the exam site (m)
//! press_direction = [0.0, -1.0, 0.0]  # into the thigh
//! repeat = 2                          # the phase list runs twice
//!
//! [[exam.phases]]
//! kind = "approach"
//! point = [0.0, 0.077, -0.01]          # above the skin (m)
//! speed = 0.05                        # m/s
//!
//! [[exam.phases]]
//! kind = "press"
//! rate = 0.04                         # m/s along press_direction
//! target_force = 10.0                 # felt tissue force that ends the press (N)
//! max_depth = 0.025                   # probe depth below the skin that ends it (m)
//!
//! [[exam.phases]]
//! kind = "hold"
//! duration = 1.0                      # s
//!
//! [[exam.phases]]
//! kind = "slide"
//! direction = [0.0, 0.0, 1.0]
//! distance = 0.02                     # m
//! speed = 0.01                        # m/s
//!
//! [[exam.phases]]
//! kind = "hold"
//! duration = 0.5
//!
//! [[exam.phases]]
//! kind = "release"
//! speed = 0.08                        # m/s against press_direction
//! clearance = 0.005                   # setpoint height above the skin that ends it (m)
//! ```
//!
//! The skin at the exam site is taken as the plane through `skin_point`
//! normal to `press_direction` (a local, planar approximation: sliding along
//! the thigh axis on a generalized cylinder keeps the skin height). Depth
//! below the skin of a point `x` is `(x − skin_point) · d̂`.

use super::ExamPhase;
use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// One phase of the exam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PhaseConfig {
    /// Move the setpoint in a straight line to `point` (m), which must lie
    /// above the skin, at `speed` (m/s).
    Approach {
        /// Target point (m, thigh frame), each component in [−1, 1] (within
        /// a metre of the thigh's axis).
        point: [f64; 3],
        /// Setpoint speed (m/s), in [0.001, 1] (exam motions run mm/s to
        /// ~0.5 m/s; 1 mm/s crosses the 2 m box in < 2000 s).
        speed: f64,
    },
    /// Move the setpoint along the press direction at `rate` (m/s) until the
    /// felt tissue force reaches `target_force` (N) or the probe is
    /// `max_depth` (m) below the skin.
    Press {
        /// Setpoint speed along the press direction (m/s), in [0.001, 0.5].
        rate: f64,
        /// Felt tissue force that ends the press (N), in [0.1, 100]
        /// (compression ultrasound uses ~5–40 N).
        target_force: f64,
        /// Probe depth below the skin that ends the press (m), in [0.001,
        /// 0.1] (the soft tissue over the femur is at most ~0.1 m thick).
        max_depth: f64,
    },
    /// Keep the setpoint still for `duration` (s).
    Hold {
        /// Duration (s), in [0.001, 3600] (`[run] duration`'s bound).
        duration: f64,
    },
    /// Move the setpoint by `distance` (m) along `direction` at `speed` (m/s),
    /// keeping the press: the component of `direction` along the press
    /// direction is removed, so the setpoint's depth does not change.
    Slide {
        /// Slide direction (normalized after removing its press component),
        /// each component in [−1000, 1000] (its square norm cannot overflow).
        direction: [f64; 3],
        /// Distance (m), in [0, 0.5] (along or around the thigh segment).
        distance: f64,
        /// Speed (m/s), in [0.001, 0.5].
        speed: f64,
    },
    /// Move the setpoint against the press direction at `speed` (m/s) until it
    /// is `clearance` (m) above the skin.
    Release {
        /// Speed (m/s), in [0.001, 1].
        speed: f64,
        /// Height of the setpoint above the skin that ends the release (m),
        /// in [0, 0.1].
        clearance: f64,
    },
}

impl PhaseConfig {
    /// Which kind of phase this is (the script's [`ExamPhase`] while it runs).
    pub fn kind(&self) -> ExamPhase {
        match self {
            PhaseConfig::Approach { .. } => ExamPhase::Approach,
            PhaseConfig::Press { .. } => ExamPhase::Press,
            PhaseConfig::Hold { .. } => ExamPhase::Hold,
            PhaseConfig::Slide { .. } => ExamPhase::Slide,
            PhaseConfig::Release { .. } => ExamPhase::Release,
        }
    }
}

/// The exam script (`[exam]`): a start setpoint, the skin's local geometry,
/// and a list of phases run `repeat` times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExamConfig {
    /// Initial hand setpoint (m, thigh frame). Default `[0, 0.092, -0.01]`
    /// (20 mm above the skin at mid-thigh). Each component in [−1, 1] (within
    /// a metre of the thigh's axis); exactly three elements.
    #[serde(deserialize_with = "exact_array3")]
    pub start: [f64; 3],
    /// A point on the skin at the exam site (m). Default `[0, 0.072, -0.01]`
    /// (top of the 72 mm semi-axis, middle of a 0.30 m segment). Each
    /// component in [−1, 1]; exactly three elements.
    #[serde(deserialize_with = "exact_array3")]
    pub skin_point: [f64; 3],
    /// Direction of the press, into the thigh (normalized), each component
    /// in [−1000, 1000] and not zero. Default `[0, −1, 0]`.
    #[serde(deserialize_with = "exact_array3")]
    pub press_direction: [f64; 3],
    /// Number of times the phase list runs, in [1, 1000]. Default 2.
    pub repeat: u32,
    /// The phases, in order. Default: approach 5 mm above the skin, press to
    /// 10 N at 40 mm/s (or 25 mm deep), hold 1 s, slide 20 mm along z at
    /// 10 mm/s, hold 0.5 s, release at 80 mm/s to 5 mm above the skin. Twice,
    /// that is ~9.8 s against a tissue of ~0.8 N/mm (7 s of it fixed).
    /// Between 1 and [`MAX_PHASES`] phases. A phase that does not decode is
    /// an error naming `exam.phases[i].field`.
    #[serde(deserialize_with = "super::phases::deserialize_phases")]
    pub phases: Vec<PhaseConfig>,
}

impl Default for ExamConfig {
    fn default() -> Self {
        ExamConfig {
            start: [0.0, 0.092, -0.01],
            skin_point: [0.0, 0.072, -0.01],
            press_direction: [0.0, -1.0, 0.0],
            repeat: 2,
            phases: vec![
                PhaseConfig::Approach {
                    point: [0.0, 0.077, -0.01],
                    speed: 0.05,
                },
                PhaseConfig::Press {
                    rate: 0.04,
                    target_force: 10.0,
                    max_depth: 0.025,
                },
                PhaseConfig::Hold { duration: 1.0 },
                PhaseConfig::Slide {
                    direction: [0.0, 0.0, 1.0],
                    distance: 0.02,
                    speed: 0.01,
                },
                PhaseConfig::Hold { duration: 0.5 },
                PhaseConfig::Release {
                    speed: 0.08,
                    clearance: 0.005,
                },
            ],
        }
    }
}

/// Most phases in a script.
pub const MAX_PHASES: usize = 1000;

/// Deserializes exactly three numbers: serde's `[f64; 3]` silently drops
/// extra elements with the TOML decoder (`start = [0, 0.09, 0, 99]` was
/// accepted).
fn exact_array3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    use serde::de::Error;
    let v = <Vec<f64> as Deserialize>::deserialize(d)?;
    let len = v.len();
    v.try_into()
        .map_err(|_| D::Error::invalid_length(len, &"exactly 3 numbers"))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

impl ExamConfig {
    /// Checks every field, naming the offending key as `"{prefix}.{field}"`
    /// and phases as `"{prefix}.phases[i].{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let point = "each component must be in [-1, 1] m (within a metre of the thigh)";
        let dir = "each component must be in [-1000, 1000] (a direction)";
        ConfigError::in_range3(p, "start", self.start, (-1.0, 1.0), point)?;
        ConfigError::in_range3(p, "skin_point", self.skin_point, (-1.0, 1.0), point)?;
        ConfigError::in_range3(p, "press_direction", self.press_direction, (-1e3, 1e3), dir)?;
        ConfigError::direction(p, "press_direction", self.press_direction)?;
        if !(1..=1000).contains(&self.repeat) {
            return Err(ConfigError::invalid(
                p,
                "repeat",
                self.repeat,
                "must be in [1, 1000]",
            ));
        }
        if self.phases.is_empty() || self.phases.len() > MAX_PHASES {
            return Err(ConfigError::invalid(
                p,
                "phases",
                format!("{} phases", self.phases.len()),
                "needs between 1 and 1000 phases",
            ));
        }
        let d = unit(self.press_direction);
        for (i, phase) in self.phases.iter().enumerate() {
            let p = format!("{prefix}.phases[{i}]");
            validate_phase(&p, phase, self.skin_point, d)?;
        }
        Ok(())
    }
}

/// Checks one phase against its documented ranges; `p` is
/// `"{prefix}.phases[i]"`, `d` the unit press direction.
fn validate_phase(
    p: &str,
    phase: &PhaseConfig,
    skin_point: [f64; 3],
    d: [f64; 3],
) -> Result<(), ConfigError> {
    let point = "each component must be in [-1, 1] m (within a metre of the thigh)";
    let speed = "must be in [0.001, 1] m/s (exam motions)";
    let slow = "must be in [0.001, 0.5] m/s (exam motions)";
    match *phase {
        PhaseConfig::Approach { point: x, speed: v } => {
            ConfigError::in_range3(p, "point", x, (-1.0, 1.0), point)?;
            ConfigError::in_range(p, "speed", v, (1e-3, 1.0), speed)?;
            let rel = [
                x[0] - skin_point[0],
                x[1] - skin_point[1],
                x[2] - skin_point[2],
            ];
            if dot(rel, d) >= 0.0 {
                return Err(ConfigError::invalid(
                    p,
                    "point",
                    format!("{x:?}"),
                    "must lie above the skin (against press_direction from skin_point)",
                ));
            }
        }
        PhaseConfig::Press {
            rate,
            target_force,
            max_depth,
        } => {
            ConfigError::in_range(p, "rate", rate, (1e-3, 0.5), slow)?;
            let force = "must be in [0.1, 100] N (compression exams use ~5-40 N)";
            ConfigError::in_range(p, "target_force", target_force, (0.1, 100.0), force)?;
            let depth = "must be in [0.001, 0.1] m (the soft tissue's thickness)";
            ConfigError::in_range(p, "max_depth", max_depth, (1e-3, 0.1), depth)?;
        }
        PhaseConfig::Hold { duration } => {
            let hold = "must be in [0.001, 3600] s (the run's bound)";
            ConfigError::in_range(p, "duration", duration, (1e-3, 3600.0), hold)?;
        }
        PhaseConfig::Slide {
            direction,
            distance,
            speed: v,
        } => {
            let dir = "each component must be in [-1000, 1000] (a direction)";
            ConfigError::in_range3(p, "direction", direction, (-1e3, 1e3), dir)?;
            ConfigError::direction(p, "direction", direction)?;
            if dot(unit(direction), d).abs() > 0.99 {
                return Err(ConfigError::invalid(
                    p,
                    "direction",
                    format!("{direction:?}"),
                    "must not be parallel to press_direction",
                ));
            }
            let dist = "must be in [0, 0.5] m (along or around the thigh)";
            ConfigError::in_range(p, "distance", distance, (0.0, 0.5), dist)?;
            ConfigError::in_range(p, "speed", v, (1e-3, 0.5), slow)?;
        }
        PhaseConfig::Release {
            speed: v,
            clearance,
        } => {
            ConfigError::in_range(p, "speed", v, (1e-3, 1.0), speed)?;
            let clear = "must be in [0, 0.1] m (above the skin)";
            ConfigError::in_range(p, "clearance", clearance, (0.0, 0.1), clear)?;
        }
    }
    Ok(())
}
