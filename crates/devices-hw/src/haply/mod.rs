//! Haply backend: the Inverse3 (and Minverse) with a VerseGrip for the
//! tool's orientation, through Haply's local Inverse Service.
//!
//! The service (3.5) owns the USB link to the devices and speaks JSON over
//! a WebSocket, by default `ws://localhost:10001` (`ECHOTHIGH_HAPLY_URL` or
//! `[device.hardware.haply] url` override it). Frames are the `haply`
//! crate's message types ([`wire`]); the exchange thread ([`link`]) makes
//! the command/state round trips off the tick. Units on the wire are SI
//! already: position m, velocity m/s, force N, in the Inverse3's base frame
//! (right-handed, origin on the mounting plate); the VerseGrip's
//! orientation is a unit quaternion taken as device ← grip.
//!
//! Watchdog: the exchange thread sends zero force once the tick's command is
//! older than `watchdog_timeout` ([`crate::servo`]). The service's own
//! behaviour when commands stop is not documented, so the backend never
//! relies on it: every exit path (drop, stop, panic unwinding through the
//! [`HardwareDevice`]) sends a zero-force frame before closing. Limits: the
//! Inverse3 is not in [`crate::safety::LIMITS`] (no sourced force figures
//! were found), so [`ModelLimits::for_model`] gives it the weakest listed
//! device's.

pub mod link;
pub mod wire;

use crate::config::HardwareConfig;
use crate::hardware::{Backend, DeviceInfo, HardwareDevice};
use crate::safety::ModelLimits;
use crate::servo::{exchange, Shared};
use crate::{DeviceError, DeviceKind};
use link::{Exchange, Link};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;
pub use wire::Inventory;

/// The environment variable that overrides the service's address.
pub const ENV_VAR: &str = "ECHOTHIGH_HAPLY_URL";
/// The Inverse Service 3.5's simulation channel.
pub const DEFAULT_URL: &str = "ws://localhost:10001";
/// The service's name in messages.
pub const SERVICE: &str = "Haply Inverse Service";

/// The address to use: the environment variable if set and non-empty, else
/// the configured one, else [`DEFAULT_URL`].
pub fn resolve_url(config: &HardwareConfig) -> String {
    match std::env::var(ENV_VAR) {
        Ok(v) if !v.trim().is_empty() => v.trim().to_string(),
        _ => config
            .haply
            .url
            .clone()
            .unwrap_or_else(|| DEFAULT_URL.to_string()),
    }
}

fn unreachable(url: &str, detail: String) -> DeviceError {
    DeviceError::ServiceUnreachable {
        backend: DeviceKind::Haply,
        service: SERVICE,
        url: url.to_string(),
        env_var: ENV_VAR,
        detail,
    }
}

/// Connects to the service and reads its inventory, then closes (for
/// `echothigh devices`).
pub fn inventory(config: &HardwareConfig) -> Result<Inventory, DeviceError> {
    let url = resolve_url(config);
    let (link, inv) = Link::connect(
        &url,
        config.haply.connect_timeout,
        config.haply.reply_timeout,
    )
    .map_err(|e| unreachable(&url, e))?;
    link.close();
    Ok(inv)
}

struct HaplyBackend {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Backend for HaplyBackend {
    /// The exchange thread sees the stop flag, sends zero force, closes the session.
    fn close(&mut self) {
        if let Some(thread) = self.thread.take() {
            self.shared.stop.store(true, Ordering::Release);
            let _ = thread.join();
        }
    }
}

impl Drop for HaplyBackend {
    fn drop(&mut self) {
        self.close();
    }
}

/// Connects, picks the Inverse3 (`haply.device_id` or the first) and the
/// first VerseGrip, and starts the exchange thread.
pub fn open(config: &HardwareConfig) -> Result<HardwareDevice, DeviceError> {
    config.validate("device.hardware")?;
    let url = resolve_url(config);
    let (link, inv) = Link::connect(
        &url,
        config.haply.connect_timeout,
        config.haply.reply_timeout,
    )
    .map_err(|e| unreachable(&url, e))?;
    let chosen = match &config.haply.device_id {
        Some(id) => inv.inverse3.iter().find(|d| &d.id == id),
        None => inv.inverse3.first(),
    };
    let Some(device) = chosen.cloned() else {
        link.close();
        let listed: Vec<&str> = inv.inverse3.iter().map(|d| d.id.as_str()).collect();
        return Err(DeviceError::NoDevice {
            backend: DeviceKind::Haply,
            detail: match &config.haply.device_id {
                Some(id) => format!(
                    "the {SERVICE} at {url} lists no Inverse3 `{id}` (it lists {listed:?}); fix [device.hardware.haply] device_id"
                ),
                None => format!(
                    "the {SERVICE} at {url} lists no Inverse3; is it powered and connected by USB?"
                ),
            },
        });
    };
    let grip = inv.grips.first().map(|g| g.id.clone());
    let (tick, side, shared) = exchange(config.watchdog_timeout);
    let run = Exchange {
        link,
        side,
        device: device.id.clone(),
        grip: grip.clone(),
        period: Duration::from_secs_f64(1.0 / config.haply.rate),
    };
    let thread = std::thread::Builder::new()
        .name("haply-exchange".into())
        .spawn(move || run.run())
        .map_err(|e| DeviceError::Sdk {
            backend: DeviceKind::Haply,
            call: "spawn exchange thread",
            detail: e.to_string(),
        })?;
    let backend = HaplyBackend {
        shared: Arc::clone(&shared),
        thread: Some(thread),
    };
    let model = match &grip {
        Some(g) => format!("{} {} + VerseGrip {g}", device.kind, device.id),
        None => format!("{} {}", device.kind, device.id),
    };
    let info = DeviceInfo {
        backend: DeviceKind::Haply,
        limits: ModelLimits::for_model(&device.kind),
        model,
        workspace_min: None,
        workspace_max: None,
        orientation_sensed: grip.is_some(),
        servo_rate: config.haply.rate,
        watchdog: "exchange thread only (the service offers no command watchdog to arm)",
    };
    Ok(HardwareDevice::new(
        Box::new(backend),
        tick,
        shared,
        info,
        config,
    ))
}
