//! A real haptic device driving the live system (issue 15): what the front
//! end (`echothigh view --device NAME`, `echothigh exam --device NAME`) hands
//! the live system, and what the page is told of it.
//!
//! The runtime does not open devices (that is `echothigh-devices-hw`'s job,
//! called by the binary): it receives a device already calibrated into the
//! thigh's frame as a `Box<dyn HapticDevice + Send>` together with its
//! description ([`LiveDeviceInfo`]), drives it with the one haptic tick
//! instead of the page's probe commands, and reports its state
//! ([`LiveDeviceStatus`]) with every snapshot.
//!
//! Units: SI (m, N), the thigh (model) frame the physics uses.

use echothigh_device::HapticDevice;
use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// A real device for the live system, and its description.
pub struct LiveDevice {
    /// The device, positions and forces in the thigh frame (calibrated).
    pub device: Box<dyn HapticDevice + Send>,
    /// What the page shows of it.
    pub info: LiveDeviceInfo,
}

/// What the page is told of the device, fixed while it is attached.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LiveDeviceInfo {
    /// Backend and model, e.g. `openhaptics: Touch`.
    pub name: String,
    /// Whether the device senses the tool's orientation (then it sets the
    /// probe's rotation about the leg and its tilt; else the probe stays
    /// normal to the skin).
    pub orientation_sensed: bool,
    /// Peak force the device renders (N, device units).
    pub max_force: f64,
    /// The device's usable workspace mapped into the thigh frame: the eight
    /// corners of its box (m), corner `i` at the box's maximum along device
    /// axis `k` when bit `k` of `i` is set ([`LiveDeviceInfo::box_corners`]);
    /// `None` when the SDK reports no workspace.
    pub workspace: Option<[[f64; 3]; 8]>,
}

impl LiveDeviceInfo {
    /// The corners of the device-frame box `[min, max]` (m) mapped by
    /// `thigh_from_device` (the calibration `p_thigh = R p_device + t`), in
    /// the order of [`LiveDeviceInfo::workspace`].
    pub fn box_corners(
        min: [f64; 3],
        max: [f64; 3],
        thigh_from_device: &Isometry3<f64>,
    ) -> [[f64; 3]; 8] {
        std::array::from_fn(|i| {
            let pick = |k: usize| if i & (1 << k) != 0 { max[k] } else { min[k] };
            let p = thigh_from_device * Point3::new(pick(0), pick(1), pick(2));
            [p.x, p.y, p.z]
        })
    }
}

/// The device's state as the page shows it, with every snapshot.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LiveDeviceStatus {
    /// Backend and model ([`LiveDeviceInfo::name`]).
    pub name: String,
    /// Whether the device answers; `false` once it stopped (unplugged, its
    /// service gone), after which its force is zero.
    pub connected: bool,
    /// Whether the trainee holds the clutch (the probe stays, the force is
    /// zero; it ramps in again on release).
    pub clutched: bool,
    /// The force the device renders after its safety chain (N, device
    /// units, thigh frame): the tissue force times the force scale, limited.
    pub force: [f64; 3],
    /// Peak force of the device (N).
    pub max_force: f64,
    /// Whether the device sets the probe's orientation.
    pub orientation_sensed: bool,
    /// The workspace box in the thigh frame ([`LiveDeviceInfo::workspace`]).
    pub workspace: Option<[[f64; 3]; 8]>,
    /// Why the device stopped, in plain words (`None` while it runs).
    pub lost: Option<String>,
}

impl LiveDeviceStatus {
    /// A copy with every non-finite number replaced by 0.
    pub fn sanitized(&self) -> LiveDeviceStatus {
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        LiveDeviceStatus {
            force: self.force.map(finite),
            max_force: finite(self.max_force),
            workspace: self.workspace.map(|w| w.map(|c| c.map(finite))),
            ..self.clone()
        }
    }
}

/// What the haptic loop reports of the device every tick (lock-free).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DeviceTick {
    /// [`HapticDevice::clutched`].
    pub clutched: bool,
    /// [`HapticDevice::force`] (N).
    pub force: [f64; 3],
    /// [`HapticDevice::lost`].
    pub lost: Option<u32>,
}

/// The plain words of a stopped device's SDK code.
pub fn lost_message(name: &str, code: u32) -> String {
    format!(
        "the haptic device ({name}) stopped answering (SDK code {code:#x}): its force is zero. \
         Check its cable or service, then restart echothigh"
    )
}

/// The unit outward normal of the elliptic cylinder `x²/a² + y²/b² = 1`
/// near `p` (m): the normal at the ellipse's point of elliptic parameter
/// `atan2(y/b, x/a)` (exact on the skin, the nearest-normal approximation
/// off it).
pub fn ellipse_normal(a: f64, b: f64, p: &Vector3<f64>) -> Vector3<f64> {
    let t = (p.y / b).atan2(p.x / a);
    Vector3::new(b * t.cos(), a * t.sin(), 0.0).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn box_corners_follow_the_calibration() {
        // A quarter turn about y (device +x ↦ thigh −z) and a shift of 0.1 m up.
        let iso = Isometry3::from_parts(
            Translation3::new(0.0, 0.1, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
        );
        let c = LiveDeviceInfo::box_corners([-0.08, -0.06, -0.035], [0.08, 0.06, 0.035], &iso);
        // Corner 1 is (max x, min y, min z) in the device frame: R(0.08,
        // −0.06, −0.035) = (−0.035, −0.06, −0.08), plus the shift.
        let want = [-0.035, 0.04, -0.08];
        for k in 0..3 {
            assert!((c[1][k] - want[k]).abs() < 1e-12, "{:?}", c[1]);
        }
        // A rigid motion keeps the box's diagonal: |c7 − c0| = |max − min|.
        let d = |p: [f64; 3], q: [f64; 3]| Vector3::from(p) - Vector3::from(q);
        let diag = (0.16f64.powi(2) + 0.12f64.powi(2) + 0.07f64.powi(2)).sqrt();
        assert!((d(c[7], c[0]).norm() - diag).abs() < 1e-12);
    }

    #[test]
    fn ellipse_normal_is_the_gradient_on_the_skin() {
        let (a, b) = (0.08, 0.072);
        for t in [0.0, 0.4, 1.3, 2.5, -1.0] {
            let p = Vector3::new(a * f64::cos(t), b * f64::sin(t), 0.03);
            // ∇(x²/a² + y²/b²) = (2x/a², 2y/b²), normalized.
            let g = Vector3::new(p.x / (a * a), p.y / (b * b), 0.0).normalize();
            assert!((ellipse_normal(a, b, &p) - g).norm() < 1e-12);
        }
    }
}
