//! Emulation of the Force Dimension DHD API (`libdhd`) for one omega.6.
//!
//! Exported with the DHD names and C signatures (`dhdc.h`, SDK 3.x; the
//! C++ default arguments are passed explicitly through the C ABI, `ID = -1`
//! meaning the default device): positions in m, forces in N, the orientation
//! frame a row-major 3×3, return 0 on success and −1 on error with the code
//! behind `dhdErrorGetLast` / `dhdErrorGetLastStr`. A firmware thread
//! advances the emulated arm ([`crate::arm`]) at 4 kHz under the last force
//! set with `dhdSetForce` while forces are enabled; the **watchdog** of
//! `dhdSetWatchdog(val)` (multiples of 125 µs, 0 = off) zeroes the force
//! when no new force command arrived within its duration, as the firmware
//! does, until the next command.
//!
//! Emulated model: omega.6 (`DHD_DEVICE_OMEGA33`; Force Dimension omega.6
//! specifications: 12 N continuous translational force, workspace
//! ⌀160 × 110 mm, closed-loop stiffness 14.5 N/mm); apparent mass 0.2 kg and
//! 2 N·s/m damping (the order of a parallel-kinematics desktop device).

use crate::arm::Arm;
use crate::{lock, now};
use std::ffi::{c_char, c_int, c_uchar, c_uint, CStr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const DHD_DEVICE_OMEGA33: c_int = 34;
const DHD_NO_ERROR: c_int = 0;
const DHD_ERROR_COM: c_int = 2;
const DHD_ERROR_NO_DEVICE_FOUND: c_int = 5;
const DHD_ERROR_NOT_AVAILABLE: c_int = 6;
const DHD_ERROR_INVALID: c_int = 29;
const MAX_FORCE: f64 = 12.0;
const WATCHDOG_TICK: f64 = 125e-6;

struct State {
    present: bool,
    open: bool,
    unplugged: bool,
    force_enabled: bool,
    arm: Arm,
    rotation: [f64; 9],
    buttons: c_uint,
    commanded: [f64; 3],
    commanded_at: f64,
    watchdog: c_uchar,
    watchdog_tripped: u64,
    max_applied: f64,
    last_error: c_int,
}

impl State {
    const fn new() -> Self {
        State {
            present: true,
            open: false,
            unplugged: false,
            force_enabled: false,
            arm: Arm::new(0.2, 2.0),
            rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            buttons: 0,
            commanded: [0.0; 3],
            commanded_at: 0.0,
            watchdog: 0,
            watchdog_tripped: 0,
            max_applied: 0.0,
            last_error: DHD_NO_ERROR,
        }
    }

    /// Fails with `code` unless the device is open and plugged in.
    fn usable(&mut self) -> bool {
        let code = if !self.open {
            DHD_ERROR_NO_DEVICE_FOUND
        } else if self.unplugged {
            DHD_ERROR_COM
        } else {
            return true;
        };
        self.last_error = code;
        false
    }
}

static STATE: Mutex<State> = Mutex::new(State::new());
static FIRMWARE: Mutex<Option<(Arc<AtomicBool>, JoinHandle<()>)>> = Mutex::new(None);

fn firmware_loop(stop: &AtomicBool) {
    let period = Duration::from_micros(250);
    let mut next = Instant::now();
    while !stop.load(Ordering::Acquire) {
        {
            let mut s = lock(&STATE);
            let t = now();
            let expired =
                s.watchdog > 0 && t - s.commanded_at > f64::from(s.watchdog) * WATCHDOG_TICK;
            if expired && s.arm.motor != [0.0; 3] {
                s.watchdog_tripped += 1;
            }
            s.arm.motor = if s.force_enabled && !s.unplugged && !expired {
                s.commanded
            } else {
                [0.0; 3]
            };
            let m = s.arm.motor;
            s.max_applied = s
                .max_applied
                .max((m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt());
            s.arm.advance(period.as_secs_f64());
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
}

fn write3(out: [*mut f64; 3], v: [f64; 3]) -> c_int {
    if out.iter().any(|p| p.is_null()) {
        lock(&STATE).last_error = DHD_ERROR_INVALID;
        return -1;
    }
    for (p, x) in out.into_iter().zip(v) {
        // SAFETY: non-null; the caller passes pointers to doubles.
        unsafe { *p = x };
    }
    0
}

/// `int dhdGetDeviceCount()`.
#[no_mangle]
pub extern "C" fn dhdGetDeviceCount() -> c_int {
    c_int::from(lock(&STATE).present)
}

/// `int dhdOpen()`: returns the device ID (0) or −1.
#[no_mangle]
pub extern "C" fn dhdOpen() -> c_int {
    {
        let mut s = lock(&STATE);
        if !s.present || s.open {
            s.last_error = DHD_ERROR_NO_DEVICE_FOUND;
            return -1;
        }
        s.open = true;
        s.force_enabled = false;
    }
    let mut fw = lock(&FIRMWARE);
    if fw.is_none() {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        match std::thread::Builder::new()
            .name("dhd-emu-firmware".into())
            .spawn(move || firmware_loop(&flag))
        {
            Ok(h) => *fw = Some((stop, h)),
            Err(_) => {
                let mut s = lock(&STATE);
                s.open = false;
                s.last_error = DHD_ERROR_NOT_AVAILABLE;
                return -1;
            }
        }
    }
    0
}

/// `int dhdClose(char ID = -1)`: zero force, stop the firmware thread.
#[no_mangle]
pub extern "C" fn dhdClose(_id: c_char) -> c_int {
    {
        let mut s = lock(&STATE);
        if !s.open {
            s.last_error = DHD_ERROR_NO_DEVICE_FOUND;
            return -1;
        }
        s.open = false;
        s.force_enabled = false;
        s.arm.motor = [0.0; 3];
    }
    if let Some((stop, h)) = lock(&FIRMWARE).take() {
        stop.store(true, Ordering::Release);
        let _ = h.join();
    }
    0
}

/// `int dhdStop(char ID = -1)`: disables forces.
#[no_mangle]
pub extern "C" fn dhdStop(_id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    s.force_enabled = false;
    0
}

/// `int dhdGetSystemType(char ID = -1)`.
#[no_mangle]
pub extern "C" fn dhdGetSystemType(_id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    DHD_DEVICE_OMEGA33
}

/// `const char* dhdGetSystemName(char ID = -1)`.
#[no_mangle]
pub extern "C" fn dhdGetSystemName(_id: c_char) -> *const c_char {
    c"omega.6".as_ptr()
}

/// `int dhdEnableForce(uchar val, char ID = -1)`.
#[no_mangle]
pub extern "C" fn dhdEnableForce(val: c_uchar, _id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    s.force_enabled = val != 0;
    0
}

/// `int dhdSetWatchdog(unsigned char val, char ID = -1)`: duration in multiples of 125 µs.
#[no_mangle]
pub extern "C" fn dhdSetWatchdog(val: c_uchar, _id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    s.watchdog = val;
    0
}

/// `int dhdGetPosition(double *px, double *py, double *pz, char ID = -1)` (m).
#[no_mangle]
pub extern "C" fn dhdGetPosition(px: *mut f64, py: *mut f64, pz: *mut f64, _id: c_char) -> c_int {
    let p = {
        let mut s = lock(&STATE);
        if !s.usable() {
            return -1;
        }
        s.arm.position
    };
    write3([px, py, pz], p)
}

/// `int dhdGetLinearVelocity(double *vx, double *vy, double *vz, char ID = -1)` (m/s).
#[no_mangle]
pub extern "C" fn dhdGetLinearVelocity(
    vx: *mut f64,
    vy: *mut f64,
    vz: *mut f64,
    _id: c_char,
) -> c_int {
    let v = {
        let mut s = lock(&STATE);
        if !s.usable() {
            return -1;
        }
        s.arm.velocity
    };
    write3([vx, vy, vz], v)
}

/// `int dhdGetOrientationFrame(double matrix[3][3], char ID = -1)`: row-major, device ← handle.
///
/// # Safety
/// `matrix` is null or points to nine doubles.
#[no_mangle]
pub unsafe extern "C" fn dhdGetOrientationFrame(matrix: *mut f64, _id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    if matrix.is_null() {
        s.last_error = DHD_ERROR_INVALID;
        return -1;
    }
    // SAFETY: non-null, nine doubles.
    unsafe { std::ptr::copy_nonoverlapping(s.rotation.as_ptr(), matrix, 9) };
    0
}

/// `uint dhdGetButtonMask(char ID = -1)`.
#[no_mangle]
pub extern "C" fn dhdGetButtonMask(_id: c_char) -> c_uint {
    lock(&STATE).buttons
}

/// `int dhdSetForce(double fx, double fy, double fz, char ID = -1)` (N). A
/// force above the device's 12 N is refused (−1), nothing applied.
#[no_mangle]
pub extern "C" fn dhdSetForce(fx: f64, fy: f64, fz: f64, _id: c_char) -> c_int {
    let mut s = lock(&STATE);
    if !s.usable() {
        return -1;
    }
    let norm = (fx * fx + fy * fy + fz * fz).sqrt();
    if norm.is_nan() || norm > MAX_FORCE {
        s.last_error = DHD_ERROR_INVALID;
        s.commanded = [0.0; 3];
        return -1;
    }
    s.commanded = [fx, fy, fz];
    s.commanded_at = now();
    0
}

/// `int dhdErrorGetLast()`.
#[no_mangle]
pub extern "C" fn dhdErrorGetLast() -> c_int {
    lock(&STATE).last_error
}

/// `const char* dhdErrorGetLastStr()`.
#[no_mangle]
pub extern "C" fn dhdErrorGetLastStr() -> *const c_char {
    let text: &'static CStr = match lock(&STATE).last_error {
        DHD_NO_ERROR => c"no error",
        DHD_ERROR_COM => c"communication error between the host and the haptic device",
        DHD_ERROR_NO_DEVICE_FOUND => c"no compatible Force Dimension device found",
        DHD_ERROR_NOT_AVAILABLE => c"feature not available",
        DHD_ERROR_INVALID => c"invalid argument",
        _ => c"undocumented error",
    };
    text.as_ptr()
}

// ---- controls for tests (not part of the DHD API) ----

/// Resets the emulated omega.6: present, closed, at rest at the origin.
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_reset() {
    *lock(&STATE) = State::new();
}

/// Makes the next `dhdOpen` find (1) or not find (0) a device.
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_set_present(present: c_int) {
    lock(&STATE).present = present != 0;
}

/// Drops the device (USB unplugged): calls fail with a communication error, the motors stop.
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_unplug() {
    let mut s = lock(&STATE);
    s.unplugged = true;
    s.arm.motor = [0.0; 3];
}

/// The emulated hand pulls the handle to `target` (m, device frame) with
/// stiffness `k` (N/m) and damping `c` (N·s/m); null releases it.
///
/// # Safety
/// `target` is null or points to three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_dhd_set_hand(target: *const f64, k: f64, c: f64) {
    let hand = if target.is_null() {
        None
    } else {
        // SAFETY: non-null, three doubles.
        Some((unsafe { [*target, *target.add(1), *target.add(2)] }, k, c))
    };
    lock(&STATE).arm.hand = hand;
}

/// Sets the handle's orientation frame (row-major 3×3, device ← handle).
///
/// # Safety
/// `r` is null or points to nine doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_dhd_set_rotation(r: *const f64) {
    if r.is_null() {
        return;
    }
    let mut m = [0.0; 9];
    // SAFETY: nine doubles.
    unsafe { std::ptr::copy_nonoverlapping(r, m.as_mut_ptr(), 9) };
    lock(&STATE).rotation = m;
}

/// Sets the button mask (bit 0 = the first button).
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_set_buttons(mask: c_uint) {
    lock(&STATE).buttons = mask;
}

/// Writes the last force commanded with `dhdSetForce` (N) into `force`;
/// returns the emulator time (s) it was commanded at.
///
/// # Safety
/// `force` is null or has room for three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_dhd_last_force(force: *mut f64) -> f64 {
    let s = lock(&STATE);
    if !force.is_null() {
        // SAFETY: room for three doubles.
        unsafe { std::ptr::copy_nonoverlapping(s.commanded.as_ptr(), force, 3) };
    }
    s.commanded_at
}

/// Writes the force the motors apply now (N) into `force`.
///
/// # Safety
/// `force` is null or has room for three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_dhd_applied_force(force: *mut f64) {
    let s = lock(&STATE);
    if !force.is_null() {
        // SAFETY: room for three doubles.
        unsafe { std::ptr::copy_nonoverlapping(s.arm.motor.as_ptr(), force, 3) };
    }
}

/// Largest force magnitude applied since reset (N).
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_max_applied_force() -> f64 {
    lock(&STATE).max_applied
}

/// How many times the watchdog cut a non-zero force since reset.
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_watchdog_trips() -> u64 {
    lock(&STATE).watchdog_tripped
}

/// The watchdog duration set with `dhdSetWatchdog` (multiples of 125 µs; 0 = off).
#[no_mangle]
pub extern "C" fn echothigh_emu_dhd_watchdog() -> c_uchar {
    lock(&STATE).watchdog
}
