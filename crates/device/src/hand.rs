//! The simulated hand: a mass-spring-damper impedance gripping the stylus,
//! pulled along a setpoint that an [`ExamScript`] may drive.
//!
//! The hand's mass moves rigidly with the end-effector (the user grips the
//! stylus); the hand exerts on it
//!
//! `F_hand = K (s − x) + B (ṡ − v)`
//!
//! with `s`, `ṡ` the setpoint and its velocity, `x`, `v` the end-effector's.
//! Damping is relative to the setpoint's motion so the hand tracks a moving
//! setpoint without a velocity lag. Defaults and sources in [`HandConfig`].

use crate::config::HandConfig;
use crate::error::ConfigError;
use crate::exam::{ExamInput, ExamScript, ExamStatus};
use crate::Vec3;

/// The simulated hand (impedance plus setpoint, optionally scripted).
#[derive(Debug, Clone)]
pub struct SimulatedHand {
    config: HandConfig,
    setpoint: Vec3,
    setpoint_velocity: Vec3,
    script: Option<ExamScript>,
}

impl SimulatedHand {
    /// A hand holding still at `setpoint` (m). Validates `config` as `hand`.
    pub fn new(config: HandConfig, setpoint: Vec3) -> Result<Self, ConfigError> {
        config.validate("hand")?;
        Ok(SimulatedHand {
            config,
            setpoint,
            setpoint_velocity: Vec3::zeros(),
            script: None,
        })
    }

    /// A hand whose setpoint follows `script`, starting at its start point.
    pub fn scripted(config: HandConfig, script: ExamScript) -> Result<Self, ConfigError> {
        let mut hand = Self::new(config, script.setpoint())?;
        hand.script = Some(script);
        Ok(hand)
    }

    /// The impedance parameters.
    pub fn config(&self) -> &HandConfig {
        &self.config
    }

    /// Hand mass (kg).
    pub fn mass(&self) -> f64 {
        self.config.mass
    }

    /// Hand damping `B` (N·s/m).
    pub fn damping(&self) -> f64 {
        self.config.damping
    }

    /// Current setpoint `s` (m).
    pub fn setpoint(&self) -> Vec3 {
        self.setpoint
    }

    /// Current setpoint velocity `ṡ` (m/s).
    pub fn setpoint_velocity(&self) -> Vec3 {
        self.setpoint_velocity
    }

    /// Sets the setpoint (m) and its velocity (m/s) directly (an unscripted
    /// hand, or overriding a script until its next advance).
    pub fn set_setpoint(&mut self, setpoint: Vec3, velocity: Vec3) {
        self.setpoint = setpoint;
        self.setpoint_velocity = velocity;
    }

    /// Moves the setpoint towards `goal` (m) by at most `max_speed × dt`
    /// (m/s × s), as a hand reaching for where the trainee points: a mouse
    /// teleports, a hand does not (~0.2 m/s for a careful probe placement).
    /// The setpoint velocity is left at zero (the hand damps against a still
    /// setpoint, so a reach does not drag the probe). Allocates nothing.
    pub fn slew_towards(&mut self, goal: Vec3, max_speed: f64, dt: f64) {
        if !(dt > 0.0 && goal.iter().all(|c| c.is_finite())) {
            return;
        }
        let step = goal - self.setpoint;
        let max = max_speed.max(0.0) * dt;
        let n = step.norm();
        let step = if n > max { step * (max / n) } else { step };
        self.setpoint += step;
        self.setpoint_velocity = Vec3::zeros();
    }

    /// The exam script, if any.
    pub fn script(&self) -> Option<&ExamScript> {
        self.script.as_ref()
    }

    /// The exam script, mutable (e.g. to reset it).
    pub fn script_mut(&mut self) -> Option<&mut ExamScript> {
        self.script.as_mut()
    }

    /// The script's status, if scripted.
    pub fn exam_status(&self) -> Option<ExamStatus> {
        self.script.as_ref().map(ExamScript::status)
    }

    /// Advances the script (if any) by `dt` (s) with what the hand senses and
    /// takes its setpoint. Allocates nothing.
    pub fn update(&mut self, dt: f64, input: ExamInput) {
        if let Some(script) = self.script.as_mut() {
            self.setpoint = script.advance(dt, input);
            self.setpoint_velocity = script.setpoint_velocity();
        }
    }

    /// The part of the hand force independent of the end-effector velocity,
    /// `K (s − x) + B ṡ` (N), at end-effector position `x` (m).
    pub fn explicit_force(&self, x: Vec3) -> Vec3 {
        (self.setpoint - x) * self.config.stiffness + self.setpoint_velocity * self.config.damping
    }

    /// The full hand force `K (s − x) + B (ṡ − v)` (N) on the end-effector.
    pub fn force(&self, x: Vec3, v: Vec3) -> Vec3 {
        self.explicit_force(x) - v * self.config.damping
    }
}
