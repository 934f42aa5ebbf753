//! [`HardwareDevice`]: a real device behind [`HapticDevice`], whatever its SDK.
//!
//! The tick's side of a backend: reading the servo thread's latest state,
//! mapping it through the calibration and the clutch into the leg frame, and
//! sending back the force after the safety chain (peak clamp and NaN
//! rejection, the thermal continuous-force limiter, clutch and fault
//! zeroing, the ramp-in), rotated into the device frame. Everything here is
//! wait-free and allocation-free; the SDK is only touched by its servo thread.

use crate::calibration::DeviceToLeg;
use crate::config::HardwareConfig;
use crate::safety::{Clutch, ForceRamp, ModelLimits, ThermalLimiter};
use crate::servo::{EmergencyRelease, ServoState, Shared, TickSide};
use crate::{DeviceKind, Vec3};
use echothigh_device::{limit_force, DeviceFaults, HapticDevice};
use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, UnitQuaternion};
use serde::Serialize;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// What a backend knows about its connected device.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeviceInfo {
    /// The backend.
    pub backend: DeviceKind,
    /// Model name as the SDK reports it.
    pub model: String,
    /// Usable workspace (m, device frame): minimum corner, when the SDK reports it.
    pub workspace_min: Option<[f64; 3]>,
    /// Usable workspace (m, device frame): maximum corner.
    pub workspace_max: Option<[f64; 3]>,
    /// Limits used (the table's, tightened by the SDK's where it reports them).
    pub limits: ModelLimits,
    /// Whether the device senses the tool's orientation.
    pub orientation_sensed: bool,
    /// Rate of the servo thread (Hz).
    pub servo_rate: f64,
    /// Where the stall watchdog runs.
    pub watchdog: &'static str,
}

/// The SDK side of a backend: owns the connection and its servo thread.
pub trait Backend: Send {
    /// Renders zero, stops the servo thread and releases the device. Idempotent.
    fn close(&mut self);
}

/// A real haptic device in the leg frame (see the module docs).
pub struct HardwareDevice {
    tick: TickSide,
    shared: Arc<Shared>,
    backend: Box<dyn Backend>,
    info: DeviceInfo,
    calibration: Isometry3<f64>,
    clutch: Clutch,
    clutch_mask: u32,
    ramp: ForceRamp,
    thermal: ThermalLimiter,
    state: ServoState,
    fault: u32,
    position: Vec3,
    velocity: Vec3,
    orientation: UnitQuaternion<f64>,
    rendered: Vec3,
    faults: DeviceFaults,
    last_dt: f64,
}

impl HardwareDevice {
    /// Wraps a started backend. `tick`/`shared` are the halves the backend's
    /// servo thread exchanges with.
    pub(crate) fn new(
        backend: Box<dyn Backend>,
        tick: TickSide,
        shared: Arc<Shared>,
        info: DeviceInfo,
        config: &HardwareConfig,
    ) -> Self {
        let mut device = HardwareDevice {
            tick,
            shared,
            backend,
            thermal: ThermalLimiter::new(
                info.limits.peak_force,
                info.limits.continuous_force,
                config.thermal_time_constant,
            ),
            info,
            calibration: config.calibration.isometry(),
            clutch: Clutch::default(),
            clutch_mask: 1 << config.clutch_button,
            ramp: ForceRamp::new(config.ramp_time),
            state: ServoState::default(),
            fault: 0,
            position: Vec3::zeros(),
            velocity: Vec3::zeros(),
            orientation: UnitQuaternion::identity(),
            rendered: Vec3::zeros(),
            faults: DeviceFaults::default(),
            last_dt: 1e-3,
        };
        device.tick.command([0.0; 3]);
        device.read_state();
        device
    }

    /// The connected device's description.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The calibration in use.
    pub fn calibration(&self) -> DeviceToLeg {
        DeviceToLeg::from_isometry(&self.calibration)
    }

    /// Raw device-frame position (m), for landmark calibration.
    pub fn device_position(&self) -> Vec3 {
        Vec3::from(self.state.position)
    }

    /// A handle any thread can use to cut the force at once.
    pub fn emergency_release(&self) -> EmergencyRelease {
        EmergencyRelease(Arc::clone(&self.shared))
    }

    /// The SDK error code that stopped the device (`servo::FAULT_LOST` when
    /// it stopped answering), if any; the force is zero from then on.
    pub fn fault(&self) -> Option<u32> {
        (self.fault != 0).then_some(self.fault)
    }

    /// How many servo iterations the watchdog zeroed a stale command.
    pub fn watchdog_trips(&self) -> u64 {
        self.shared.watchdog_trips.load(Ordering::Relaxed)
    }

    /// Servo iterations since start.
    pub fn servo_ticks(&self) -> u64 {
        self.state.ticks
    }

    /// The current ramp gain in [0, 1].
    pub fn ramp_gain(&self) -> f64 {
        self.ramp.gain()
    }

    fn read_state(&mut self) {
        let state = self.tick.latest();
        if state.fault != 0 && self.fault == 0 {
            self.fault = state.fault;
        }
        if self.fault != 0 {
            // Hold the last good pose; the device is gone.
            self.velocity = Vec3::zeros();
            return;
        }
        self.state = state;
        let calibrated = (self.calibration * Point3::from(Vec3::from(state.position))).coords;
        let pressed = state.buttons & self.clutch_mask != 0;
        if self.clutch.update(pressed, calibrated) {
            self.ramp.restart();
        }
        self.position = self.clutch.probe(calibrated);
        self.velocity = if self.clutch.engaged() {
            Vec3::zeros()
        } else {
            self.calibration.rotation * Vec3::from(state.velocity)
        };
        let r = state.rotation;
        let tool = Matrix3::new(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8]);
        self.orientation = self.calibration.rotation
            * UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&tool));
    }
}

impl HapticDevice for HardwareDevice {
    fn position(&self) -> Vec3 {
        self.position
    }

    fn velocity(&self) -> Vec3 {
        self.velocity
    }

    fn set_force(&mut self, force: Vec3) {
        let limited = limit_force(force, self.info.limits.peak_force, &mut self.faults);
        let mut f = self.thermal.limit(limited, self.last_dt) * self.ramp.gain();
        if self.clutch.engaged() || self.fault != 0 || self.shared.emergency.load(Ordering::Acquire)
        {
            f = Vec3::zeros();
        }
        self.rendered = f;
        let device = self.calibration.rotation.inverse() * f;
        self.tick.command([device.x, device.y, device.z]);
    }

    fn force(&self) -> Vec3 {
        self.rendered
    }

    fn max_force(&self) -> f64 {
        self.info.limits.peak_force
    }

    fn max_stiffness(&self) -> f64 {
        self.info.limits.max_stiffness
    }

    fn sampling_rate(&self) -> f64 {
        self.info.servo_rate
    }

    /// The exchange point with the SDK's servo thread: takes its latest
    /// state (pose, buttons, faults) and advances the ramp by `dt` (s).
    fn advance(&mut self, dt: f64) {
        if !(dt.is_finite() && dt > 0.0) {
            return;
        }
        self.ramp.advance(dt);
        self.last_dt = dt;
        self.read_state();
    }

    fn faults(&self) -> DeviceFaults {
        self.faults
    }

    fn orientation(&self) -> Option<UnitQuaternion<f64>> {
        self.info.orientation_sensed.then_some(self.orientation)
    }

    fn clutched(&self) -> bool {
        self.clutch.engaged()
    }

    fn lost(&self) -> Option<u32> {
        self.fault()
    }
}

impl Drop for HardwareDevice {
    /// Zero force on every exit path: the tick's last command is zero, the
    /// stop flag makes the servo render zero, and the backend releases the device.
    fn drop(&mut self) {
        self.tick.command([0.0; 3]);
        self.shared.stop.store(true, Ordering::Release);
        self.backend.close();
    }
}
