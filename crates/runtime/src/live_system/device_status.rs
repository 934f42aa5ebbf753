//! What the live system tells the page of a real device driving the probe
//! (issue 15), and why it refuses the page's probe commands meanwhile.

use super::LiveSystem;
use crate::live_device::{lost_message, LiveDeviceStatus};

/// Why the page's probe commands are refused while a device drives.
pub fn device_drives_message(name: &str) -> String {
    format!(
        "the haptic device ({name}) drives the probe: the page's probe controls are off while it \
         is attached (move the stylus; hold its clutch button to reposition your hand)"
    )
}

impl LiveSystem {
    /// The attached device's state for the page (`None` without one).
    pub(super) fn device_status(&self) -> Option<LiveDeviceStatus> {
        let info = self.device_info.as_ref()?;
        let mut status = LiveDeviceStatus {
            name: info.name.clone(),
            connected: true,
            clutched: false,
            force: [0.0; 3],
            max_force: info.max_force,
            orientation_sensed: info.orientation_sensed,
            workspace: info.workspace,
            lost: None,
        };
        if let Ok(mut d) = self.shared.device.lock() {
            match d.as_mut().map(|o| *o.read()) {
                Some(t) => {
                    status.clutched = t.clutched;
                    status.force = t.force;
                    if let Some(code) = t.lost {
                        status.connected = false;
                        status.lost = Some(lost_message(&info.name, code));
                    }
                }
                None => {
                    status.connected = false;
                    status.lost = Some(format!("the haptic device ({}) is not running", info.name));
                }
            }
        }
        Some(status)
    }

    /// Whether a real device drives the probe.
    pub fn device_drives(&self) -> bool {
        self.device_info.is_some()
    }
}
