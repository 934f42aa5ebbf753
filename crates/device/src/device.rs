//! The [`HapticDevice`] seam, the force scale between tissue and device, and
//! the force limiter every device applies before anything is rendered.
//!
//! As in CHAI3D, the device knows nothing of the force algorithm: the haptic
//! loop reads [`HapticDevice::position`], computes a force with the proxy
//! (DESIGN §3), scales it with [`ForceScale`] and writes it with
//! [`HapticDevice::set_force`]. A real driver would implement the same trait
//! by exchanging with the hardware in [`HapticDevice::advance`].

use crate::error::ConfigError;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// Fault counters of a device (monotonic since construction).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceFaults {
    /// Forces rejected because a component was NaN or infinite (zero was rendered instead).
    pub non_finite: u64,
    /// Forces whose magnitude exceeded [`HapticDevice::max_force`] and were clamped.
    pub clamped: u64,
}

/// A force-feedback device, simulated or real, in the thigh frame.
///
/// Positions are of the end-effector (the probe's reference point) in the
/// thigh frame (m); forces are *device* forces (N), i.e. tissue forces
/// multiplied by a [`ForceScale`]. Object-safe: the runtime holds a
/// `Box<dyn HapticDevice + Send>`.
pub trait HapticDevice {
    /// End-effector position (m, thigh frame).
    fn position(&self) -> Vec3;
    /// End-effector velocity (m/s, thigh frame).
    fn velocity(&self) -> Vec3;
    /// Commands the device force (N), held constant until the next call.
    ///
    /// A magnitude above [`max_force`](Self::max_force) is clamped (direction
    /// kept, counted in [`DeviceFaults::clamped`]); a non-finite component
    /// makes the device output zero and counts [`DeviceFaults::non_finite`].
    fn set_force(&mut self, force: Vec3);
    /// The force actually rendered after limiting (N).
    fn force(&self) -> Vec3;
    /// Peak force the device can render (N).
    fn max_force(&self) -> f64;
    /// Largest virtual stiffness the device renders stably at its sampling rate (N/m).
    fn max_stiffness(&self) -> f64;
    /// Servo rate the device expects forces at (Hz), e.g. 1000.
    fn sampling_rate(&self) -> f64;
    /// Advances the device by `dt` (s) with the commanded force held over the
    /// call. A simulated device integrates its dynamics with sub-steps of at
    /// most 100 µs (≥ 10 kHz); a replay moves along its recording; a driver
    /// exchanges with the hardware. Non-finite or non-positive `dt` is ignored.
    fn advance(&mut self, dt: f64);
    /// Fault counters since construction.
    fn faults(&self) -> DeviceFaults;
    /// The tool's orientation in the thigh frame (thigh ← tool), where the
    /// device senses it (a Touch's gimbal, an omega.6/7's wrist); `None` for a
    /// 3-DoF device, whose probe stays normal to the skin.
    fn orientation(&self) -> Option<nalgebra::UnitQuaternion<f64>> {
        None
    }
    /// Whether the device is clutched (the user repositions the hand; the
    /// probe holds still and the force is zero). Simulated devices never are.
    fn clutched(&self) -> bool {
        false
    }
    /// The SDK error code that stopped the device (unplugged, a lost
    /// service, a driver fault), if it stopped: its force is zero from then
    /// on and its pose holds the last good reading. Simulated devices never stop.
    fn lost(&self) -> Option<u32> {
        None
    }
}

/// A boxed device is a device (the runtime drives `Box<dyn HapticDevice +
/// Send>` when the backend is chosen at run time: `--device NAME`).
impl<T: HapticDevice + ?Sized> HapticDevice for Box<T> {
    fn position(&self) -> Vec3 {
        (**self).position()
    }
    fn velocity(&self) -> Vec3 {
        (**self).velocity()
    }
    fn set_force(&mut self, force: Vec3) {
        (**self).set_force(force)
    }
    fn force(&self) -> Vec3 {
        (**self).force()
    }
    fn max_force(&self) -> f64 {
        (**self).max_force()
    }
    fn max_stiffness(&self) -> f64 {
        (**self).max_stiffness()
    }
    fn sampling_rate(&self) -> f64 {
        (**self).sampling_rate()
    }
    fn advance(&mut self, dt: f64) {
        (**self).advance(dt)
    }
    fn faults(&self) -> DeviceFaults {
        (**self).faults()
    }
    fn orientation(&self) -> Option<nalgebra::UnitQuaternion<f64>> {
        (**self).orientation()
    }
    fn clutched(&self) -> bool {
        (**self).clutched()
    }
    fn lost(&self) -> Option<u32> {
        (**self).lost()
    }
}

/// Limits a commanded force to `max_force` (N) and rejects non-finite input,
/// updating `faults`. Returns the force to render (N).
pub fn limit_force(force: Vec3, max_force: f64, faults: &mut DeviceFaults) -> Vec3 {
    if !(force.x.is_finite() && force.y.is_finite() && force.z.is_finite()) {
        faults.non_finite += 1;
        return Vec3::zeros();
    }
    let magnitude = force.norm();
    if magnitude > max_force {
        faults.clamped += 1;
        force * (max_force / magnitude)
    } else {
        force
    }
}

/// The scale between tissue force and device force: `f_device = scale × f_tissue`.
///
/// Clinical compression of the thigh uses probe forces of ~10–20 N, up to
/// ~30 N (DESIGN §2), while a PHANToM-class desktop device peaks at ~6–8 N
/// and sustains only ~1.5 N (Massie & Salisbury 1994, "The PHANToM haptic
/// interface: a device for probing virtual objects", ASME DSC 55-1; SensAble
/// PHANToM Premium 1.5 / Desktop specifications: 8.5 N / 7.9 N peak,
/// 1.4 N / 1.75 N continuous). The default 0.3 maps 20 N of tissue force to
/// the device's 6 N peak, so the whole clinical range below 20 N is felt
/// without saturation, in proportion.
///
/// The scale applies to forces only; positions are not scaled (the stylus
/// moves as far as the probe would). The stiffness felt through the device
/// is therefore also `scale × k_tissue`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ForceScale(f64);

impl ForceScale {
    /// Default scale: 20 N of tissue force ↦ 6 N of device force.
    pub const DEFAULT: f64 = 0.3;

    /// A scale `f_device / f_tissue` (dimensionless, finite, > 0).
    pub fn new(scale: f64) -> Result<Self, ConfigError> {
        ConfigError::positive("device", "force_scale", scale)?;
        Ok(ForceScale(scale))
    }

    /// The scale factor (dimensionless).
    pub fn value(self) -> f64 {
        self.0
    }

    /// Device force (N) for a tissue force (N).
    pub fn tissue_to_device(self, tissue_force: Vec3) -> Vec3 {
        tissue_force * self.0
    }

    /// Tissue force (N) that a device force (N) stands for.
    pub fn device_to_tissue(self, device_force: Vec3) -> Vec3 {
        device_force / self.0
    }
}

impl Default for ForceScale {
    fn default() -> Self {
        ForceScale(Self::DEFAULT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_keeps_direction_and_counts() {
        let mut faults = DeviceFaults::default();
        let f = limit_force(Vec3::new(0.0, 8.0, 6.0), 5.0, &mut faults);
        assert!((f.norm() - 5.0).abs() < 1e-12);
        assert!((f.normalize() - Vec3::new(0.0, 0.8, 0.6)).norm() < 1e-12);
        assert_eq!(
            faults,
            DeviceFaults {
                non_finite: 0,
                clamped: 1
            }
        );
        let g = limit_force(Vec3::new(1.0, 2.0, 2.0), 5.0, &mut faults);
        assert_eq!(g, Vec3::new(1.0, 2.0, 2.0));
        assert_eq!(faults.clamped, 1);
    }

    #[test]
    fn non_finite_force_renders_zero() {
        let mut faults = DeviceFaults::default();
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let f = limit_force(Vec3::new(1.0, bad, 0.0), 6.0, &mut faults);
            assert_eq!(f, Vec3::zeros());
        }
        assert_eq!(faults.non_finite, 3);
    }

    #[test]
    fn default_scale_maps_20_newtons_to_6() {
        let s = ForceScale::default();
        let d = s.tissue_to_device(Vec3::new(0.0, 20.0, 0.0));
        assert!((d.y - 6.0).abs() < 1e-12);
        assert!((s.device_to_tissue(d).y - 20.0).abs() < 1e-12);
        assert!(ForceScale::new(0.0).is_err());
        assert!(ForceScale::new(f64::NAN).is_err());
    }
}
