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

use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// One phase of the exam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PhaseConfig {
    /// Move the setpoint in a straight line to `point` (m), which must lie
    /// above the skin, at `speed` (m/s).
    Approach {
        /// Target point (m, thigh frame).
        point: [f64; 3],
        /// Setpoint speed (m/s).
        speed: f64,
    },
    /// Move the setpoint along the press direction at `rate` (m/s) until the
    /// felt tissue force reaches `target_force` (N) or the probe is
    /// `max_depth` (m) below the skin.
    Press {
        /// Setpoint speed along the press direction (m/s).
        rate: f64,
        /// Felt tissue force that ends the press (N).
        target_force: f64,
        /// Probe depth below the skin that ends the press (m).
        max_depth: f64,
    },
    /// Keep the setpoint still for `duration` (s).
    Hold {
        /// Duration (s).
        duration: f64,
    },
    /// Move the setpoint by `distance` (m) along `direction` at `speed` (m/s),
    /// keeping the press: the component of `direction` along the press
    /// direction is removed, so the setpoint's depth does not change.
    Slide {
        /// Slide direction (normalized after removing its press component).
        direction: [f64; 3],
        /// Distance (m).
        distance: f64,
        /// Speed (m/s).
        speed: f64,
    },
    /// Move the setpoint against the press direction at `speed` (m/s) until it
    /// is `clearance` (m) above the skin.
    Release {
        /// Speed (m/s).
        speed: f64,
        /// Height of the setpoint above the skin that ends the release (m).
        clearance: f64,
    },
}

/// The exam script (`[exam]`): a start setpoint, the skin's local geometry,
/// and a list of phases run `repeat` times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExamConfig {
    /// Initial hand setpoint (m, thigh frame). Default `[0, 0.092, -0.01]`
    /// (20 mm above the skin at mid-thigh).
    pub start: [f64; 3],
    /// A point on the skin at the exam site (m). Default `[0, 0.072, -0.01]`
    /// (top of the 72 mm semi-axis, middle of a 0.30 m segment).
    pub skin_point: [f64; 3],
    /// Direction of the press, into the thigh (normalized). Default `[0, −1, 0]`.
    pub press_direction: [f64; 3],
    /// Number of times the phase list runs (≥ 1). Default 2.
    pub repeat: u32,
    /// The phases, in order. Default: approach 5 mm above the skin, press to
    /// 10 N at 40 mm/s (or 25 mm deep), hold 1 s, slide 20 mm along z at
    /// 10 mm/s, hold 0.5 s, release at 80 mm/s to 5 mm above the skin. Twice,
    /// that is ~9.8 s against a tissue of ~0.8 N/mm (7 s of it fixed).
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

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

impl ExamConfig {
    /// Parses the `[exam]` section of a scenario TOML document. Other
    /// sections are ignored (they belong to other crates); a document without
    /// `[exam]` gives the default script. Unknown keys inside `[exam]`,
    /// missing phase fields and wrong types are errors naming the key; the
    /// result is validated.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let parse = |e: toml::de::Error| ConfigError::Parse {
            section: "exam",
            message: e.to_string(),
        };
        let mut table: toml::Table = toml::from_str(text).map_err(parse)?;
        let config = match table.remove("exam") {
            None => ExamConfig::default(),
            Some(value) => value.try_into::<ExamConfig>().map_err(parse)?,
        };
        config.validate("exam")?;
        Ok(config)
    }

    /// Checks every field, naming the offending key as `"{prefix}.{field}"`
    /// and phases as `"{prefix}.phases[i].{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::finite3(prefix, "start", self.start)?;
        ConfigError::finite3(prefix, "skin_point", self.skin_point)?;
        ConfigError::direction(prefix, "press_direction", self.press_direction)?;
        if self.repeat == 0 {
            return Err(ConfigError::invalid(prefix, "repeat", 0, "must be >= 1"));
        }
        if self.phases.is_empty() {
            return Err(ConfigError::invalid(
                prefix,
                "phases",
                "[]",
                "needs at least one phase",
            ));
        }
        let d = unit(self.press_direction);
        for (i, phase) in self.phases.iter().enumerate() {
            let p = format!("{prefix}.phases[{i}]");
            match *phase {
                PhaseConfig::Approach { point, speed } => {
                    ConfigError::finite3(&p, "point", point)?;
                    ConfigError::positive(&p, "speed", speed)?;
                    let rel = [
                        point[0] - self.skin_point[0],
                        point[1] - self.skin_point[1],
                        point[2] - self.skin_point[2],
                    ];
                    if dot(rel, d) >= 0.0 {
                        return Err(ConfigError::invalid(
                            &p,
                            "point",
                            format!("{point:?}"),
                            "must lie above the skin (against press_direction from skin_point)",
                        ));
                    }
                }
                PhaseConfig::Press {
                    rate,
                    target_force,
                    max_depth,
                } => {
                    ConfigError::positive(&p, "rate", rate)?;
                    ConfigError::positive(&p, "target_force", target_force)?;
                    ConfigError::positive(&p, "max_depth", max_depth)?;
                }
                PhaseConfig::Hold { duration } => ConfigError::positive(&p, "duration", duration)?,
                PhaseConfig::Slide {
                    direction,
                    distance,
                    speed,
                } => {
                    ConfigError::direction(&p, "direction", direction)?;
                    let u = unit(direction);
                    if dot(u, d).abs() > 0.99 {
                        return Err(ConfigError::invalid(
                            &p,
                            "direction",
                            format!("{direction:?}"),
                            "must not be parallel to press_direction",
                        ));
                    }
                    ConfigError::non_negative(&p, "distance", distance)?;
                    ConfigError::positive(&p, "speed", speed)?;
                }
                PhaseConfig::Release { speed, clearance } => {
                    ConfigError::positive(&p, "speed", speed)?;
                    ConfigError::non_negative(&p, "clearance", clearance)?;
                }
            }
        }
        Ok(())
    }
}
