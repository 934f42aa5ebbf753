//! Diagnostics: which backends can start here, and why not (`echothigh devices`).

use crate::config::HardwareConfig;
use crate::hardware::DeviceInfo;
use crate::{open_hardware, DeviceError, DeviceKind};
use serde::Serialize;

/// One backend's state on this machine.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BackendReport {
    /// The backend.
    pub backend: DeviceKind,
    /// The SDK it needs.
    pub sdk: &'static str,
    /// The library file looked for (after the environment variable and the
    /// configuration); for a service-based backend, the service's address.
    pub library: String,
    /// The environment variable that overrides the library's path (or the service's address).
    pub env_var: &'static str,
    /// Its value, when set.
    pub env_value: Option<String>,
    /// Whether the library loaded with every function the backend calls
    /// (for `haply`: whether this build has the backend's client).
    pub found: bool,
    /// Whether a local service is reachable: `None` for the SDKs that need
    /// none (HD, DHD); for `haply`, whether the Inverse Service answered.
    pub service_reachable: Option<bool>,
    /// Devices found, with model, workspace and limits.
    pub devices: Vec<DeviceInfo>,
    /// Why no device can be used, with what to do about it; `None` when one can.
    pub reason: Option<String>,
}

/// Probes one backend: loads its library and, if that works, opens the
/// first device briefly (zero force: the ramp-in has not begun) to read its
/// description, then closes it.
pub fn probe(kind: DeviceKind, config: &HardwareConfig) -> BackendReport {
    let (spec, configured) = match kind {
        DeviceKind::Openhaptics => (
            crate::openhaptics::library_spec(),
            config.openhaptics.library.as_ref(),
        ),
        DeviceKind::Forcedimension => (
            crate::forcedimension::library_spec(),
            config.forcedimension.library.as_ref(),
        ),
        DeviceKind::Haply => return probe_haply(config),
    };
    let library = spec.resolve(configured);
    let mut report = BackendReport {
        backend: kind,
        sdk: spec.sdk,
        library,
        env_var: spec.env_var,
        env_value: std::env::var(spec.env_var).ok(),
        found: false,
        service_reachable: None,
        devices: Vec::new(),
        reason: None,
    };
    match open_hardware(kind, config) {
        Ok(device) => {
            report.found = true;
            report.devices.push(device.info().clone());
        }
        Err(e) => {
            report.found = !matches!(
                e,
                DeviceError::LibraryNotFound { .. } | DeviceError::MissingSymbol { .. }
            );
            report.reason = Some(e.to_string());
        }
    }
    report
}

/// Probes the Haply backend: connects to the Inverse Service, reads its
/// inventory and, when it lists an Inverse3, opens it briefly (zero force)
/// for its description.
#[cfg(feature = "haply")]
fn probe_haply(config: &HardwareConfig) -> BackendReport {
    use crate::haply;
    let mut report = BackendReport {
        backend: DeviceKind::Haply,
        sdk: haply::SERVICE,
        library: haply::resolve_url(config),
        env_var: haply::ENV_VAR,
        env_value: std::env::var(haply::ENV_VAR).ok(),
        found: true,
        service_reachable: Some(false),
        devices: Vec::new(),
        reason: None,
    };
    if let Err(e) = haply::inventory(config) {
        report.reason = Some(e.to_string());
        return report;
    }
    report.service_reachable = Some(true);
    match open_hardware(DeviceKind::Haply, config) {
        Ok(device) => report.devices.push(device.info().clone()),
        Err(e) => report.reason = Some(e.to_string()),
    }
    report
}

/// Without the `haply` feature: the backend is reported absent, saying why.
#[cfg(not(feature = "haply"))]
fn probe_haply(_config: &HardwareConfig) -> BackendReport {
    BackendReport {
        backend: DeviceKind::Haply,
        sdk: "Haply Inverse Service",
        library: "ws://localhost:10001".into(),
        env_var: "ECHOTHIGH_HAPLY_URL",
        env_value: std::env::var("ECHOTHIGH_HAPLY_URL").ok(),
        found: false,
        service_reachable: None,
        devices: Vec::new(),
        reason: Some(
            DeviceError::NotBuilt {
                backend: DeviceKind::Haply,
                feature: "haply",
            }
            .to_string(),
        ),
    }
}

/// Probes every backend, in [`DeviceKind::ALL`] order.
pub fn probe_all(config: &HardwareConfig) -> Vec<BackendReport> {
    DeviceKind::ALL
        .into_iter()
        .map(|k| probe(k, config))
        .collect()
}
