//! Real haptic devices for echothigh, behind [`echothigh_device::HapticDevice`].
//!
//! Backends, one module each, their vendor library loaded at run time so that
//! echothigh builds and runs where it is absent:
//! - [`openhaptics`]: 3D Systems Touch / Touch X / PHANTOM Premium through the
//!   OpenHaptics HD API (`libHD`, override with `ECHOTHIGH_HD_LIB`);
//! - [`forcedimension`]: Force Dimension delta / omega / sigma and the Novint
//!   Falcon through the DHD API (`libdhd`, override with `ECHOTHIGH_DHD_LIB`);
//! - [`haply`] (cargo feature `haply`, on by default): Haply Inverse3 with a
//!   VerseGrip through Haply's local Inverse Service over a WebSocket
//!   (override the address with `ECHOTHIGH_HAPLY_URL`).
//!
//! Every backend is a [`HardwareDevice`]: the SDK's servo thread exchanges
//! with the 1 kHz tick through wait-free triple buffers ([`servo`]), so that
//! [`HapticDevice::advance`] (the exchange point) and
//! [`HapticDevice::set_force`] never block, allocate or do I/O. Positions and
//! the tool's orientation are mapped to the leg by a calibrated rigid
//! transform ([`calibration`], with a landmark fit), a held button clutches
//! ([`safety::Clutch`]), and forces pass the safety chain of [`safety`]
//! (per-model limits with sources, continuous-force limiter, 0.5 s ramp-in
//! at start and after each clutch, zero while clutched, faulted or released
//! by [`servo::EmergencyRelease`]), a watchdog zeroes a stale command in the
//! servo thread (and in the DHD firmware), and every exit path (drop,
//! unwinding panic, stall) ends in zero force.
//!
//! **Tested against emulators, not hardware**: `echothigh-device-emu` is a
//! shared library exporting the HD and DHD C functions used here with the
//! vendors' signatures; no physical device was available.
//!
//! Frames: the leg's (m): `z` along the thigh, `x` lateral, `y` anterior.
#![warn(missing_docs)]

pub mod calibration;
pub mod config;
mod error;
pub mod forcedimension;
#[cfg(feature = "haply")]
pub mod haply;
mod hardware;
pub mod landmarks;
pub mod library;
pub mod openhaptics;
pub mod probe;
pub mod safety;
pub mod servo;

pub use calibration::{fit_landmarks, CalibrationError, DeviceToLeg, LandmarkFit};
pub use config::{
    DeviceKind, ForceDimensionConfig, HaplyConfig, HardwareConfig, OpenHapticsConfig,
    UnknownDeviceKind,
};
pub use error::DeviceError;
pub use hardware::{Backend, DeviceInfo, HardwareDevice};
pub use landmarks::{capture_landmarks, CaptureConfig, CaptureError, CaptureEvent, Landmark};
pub use probe::{probe, probe_all, BackendReport};

use echothigh_device::HapticDevice;

/// A 3-vector (m, m/s or N by context).
pub type Vec3 = nalgebra::Vector3<f64>;

/// Opens the first device of a backend as a concrete [`HardwareDevice`]
/// (with its orientation, clutch, emergency release and diagnostics).
pub fn open_hardware(
    kind: DeviceKind,
    config: &HardwareConfig,
) -> Result<HardwareDevice, DeviceError> {
    match kind {
        DeviceKind::Openhaptics => openhaptics::open(config),
        DeviceKind::Forcedimension => forcedimension::open(config),
        #[cfg(feature = "haply")]
        DeviceKind::Haply => haply::open(config),
        #[cfg(not(feature = "haply"))]
        DeviceKind::Haply => Err(DeviceError::NotBuilt {
            backend: kind,
            feature: "haply",
        }),
    }
}

/// Opens the first device of a backend for the haptic loop.
pub fn open_device(
    kind: &DeviceKind,
    config: &HardwareConfig,
) -> Result<Box<dyn HapticDevice + Send>, DeviceError> {
    Ok(Box::new(open_hardware(*kind, config)?))
}
