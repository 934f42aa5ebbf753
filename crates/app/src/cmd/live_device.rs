//! The real device of `echothigh view` and `echothigh exam --trainee`
//! (issue 15): `--device NAME` (or the scenario's `[device] kind`) opened
//! here, with its description for the page — its model, limits and the
//! workspace box mapped into the thigh frame by the calibration — and handed
//! to the live system, whose one haptic tick then reads it instead of the
//! page's probe commands.

use super::device_arg::DeviceArgs;
use anyhow::Result;
use echothigh_device::DeviceKindSetting;
use echothigh_runtime::live_device::{LiveDevice, LiveDeviceInfo};

/// Opens the device `args` chose (`None`: the simulated hand, which the
/// page drives). A missing library, an unreachable service or no device is
/// an error naming the library or address and the variable that overrides it.
pub fn open(args: &DeviceArgs, scenario: DeviceKindSetting) -> Result<Option<LiveDevice>> {
    let Some(device) = args.open_hardware(scenario)? else {
        return Ok(None);
    };
    let info = device.info();
    let iso = device.calibration().isometry();
    let workspace = match (info.workspace_min, info.workspace_max) {
        (Some(min), Some(max)) => Some(LiveDeviceInfo::box_corners(min, max, &iso)),
        _ => None,
    };
    let info = LiveDeviceInfo {
        name: format!("{}: {}", info.backend, info.model),
        orientation_sensed: info.orientation_sensed,
        max_force: info.limits.peak_force,
        workspace,
    };
    eprintln!(
        "haptic device: {} (peak {:.1} N, orientation {}); it drives the probe",
        info.name,
        info.max_force,
        if info.orientation_sensed {
            "sensed"
        } else {
            "not sensed: the probe stays normal to the skin"
        }
    );
    Ok(Some(LiveDevice {
        device: Box::new(device),
        info,
    }))
}
