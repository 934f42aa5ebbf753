//! Configuration of the simulated device (`[device]`) and hand (`[hand]`).
//!
//! Defaults and their sources:
//! - **Device** (PHANToM-class): peak force ~6–8 N and ~1.5 N continuous,
//!   apparent end-effector mass ~45–100 g (Massie & Salisbury 1994, "The
//!   PHANToM haptic interface", ASME DSC 55-1: < 100 g, 1.5 N continuous;
//!   SensAble PHANToM Desktop / Premium 1.5 specifications: 45 g / 75 g
//!   apparent tip mass, 7.9 N / 8.5 N peak). Viscous friction of
//!   ~0.5–2 N·s/m is the order used for such arms in sampled-data stability
//!   analyses (Colgate & Schenkel 1997, "Passivity of a class of sampled-data
//!   systems: application to haptic interfaces", J. Robotic Systems 14(1);
//!   Diolaiti et al. 2006, "Stability of haptic rendering", IEEE T-RO 22(2)).
//!   Colgate & Schenkel's passivity condition `b > K T / 2` with `b` = 1 N·s/m
//!   and `T` = 1 ms bounds the stiffness at 2000 N/m; the default
//!   `max_stiffness` of 1000 N/m keeps a factor 2 margin.
//! - **Hand** gripping the stylus: a mass-spring-damper impedance. Human arm
//!   and hand postural stiffness is of the order of 200–1000 N/m and damping
//!   of a few N·s/m to ~10 N·s/m (Mussa-Ivaldi, Hogan & Bizzi 1985, "Neural,
//!   mechanical, and geometric factors subserving arm posture in humans",
//!   J. Neurosci. 5(10); Tsuji, Morasso, Goto & Ito 1995, "Human hand
//!   impedance characteristics during maintained posture", Biol. Cybern. 72).
//!   Defaults: 0.5 kg, 300 N/m, 5 N·s/m (a relaxed grip).

use crate::device::ForceScale;
use crate::error::ConfigError;
use serde::{Deserialize, Serialize};

/// Parameters of the simulated PHANToM-class device (`[device]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeviceConfig {
    /// Apparent end-effector mass at the stylus tip (kg). Default 0.075.
    pub mass: f64,
    /// Viscous friction of the arm (N·s/m). Default 1.0.
    pub viscous_friction: f64,
    /// Peak force the device renders (N); larger commands are clamped. Default 6.0.
    pub max_force: f64,
    /// Largest stable rendered stiffness at `sampling_rate` (N/m). Default 1000.
    pub max_stiffness: f64,
    /// Servo rate at which forces are expected (Hz). Default 1000.
    pub sampling_rate: f64,
    /// Rate of the integration sub-steps inside [`advance`](crate::HapticDevice::advance)
    /// (Hz); at least 10 000. Default 10 000.
    pub substep_rate: f64,
    /// Device force / tissue force (dimensionless), see [`ForceScale`]. Default 0.3.
    pub force_scale: f64,
}

impl Default for DeviceConfig {
    fn default() -> Self {
        DeviceConfig {
            mass: 0.075,
            viscous_friction: 1.0,
            max_force: 6.0,
            max_stiffness: 1000.0,
            sampling_rate: 1000.0,
            substep_rate: 10_000.0,
            force_scale: ForceScale::DEFAULT,
        }
    }
}

impl DeviceConfig {
    /// Lowest accepted sub-step rate (Hz).
    pub const MIN_SUBSTEP_RATE: f64 = 10_000.0;

    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::positive(prefix, "mass", self.mass)?;
        ConfigError::non_negative(prefix, "viscous_friction", self.viscous_friction)?;
        ConfigError::positive(prefix, "max_force", self.max_force)?;
        ConfigError::positive(prefix, "max_stiffness", self.max_stiffness)?;
        ConfigError::positive(prefix, "sampling_rate", self.sampling_rate)?;
        ConfigError::positive(prefix, "substep_rate", self.substep_rate)?;
        if self.substep_rate < Self::MIN_SUBSTEP_RATE {
            return Err(ConfigError::invalid(
                prefix,
                "substep_rate",
                self.substep_rate,
                "must be >= 10000 Hz",
            ));
        }
        ConfigError::positive(prefix, "force_scale", self.force_scale)
    }

    /// The force scale as a typed value (call after [`validate`](Self::validate)).
    pub fn force_scale(&self) -> ForceScale {
        ForceScale::new(self.force_scale).unwrap_or_default()
    }

    /// The largest stiffness the haptic loop may render, in tissue units
    /// (N/m): `max_stiffness / force_scale`, since the device displays
    /// `scale × k_tissue` (see [`ForceScale`]).
    pub fn tissue_max_stiffness(&self) -> f64 {
        self.max_stiffness / self.force_scale().value()
    }
}

/// Parameters of the simulated hand's impedance (`[hand]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HandConfig {
    /// Hand (and forearm) mass moving rigidly with the stylus (kg). Default 0.5.
    pub mass: f64,
    /// Stiffness of the spring pulling towards the setpoint (N/m). Default 300.
    pub stiffness: f64,
    /// Damping relative to the setpoint's velocity (N·s/m). Default 5.
    pub damping: f64,
}

impl Default for HandConfig {
    fn default() -> Self {
        HandConfig {
            mass: 0.5,
            stiffness: 300.0,
            damping: 5.0,
        }
    }
}

impl HandConfig {
    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::non_negative(prefix, "mass", self.mass)?;
        ConfigError::non_negative(prefix, "stiffness", self.stiffness)?;
        ConfigError::non_negative(prefix, "damping", self.damping)
    }
}
