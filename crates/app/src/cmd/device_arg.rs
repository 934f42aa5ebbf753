//! `--device NAME` (and `--hardware FILE`) of `run` and `haptic-client`:
//! which device the one haptic tick drives — the scenario's simulated hand
//! and device, or a real device through its vendor's library, loaded at run
//! time (`echothigh devices` lists what this machine has).

use anyhow::{Context, Result};
use echothigh_device::HapticDevice;
use echothigh_devices_hw::{open_device, DeviceKind, HardwareConfig};
use std::path::PathBuf;

/// The device a run drives.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeviceArg {
    /// The scenario's simulated device, moved by its scripted hand.
    #[default]
    Simulated,
    /// 3D Systems Touch / Touch X / PHANTOM Premium (OpenHaptics HD,
    /// `libHD`; override the path with ECHOTHIGH_HD_LIB).
    Openhaptics,
    /// Force Dimension delta / omega / sigma, Novint Falcon (DHD, `libdhd`;
    /// override the path with ECHOTHIGH_DHD_LIB).
    Forcedimension,
}

/// The device options shared by the commands that run the haptic loop.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Haptic device the loop drives: `simulated` (default) or a real one;
    /// with a real device a person's hand replaces the exam script.
    #[arg(long, value_enum, default_value_t)]
    pub device: DeviceArg,
    /// The real device's settings, a TOML file of `[device.hardware]` keys
    /// (calibration, ramp_time, watchdog_timeout, clutch_button,
    /// thermal_time_constant, [openhaptics], [forcedimension]); defaults
    /// otherwise.
    #[arg(long)]
    pub hardware: Option<PathBuf>,
}

impl DeviceArgs {
    /// Opens the real device asked for (`None` for `simulated`). A missing
    /// library, no device or a bad settings file is an error naming the
    /// file, the library and the variable that overrides its path.
    pub fn open(&self) -> Result<Option<Box<dyn HapticDevice + Send>>> {
        let kind = match self.device {
            DeviceArg::Simulated if self.hardware.is_some() => {
                anyhow::bail!(
                    "--hardware applies to a real device: add --device openhaptics|forcedimension"
                )
            }
            DeviceArg::Simulated => return Ok(None),
            DeviceArg::Openhaptics => DeviceKind::Openhaptics,
            DeviceArg::Forcedimension => DeviceKind::Forcedimension,
        };
        let config = match &self.hardware {
            None => HardwareConfig::default(),
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("reading {}", path.display()))?;
                toml::from_str(&text).with_context(|| format!("{}", path.display()))?
            }
        };
        let device = open_device(&kind, &config).with_context(|| {
            format!("opening the {kind} device (`echothigh devices` lists what is installed)")
        })?;
        Ok(Some(device))
    }
}
