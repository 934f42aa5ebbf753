//! The scripted compression exam that drives the simulated hand's setpoint:
//! approach, press to a target force or depth, hold, slide, release, repeat.

mod config;
mod phases;
mod script;

pub use config::{ExamConfig, PhaseConfig, MAX_PHASES};
pub use script::{ExamInput, ExamPhase, ExamScript, ExamStatus};
