//! `--device NAME` (and `--hardware FILE`) of `run` and `haptic-client`:
//! which device the one haptic tick drives — the scenario's simulated hand
//! and device, or a real device through its vendor's library, loaded at run
//! time (`echothigh devices` lists what this machine has).

use anyhow::{Context, Result};
use echothigh_device::{DeviceKindSetting, HapticDevice};
use echothigh_devices_hw::{open_hardware, DeviceKind, HardwareConfig, HardwareDevice};
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
    /// Haply Inverse3 with a VerseGrip, through Haply's Inverse Service
    /// (default ws://localhost:10001; override with ECHOTHIGH_HAPLY_URL).
    Haply,
}

impl DeviceArg {
    /// The real-device backend, `None` for the simulated device.
    pub fn kind(self) -> Option<DeviceKind> {
        match self {
            DeviceArg::Simulated => None,
            DeviceArg::Openhaptics => Some(DeviceKind::Openhaptics),
            DeviceArg::Forcedimension => Some(DeviceKind::Forcedimension),
            DeviceArg::Haply => Some(DeviceKind::Haply),
        }
    }
}

/// The device options shared by the commands that run the haptic loop.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Haptic device the loop drives: `simulated` or a real one; with a
    /// real device a person's hand replaces the exam script. Default: the
    /// scenario's `[device] kind` (itself `simulated` by default).
    #[arg(long, value_enum)]
    pub device: Option<DeviceArg>,
    /// The real device's settings, a TOML file of `[device.hardware]` keys
    /// (calibration, ramp_time, watchdog_timeout, clutch_button,
    /// thermal_time_constant, [openhaptics], [forcedimension], [haply]); defaults
    /// otherwise.
    #[arg(long)]
    pub hardware: Option<PathBuf>,
}

impl DeviceArg {
    /// The device a scenario's `[device] kind` names.
    pub fn from_setting(setting: DeviceKindSetting) -> DeviceArg {
        match setting {
            DeviceKindSetting::Simulated => DeviceArg::Simulated,
            DeviceKindSetting::Openhaptics => DeviceArg::Openhaptics,
            DeviceKindSetting::Forcedimension => DeviceArg::Forcedimension,
            DeviceKindSetting::Haply => DeviceArg::Haply,
        }
    }
}

impl DeviceArgs {
    /// The device to drive: `--device` if given, else the scenario's `[device] kind`.
    pub fn chosen(&self, scenario: DeviceKindSetting) -> DeviceArg {
        self.device
            .unwrap_or_else(|| DeviceArg::from_setting(scenario))
    }

    /// Opens the real device chosen (`None` for `simulated`; `scenario` is
    /// the scenario's `[device] kind`). A missing library, an unreachable
    /// service, no device or a bad settings file is an error naming the
    /// file, the library or address, and the variable that overrides it.
    pub fn open(
        &self,
        scenario: DeviceKindSetting,
    ) -> Result<Option<Box<dyn HapticDevice + Send>>> {
        Ok(self
            .open_hardware(scenario)?
            .map(|d| Box::new(d) as Box<dyn HapticDevice + Send>))
    }

    /// [`DeviceArgs::open`], the concrete device (its description,
    /// calibration and diagnostics).
    pub fn open_hardware(&self, scenario: DeviceKindSetting) -> Result<Option<HardwareDevice>> {
        let Some(kind) = self.chosen(scenario).kind() else {
            if self.hardware.is_some() {
                anyhow::bail!(
                    "--hardware applies to a real device: add --device openhaptics|forcedimension|haply"
                );
            }
            return Ok(None);
        };
        let config = match &self.hardware {
            None => HardwareConfig::default(),
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("reading {}", path.display()))?;
                toml::from_str(&text).with_context(|| format!("{}", path.display()))?
            }
        };
        let device = open_hardware(kind, &config).with_context(|| {
            format!("opening the {kind} device (`echothigh devices` lists what is installed)")
        })?;
        Ok(Some(device))
    }
}
