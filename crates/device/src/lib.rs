//! The haptic device side of echothigh (DESIGN §4, ARCHITECTURE "device"):
//!
//! - [`HapticDevice`]: the seam between the haptic loop and a device,
//!   simulated, replayed or real; device forces relate to tissue forces by a
//!   documented [`ForceScale`].
//! - [`SimulatedDevice`]: a PHANToM-class arm (end-effector mass, viscous
//!   friction, force limit) integrated at ≥ 10 kHz inside each call to
//!   [`HapticDevice::advance`], optionally gripped by a [`SimulatedHand`].
//! - [`SimulatedHand`]: a mass-spring-damper impedance whose setpoint follows
//!   an [`ExamScript`] (approach, press to a force or depth, hold, slide,
//!   release, repeat) configured from the scenario's `[exam]` section.
//! - [`ReplayDevice`]: replays a recorded `t,x,y,z` CSV trajectory.
//!
//! Frame: the thigh's (m): `z` along the thigh, `x` lateral, `y` anterior.
//! Nothing here depends on the physics or the haptic loop; everything runs
//! on the caller's clock, so simulations can run faster or slower than real
//! time. `advance` allocates nothing (see `tests/no_alloc.rs`).
//!
//! ```
//! use echothigh_device::{DeviceConfig, ExamConfig, ExamScript, HandConfig,
//!     HapticDevice, SimulatedDevice, SimulatedHand, Vec3};
//! let script = ExamScript::new(ExamConfig::default()).unwrap();
//! let hand = SimulatedHand::scripted(HandConfig::default(), script).unwrap();
//! let mut device = SimulatedDevice::with_hand(DeviceConfig::default(), hand).unwrap();
//! for _ in 0..100 {
//!     // the haptic loop would compute this from the proxy
//!     device.set_force(Vec3::zeros());
//!     device.advance(1e-3);
//! }
//! assert!(device.position().y < 0.092);
//! ```
#![warn(missing_docs)]

mod config;
mod device;
mod error;
mod exam;
mod hand;
mod replay;
mod simulated;

pub use config::{DeviceConfig, DeviceKindSetting, HandConfig};
pub use device::{limit_force, DeviceFaults, ForceScale, HapticDevice};
pub use error::{ConfigError, ReplayError};
pub use exam::{ExamConfig, ExamInput, ExamPhase, ExamScript, ExamStatus, PhaseConfig, MAX_PHASES};
pub use hand::SimulatedHand;
pub use replay::{ReplayDevice, MAX_TRAJECTORY_BYTES};
pub use simulated::SimulatedDevice;

/// A 3-vector in the thigh frame (m, m/s or N by context).
pub type Vec3 = nalgebra::Vector3<f64>;
