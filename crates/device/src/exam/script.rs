//! The exam script's state machine, advanced on the caller's clock.
//!
//! Each call to [`ExamScript::advance`] moves the hand's setpoint over `dt`
//! seconds. The press needs the force the hand feels, so every advance takes
//! an [`ExamInput`]: the probe position (m) and the felt tissue force (N).
//! A phase that ends inside a step hands the rest of the step to the next
//! phase, so the script's timing does not depend on the step size.
//! Deterministic: no wall clock, no randomness.

use super::config::{ExamConfig, PhaseConfig};
use crate::device::ForceScale;
use crate::error::ConfigError;
use crate::Vec3;

/// Which kind of phase the script is in. `Done` after the last repetition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExamPhase {
    /// Moving towards the point above the skin.
    Approach,
    /// Pressing into the thigh.
    Press,
    /// Holding the setpoint still (in contact when it follows a press).
    Hold,
    /// Sliding along the skin, keeping the press.
    Slide,
    /// Backing up off the skin.
    Release,
    /// All repetitions finished; the setpoint stays where it is.
    Done,
}

impl ExamPhase {
    /// A stable lower-case name, for traces (`"approach"`, ..., `"done"`).
    pub fn name(self) -> &'static str {
        match self {
            ExamPhase::Approach => "approach",
            ExamPhase::Press => "press",
            ExamPhase::Hold => "hold",
            ExamPhase::Slide => "slide",
            ExamPhase::Release => "release",
            ExamPhase::Done => "done",
        }
    }
}

/// Where the script is (Copy, for traces and experiments).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExamStatus {
    /// The current phase.
    pub phase: ExamPhase,
    /// Index of the current phase in the phase list (the list's length when done).
    pub phase_index: usize,
    /// Repetition in progress, 0-based (equals `repeat` when done).
    pub repetition: u32,
    /// Time spent in the current phase (s).
    pub phase_time: f64,
    /// Time since the script started (s).
    pub time: f64,
}

/// What the hand senses, given to [`ExamScript::advance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExamInput {
    /// Probe (end-effector) position (m, thigh frame).
    pub position: Vec3,
    /// Tissue force felt against the press (N, ≥ 0 when the tissue pushes back).
    pub felt_tissue_force: f64,
}

/// The running exam script: the hand's setpoint as a function of time and of
/// what the hand feels.
#[derive(Debug, Clone)]
pub struct ExamScript {
    config: ExamConfig,
    /// The configured phases, slide directions already made unit and
    /// perpendicular to the press direction.
    phases: Vec<PhaseConfig>,
    skin_point: Vec3,
    press_direction: Vec3,
    setpoint: Vec3,
    setpoint_velocity: Vec3,
    index: usize,
    repetition: u32,
    phase_time: f64,
    time: f64,
    slide_target: Vec3,
    entered: bool,
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Moves `from` towards `to` at `speed` for at most `dt`; returns the new
/// point, the time used (s) and whether `to` was reached.
fn move_toward(from: Vec3, to: Vec3, speed: f64, dt: f64) -> (Vec3, f64, bool) {
    let gap = to - from;
    let distance = gap.norm();
    if distance <= speed * dt {
        (to, distance / speed, true)
    } else {
        (from + gap * (speed * dt / distance), dt, false)
    }
}

impl ExamScript {
    /// Builds a script from a configuration (validated with prefix `exam`).
    pub fn new(config: ExamConfig) -> Result<Self, ConfigError> {
        config.validate("exam")?;
        let d = v3(config.press_direction).normalize();
        let phases = config
            .phases
            .iter()
            .map(|p| match *p {
                PhaseConfig::Slide {
                    direction,
                    distance,
                    speed,
                } => {
                    let u = v3(direction);
                    let along = (u - d * u.dot(&d)).normalize();
                    PhaseConfig::Slide {
                        direction: [along.x, along.y, along.z],
                        distance,
                        speed,
                    }
                }
                other => other,
            })
            .collect();
        let start = v3(config.start);
        Ok(ExamScript {
            skin_point: v3(config.skin_point),
            press_direction: d,
            phases,
            setpoint: start,
            setpoint_velocity: Vec3::zeros(),
            index: 0,
            repetition: 0,
            phase_time: 0.0,
            time: 0.0,
            slide_target: start,
            entered: false,
            config,
        })
    }

    /// The configuration the script was built from.
    pub fn config(&self) -> &ExamConfig {
        &self.config
    }

    /// Unit press direction, into the thigh.
    pub fn press_direction(&self) -> Vec3 {
        self.press_direction
    }

    /// Depth of `x` below the skin plane (m; negative above the skin).
    pub fn depth(&self, x: Vec3) -> f64 {
        (x - self.skin_point).dot(&self.press_direction)
    }

    /// The tissue force (N) a device force (N) stands for, as felt against
    /// the press: `max(0, −f·d̂) / scale`.
    pub fn felt_tissue_force(&self, device_force: Vec3, scale: ForceScale) -> f64 {
        (-device_force.dot(&self.press_direction)).max(0.0) / scale.value()
    }

    /// Current setpoint (m, thigh frame).
    pub fn setpoint(&self) -> Vec3 {
        self.setpoint
    }

    /// Mean setpoint velocity over the last advance (m/s).
    pub fn setpoint_velocity(&self) -> Vec3 {
        self.setpoint_velocity
    }

    /// Whether every repetition has finished.
    pub fn is_done(&self) -> bool {
        self.index >= self.phases.len()
    }

    /// Where the script is.
    pub fn status(&self) -> ExamStatus {
        let phase = self
            .phases
            .get(self.index)
            .map_or(ExamPhase::Done, PhaseConfig::kind);
        ExamStatus {
            phase,
            phase_index: self.index,
            repetition: self.repetition,
            phase_time: self.phase_time,
            time: self.time,
        }
    }

    /// Back to the start setpoint and the first phase.
    pub fn reset(&mut self) {
        self.setpoint = v3(self.config.start);
        self.setpoint_velocity = Vec3::zeros();
        self.index = 0;
        self.repetition = 0;
        self.phase_time = 0.0;
        self.time = 0.0;
        self.entered = false;
    }

    fn next_phase(&mut self) {
        self.index += 1;
        self.phase_time = 0.0;
        self.entered = false;
        if self.index == self.phases.len() {
            self.repetition += 1;
            if self.repetition < self.config.repeat {
                self.index = 0;
            }
        }
    }

    /// Advances the script by `dt` (s) given what the hand senses at the
    /// start of the step, and returns the new setpoint (m). Non-finite or
    /// non-positive `dt` leaves the script unchanged. Allocates nothing.
    ///
    /// The press ends when `input.felt_tissue_force ≥ target_force` or the
    /// probe's depth `(input.position − skin_point)·d̂ ≥ max_depth`.
    ///
    /// Bounded: one advance ends at most `phases.len()` phases (one pass of
    /// the list). Phases can take no time (a slide of 0 m, an approach to
    /// where the setpoint is, a press already at its force), so without the
    /// bound a script of instant phases would run all its `repeat ×
    /// phases` (up to 10⁶) transitions inside one 1 ms tick. A step that
    /// would complete more than a pass leaves the rest of its time unused
    /// (the script then lags the clock by it).
    pub fn advance(&mut self, dt: f64, input: ExamInput) -> Vec3 {
        if !(dt.is_finite() && dt > 0.0) {
            return self.setpoint;
        }
        let before = self.setpoint;
        self.time += dt;
        let mut remaining = dt;
        let mut transitions = 0;
        while let Some(&phase) = self.phases.get(self.index) {
            if !self.entered {
                self.entered = true;
                if let PhaseConfig::Slide {
                    direction,
                    distance,
                    ..
                } = phase
                {
                    self.slide_target = self.setpoint + v3(direction) * distance;
                }
            }
            let (used, complete) = match phase {
                PhaseConfig::Approach { point, speed } => {
                    let (p, used, done) = move_toward(self.setpoint, v3(point), speed, remaining);
                    self.setpoint = p;
                    (used, done)
                }
                PhaseConfig::Press {
                    rate,
                    target_force,
                    max_depth,
                } => {
                    if input.felt_tissue_force >= target_force
                        || self.depth(input.position) >= max_depth
                    {
                        (0.0, true)
                    } else {
                        self.setpoint += self.press_direction * (rate * remaining);
                        (remaining, false)
                    }
                }
                PhaseConfig::Hold { duration } => {
                    let left = (duration - self.phase_time).max(0.0);
                    if left <= remaining {
                        (left, true)
                    } else {
                        (remaining, false)
                    }
                }
                PhaseConfig::Slide { speed, .. } => {
                    let (p, used, done) =
                        move_toward(self.setpoint, self.slide_target, speed, remaining);
                    self.setpoint = p;
                    (used, done)
                }
                PhaseConfig::Release { speed, clearance } => {
                    let to_go = self.depth(self.setpoint) + clearance;
                    if to_go <= speed * remaining {
                        self.setpoint -= self.press_direction * to_go.max(0.0);
                        (to_go.max(0.0) / speed, true)
                    } else {
                        self.setpoint -= self.press_direction * (speed * remaining);
                        (remaining, false)
                    }
                }
            };
            self.phase_time += used;
            remaining -= used;
            if !complete {
                break;
            }
            self.next_phase();
            transitions += 1;
            if remaining <= 0.0 || transitions >= self.phases.len() {
                break;
            }
        }
        self.setpoint_velocity = (self.setpoint - before) / dt;
        self.setpoint
    }
}
