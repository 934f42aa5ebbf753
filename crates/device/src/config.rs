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

/// Which device a scenario's haptic loop drives (`[device] kind`). The real
/// devices' settings are the `[device.hardware]` keys of a `--hardware`
/// file (crate `echothigh-devices-hw`), which this crate does not depend on.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DeviceKindSetting {
    /// The simulated PHANToM-class device below, moved by `[hand]` and `[exam]`.
    #[default]
    Simulated,
    /// 3D Systems Touch / PHANTOM through OpenHaptics HD.
    Openhaptics,
    /// Force Dimension delta / omega / sigma / Falcon through DHD.
    Forcedimension,
    /// Haply Inverse3 (+ VerseGrip) through Haply's Inverse Service.
    Haply,
}

impl DeviceKindSetting {
    /// The name used in the scenario and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKindSetting::Simulated => "simulated",
            DeviceKindSetting::Openhaptics => "openhaptics",
            DeviceKindSetting::Forcedimension => "forcedimension",
            DeviceKindSetting::Haply => "haply",
        }
    }
}

/// Parameters of the simulated PHANToM-class device (`[device]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeviceConfig {
    /// The device the run drives: `simulated` (default), `openhaptics`,
    /// `forcedimension` or `haply`; `--device` on the command line wins.
    /// The other keys describe the simulated device only.
    pub kind: DeviceKindSetting,
    /// Apparent end-effector mass at the stylus tip (kg), in [0.01, 5]: from
    /// the lightest desktop devices (~20 g) to large arm-scale devices (a few
    /// kg). Default 0.075.
    pub mass: f64,
    /// Viscous friction of the arm (N·s/m), in [0, 50] (the order of 1 N·s/m
    /// of PHANToM-class arms; 50 is already as viscous as the hand itself).
    /// Default 1.0.
    pub viscous_friction: f64,
    /// Peak force the device renders (N), in [0.5, 100]; larger commands are
    /// clamped (desktop devices 3–9 N, the largest commercial ones ~40 N,
    /// with margin). Default 6.0.
    pub max_force: f64,
    /// Largest stable rendered stiffness at `sampling_rate` (N/m), in [10,
    /// 1e5] (Colgate & Schenkel's `2 b / T` with `b` ≤ 50 N·s/m and `T` ≥
    /// 0.1 ms bounds it at 1e6; real devices 1–10 kN/m). Default 1000.
    pub max_stiffness: f64,
    /// Servo rate at which forces are expected (Hz), in [100, 10 000]
    /// (haptic servo loops run 0.5–10 kHz). Default 1000.
    pub sampling_rate: f64,
    /// Rate of the integration sub-steps inside [`advance`](crate::HapticDevice::advance)
    /// (Hz), in [10 000, 100 000]: at least 10 kHz so that the hand's
    /// fastest mode (`√(k/m)` ≤ 1 krad/s with `[hand]`'s bounds) is
    /// resolved; at most 100 kHz so that a run's sub-steps stay bounded (an
    /// hour at 100 kHz is already 3.6e8 sub-steps). Default 10 000.
    pub substep_rate: f64,
    /// Device force / tissue force (dimensionless), in [0.01, 10], see
    /// [`ForceScale`] (scales the clinical 5–40 N to a device's few N, or
    /// up). Default 0.3. On a patient's leg the scenario lowers it where it
    /// must (see `scale_to_patient`).
    pub force_scale: f64,
    /// Whether, on a patient's leg, `force_scale` is lowered where it must
    /// be so that `max_force / force_scale` covers the patient's exam force
    /// (the force at which the artery is clearly oval at the leg's hardest
    /// level, `echothigh_anatomy::Patient::exam_force`; the scenario applies
    /// it, `echothigh_runtime::scenario::Scenario::device`). Default true;
    /// false keeps the configured scale whatever the leg (the paper's Fig. 4
    /// experiment, `scenarios/fig4.toml`, whose device is the paper's).
    pub scale_to_patient: bool,
}

impl Default for DeviceConfig {
    fn default() -> Self {
        DeviceConfig {
            kind: DeviceKindSetting::Simulated,
            mass: 0.075,
            viscous_friction: 1.0,
            max_force: 6.0,
            max_stiffness: 1000.0,
            sampling_rate: 1000.0,
            substep_rate: 10_000.0,
            force_scale: ForceScale::DEFAULT,
            scale_to_patient: true,
        }
    }
}

impl DeviceConfig {
    /// Lowest accepted sub-step rate (Hz).
    pub const MIN_SUBSTEP_RATE: f64 = 10_000.0;

    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let mass = "must be in [0.01, 5] kg (desktop to arm-scale devices)";
        ConfigError::in_range(p, "mass", self.mass, (0.01, 5.0), mass)?;
        let visc = "must be in [0, 50] N·s/m (PHANToM-class arms ~1 N·s/m)";
        ConfigError::in_range(
            p,
            "viscous_friction",
            self.viscous_friction,
            (0.0, 50.0),
            visc,
        )?;
        let force = "must be in [0.5, 100] N (haptic devices' peak forces)";
        ConfigError::in_range(p, "max_force", self.max_force, (0.5, 100.0), force)?;
        let stiff = "must be in [10, 1e5] N/m (passivity bound 2b/T)";
        ConfigError::in_range(p, "max_stiffness", self.max_stiffness, (10.0, 1e5), stiff)?;
        let rate = "must be in [100, 10000] Hz (haptic servo rates)";
        ConfigError::in_range(p, "sampling_rate", self.sampling_rate, (100.0, 1e4), rate)?;
        let sub = "must be in [10000, 100000] Hz (resolves the hand; bounds the sub-steps)";
        ConfigError::in_range(p, "substep_rate", self.substep_rate, (1e4, 1e5), sub)?;
        let scale = "must be in [0.01, 10] (device force / tissue force)";
        ConfigError::in_range(p, "force_scale", self.force_scale, (0.01, 10.0), scale)
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
    /// Hand (and forearm) mass moving rigidly with the stylus (kg), in [0,
    /// 5] (0: a massless grip; a hand is ~0.4 kg, hand and forearm ~2 kg).
    /// Default 0.5.
    pub mass: f64,
    /// Stiffness of the spring pulling towards the setpoint (N/m), in [0,
    /// 5000]: postural arm stiffness is 200–1000 N/m relaxed and a few kN/m
    /// co-contracted (Mussa-Ivaldi et al. 1985; Tsuji et al. 1995). Default 300.
    pub stiffness: f64,
    /// Damping relative to the setpoint's velocity (N·s/m), in [0, 100]
    /// (measured hand damping is a few to ~10 N·s/m, Tsuji et al. 1995).
    /// Default 5.
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
        let p = prefix;
        let mass = "must be in [0, 5] kg (hand and forearm ~2 kg)";
        ConfigError::in_range(p, "mass", self.mass, (0.0, 5.0), mass)?;
        let stiff = "must be in [0, 5000] N/m (postural arm stiffness)";
        ConfigError::in_range(p, "stiffness", self.stiffness, (0.0, 5000.0), stiff)?;
        let damp = "must be in [0, 100] N·s/m (measured hand damping ~10 N·s/m)";
        ConfigError::in_range(p, "damping", self.damping, (0.0, 100.0), damp)
    }
}
