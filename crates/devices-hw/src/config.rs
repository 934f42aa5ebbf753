//! The backend selection ([`DeviceKind`]) and the `[device.hardware]`
//! configuration every backend shares.

use crate::calibration::DeviceToLeg;
use crate::safety::ThermalLimiter;
use echothigh_device::ConfigError;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

/// A real-device backend, as named by `--device NAME` and `[device] kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DeviceKind {
    /// 3D Systems Touch / Touch X / PHANTOM Premium through OpenHaptics HD (`libHD`).
    Openhaptics,
    /// Force Dimension delta / omega / sigma (and the Novint Falcon) through DHD (`libdhd`).
    Forcedimension,
    /// Haply Inverse3 (with a VerseGrip for orientation) through Haply's local Inverse Service.
    Haply,
}

impl DeviceKind {
    /// Every backend, in the order `echothigh devices` lists them.
    pub const ALL: [DeviceKind; 3] = [
        DeviceKind::Openhaptics,
        DeviceKind::Forcedimension,
        DeviceKind::Haply,
    ];

    /// The name used on the command line and in the scenario.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Openhaptics => "openhaptics",
            DeviceKind::Forcedimension => "forcedimension",
            DeviceKind::Haply => "haply",
        }
    }
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown backend name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown device backend `{0}`: expected one of openhaptics, forcedimension, haply")]
pub struct UnknownDeviceKind(pub String);

impl FromStr for DeviceKind {
    type Err = UnknownDeviceKind;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DeviceKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownDeviceKind(s.to_string()))
    }
}

/// `[device.hardware]`: settings shared by the real-device backends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HardwareConfig {
    /// Device → leg transform.
    pub calibration: DeviceToLeg,
    /// Force ramp-in at start and after each clutch (s). Default 0.5.
    pub ramp_time: f64,
    /// The servo thread zeroes the force when the tick sent nothing for this long (s);
    /// on DHD devices also the firmware watchdog (at most 255 × 125 µs = 31.875 ms). Default 0.01.
    pub watchdog_timeout: f64,
    /// Index of the button that clutches while held (0 = first). Default 1.
    pub clutch_button: u32,
    /// Thermal time constant of the continuous-force limiter (s). Default 10.
    pub thermal_time_constant: f64,
    /// OpenHaptics settings.
    pub openhaptics: OpenHapticsConfig,
    /// Force Dimension settings.
    pub forcedimension: ForceDimensionConfig,
    /// Haply Inverse Service settings.
    pub haply: HaplyConfig,
}

/// `[device.hardware.openhaptics]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpenHapticsConfig {
    /// Path of `libHD` (the environment variable `ECHOTHIGH_HD_LIB` wins). Default: the system's `libHD`.
    pub library: Option<PathBuf>,
    /// Device name from the Touch Setup utility; default `HD_DEFAULT_DEVICE`.
    pub device_name: Option<String>,
}

/// `[device.hardware.forcedimension]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ForceDimensionConfig {
    /// Path of `libdhd` (the environment variable `ECHOTHIGH_DHD_LIB` wins). Default: the system's `libdhd`.
    pub library: Option<PathBuf>,
    /// Rate of the servo thread that talks to the device (Hz). Default 1000.
    pub servo_rate: f64,
}

impl Default for ForceDimensionConfig {
    fn default() -> Self {
        ForceDimensionConfig {
            library: None,
            servo_rate: 1000.0,
        }
    }
}

/// `[device.hardware.haply]`: how to reach Haply's Inverse Service.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HaplyConfig {
    /// WebSocket address of the service's simulation channel (the environment
    /// variable `ECHOTHIGH_HAPLY_URL` wins). Default `ws://localhost:10001`
    /// (Inverse Service 3.5: simulation channel and HTTP on port 10001).
    pub url: Option<String>,
    /// The Inverse3 to drive, by its `device_id`; default: the first listed.
    pub device_id: Option<String>,
    /// Rate of the exchange thread's command/state round trips (Hz). Default 1000.
    pub rate: f64,
    /// Connecting and the WebSocket handshake give up after this long (s). Default 1.
    pub connect_timeout: f64,
    /// A state frame not answered within this long declares the service lost (s). Default 0.1.
    pub reply_timeout: f64,
}

impl Default for HaplyConfig {
    fn default() -> Self {
        HaplyConfig {
            url: None,
            device_id: None,
            rate: 1000.0,
            connect_timeout: 1.0,
            reply_timeout: 0.1,
        }
    }
}

impl Default for HardwareConfig {
    fn default() -> Self {
        HardwareConfig {
            calibration: DeviceToLeg::default(),
            ramp_time: 0.5,
            watchdog_timeout: 0.01,
            clutch_button: 1,
            thermal_time_constant: ThermalLimiter::DEFAULT_TAU,
            openhaptics: OpenHapticsConfig::default(),
            forcedimension: ForceDimensionConfig::default(),
            haply: HaplyConfig::default(),
        }
    }
}

/// Longest DHD firmware watchdog: 255 × 125 µs (s).
pub const MAX_WATCHDOG: f64 = 255.0 * 125e-6;

impl HardwareConfig {
    /// Checks every field, naming the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        self.calibration
            .validate(&format!("{prefix}.calibration"))?;
        ConfigError::non_negative(prefix, "ramp_time", self.ramp_time)?;
        ConfigError::positive(prefix, "watchdog_timeout", self.watchdog_timeout)?;
        if self.watchdog_timeout > MAX_WATCHDOG {
            return Err(ConfigError::invalid(
                prefix,
                "watchdog_timeout",
                self.watchdog_timeout,
                "must be <= 0.031875 s (the DHD firmware's longest watchdog)",
            ));
        }
        if self.clutch_button > 31 {
            return Err(ConfigError::invalid(
                prefix,
                "clutch_button",
                self.clutch_button,
                "must be a button index 0..=31",
            ));
        }
        ConfigError::positive(prefix, "thermal_time_constant", self.thermal_time_constant)?;
        ConfigError::positive(
            &format!("{prefix}.forcedimension"),
            "servo_rate",
            self.forcedimension.servo_rate,
        )?;
        if self.forcedimension.servo_rate > 10_000.0 {
            return Err(ConfigError::invalid(
                &format!("{prefix}.forcedimension"),
                "servo_rate",
                self.forcedimension.servo_rate,
                "must be <= 10000 Hz (DHD devices run up to 8 kHz)",
            ));
        }
        let haply = format!("{prefix}.haply");
        ConfigError::positive(&haply, "rate", self.haply.rate)?;
        if self.haply.rate > 10_000.0 {
            return Err(ConfigError::invalid(
                &haply,
                "rate",
                self.haply.rate,
                "must be <= 10000 Hz",
            ));
        }
        ConfigError::positive(&haply, "connect_timeout", self.haply.connect_timeout)?;
        ConfigError::positive(&haply, "reply_timeout", self.haply.reply_timeout)?;
        if let Some(url) = &self.haply.url {
            if !(url.starts_with("ws://") || url.starts_with("wss://")) {
                return Err(ConfigError::invalid(
                    &haply,
                    "url",
                    url,
                    "must be a WebSocket address ws://HOST:PORT",
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_parses_and_round_trips() {
        assert_eq!(
            "OpenHaptics".parse::<DeviceKind>().unwrap(),
            DeviceKind::Openhaptics
        );
        let e = "phantom".parse::<DeviceKind>().unwrap_err().to_string();
        assert!(e.contains("openhaptics, forcedimension"), "{e}");
        for k in DeviceKind::ALL {
            assert_eq!(k.name().parse::<DeviceKind>().unwrap(), k);
        }
    }

    #[test]
    fn validation_names_keys() {
        let mut c = HardwareConfig::default();
        c.validate("device.hardware").unwrap();
        c.watchdog_timeout = 0.05;
        let e = c.validate("device.hardware").unwrap_err().to_string();
        assert!(e.contains("device.hardware.watchdog_timeout"), "{e}");
        c.watchdog_timeout = 0.01;
        c.forcedimension.servo_rate = f64::NAN;
        let e = c.validate("device.hardware").unwrap_err().to_string();
        assert!(
            e.contains("device.hardware.forcedimension.servo_rate"),
            "{e}"
        );
    }
}
