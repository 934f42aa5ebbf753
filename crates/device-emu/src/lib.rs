//! Emulators of two haptic-device C APIs, built as one shared library
//! (`libechothigh_device_emu.so`) that echothigh's device backends load at
//! run time in place of the vendor's library:
//!
//! - [`hd`]: the OpenHaptics HD API (`libHD`) of the 3D Systems Touch /
//!   PHANToM family: device init, the servo scheduler thread that calls the
//!   scheduled callbacks at 1 kHz, frames, parameters in mm and N, errors.
//! - [`dhd`]: the Force Dimension DHD API (`libdhd`): open/close, position in
//!   m, orientation frame, force, the firmware's force watchdog.
//! - [`inverse`] (feature `haply`): Haply's Inverse Service, a local
//!   WebSocket server in the `haply` crate's message types, used in-process
//!   by the tests (a Rust API rather than C functions).
//!
//! **No hardware is emulated faithfully beyond its interface**: each device is
//! a point mass with viscous damping ([`arm::Arm`]) moved by the commanded
//! motor force and by an optional emulated hand (a spring-damper pulling the
//! end-effector to a target), integrated at 10 kHz. The emulators record the
//! last force the backend commanded and the time it was commanded, the largest
//! force applied, and they can drop the device mid-run. Those controls are
//! extra C functions prefixed `echothigh_emu_` that no vendor library has;
//! the backends never call them, the tests do.
//!
//! Signatures and constants follow the vendors' headers (`hdDefines.h`,
//! `hd.h`, `hdScheduler.h`; `dhdc.h` of the Force Dimension SDK 3.x). Every
//! exported function takes the C ABI and never unwinds into C: they hold no
//! code that can panic on caller input (pointers are checked for null).
#![warn(missing_docs)]

pub mod arm;
pub mod dhd;
pub mod hd;
#[cfg(feature = "haply")]
pub mod inverse;

use std::sync::OnceLock;
use std::time::Instant;

/// Seconds since the library's first use (the emulators' clock).
pub fn now() -> f64 {
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Locks a mutex, recovering the data if a panicking thread poisoned it (the
/// emulators' state stays meaningful: every update is a plain assignment).
fn lock<T>(m: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}
