//! Emulation of the OpenHaptics HD API (`libHD`) for one 3D Systems Touch.
//!
//! Exported with the HD names and C signatures (`hdDefines.h`, `hd.h`,
//! `hdScheduler.h`, OpenHaptics 3.x): units are mm, mm/s and N; the
//! transform is a column-major 4×4 with the translation in mm; errors stack
//! until `hdGetError` pops them. `hdStartScheduler` starts the servo thread,
//! which every 1 ms advances the emulated arm ([`crate::arm`]) under the force
//! applied at the last `hdEndFrame` and then calls each scheduled callback;
//! a callback returning `HD_CALLBACK_DONE` is unscheduled. The force set in a
//! frame stays applied until another frame sets one (the stricter reading for
//! tests of a backend's watchdog). A force above the nominal maximum is not
//! applied: the frame reports `HD_EXCEEDED_MAX_FORCE` and zero is rendered.
//!
//! Emulated model: Touch (3D Systems Touch specifications: 3.3 N peak,
//! 0.88 N continuous, stiffness ≥ 1.02 N/mm on its weakest axis, usable
//! workspace 160 × 120 × 70 mm); apparent tip mass 45 g and 1 N·s/m damping
//! (the PHANToM-class values of `echothigh-device`'s simulated device).

use crate::arm::Arm;
use crate::{lock, now};
use std::ffi::{c_char, c_int, c_ulong, c_void, CStr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Device handle (`HHD`).
pub type Hhd = u32;
/// `HDenum` / `HDerror`.
pub type HdEnum = u32;
/// `HDSchedulerHandle`.
pub type HdSchedulerHandle = c_ulong;
/// `HDSchedulerCallback`: `HDCallbackCode (*)(void *pUserData)`.
pub type HdSchedulerCallback = extern "C" fn(*mut c_void) -> u32;

/// `HDErrorInfo`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HdErrorInfo {
    /// The HD_ error code.
    pub error_code: HdEnum,
    /// The device's internal error code.
    pub internal_error_code: c_int,
    /// The device current when the error occurred.
    pub hhd: Hhd,
}

// Constants of hdDefines.h / hdScheduler.h used here.
const HD_SUCCESS: u32 = 0x0000;
const HD_INVALID_ENUM: u32 = 0x0100;
const HD_INVALID_VALUE: u32 = 0x0101;
const HD_BAD_HANDLE: u32 = 0x0104;
const HD_EXCEEDED_MAX_FORCE: u32 = 0x0201;
const HD_DEVICE_ALREADY_INITIATED: u32 = 0x0301;
const HD_COMM_ERROR: u32 = 0x0302;
const HD_COMM_CONFIG_ERROR: u32 = 0x0303;
const HD_ILLEGAL_BEGIN: u32 = 0x0400;
const HD_ILLEGAL_END: u32 = 0x0401;
const HD_CURRENT_BUTTONS: u32 = 0x2000;
const HD_CURRENT_POSITION: u32 = 0x2050;
const HD_CURRENT_VELOCITY: u32 = 0x2051;
const HD_CURRENT_TRANSFORM: u32 = 0x2052;
const HD_DEVICE_MODEL_TYPE: u32 = 0x2501;
const HD_DEVICE_VENDOR: u32 = 0x2503;
const HD_DEVICE_SERIAL_NUMBER: u32 = 0x2504;
const HD_MAX_WORKSPACE_DIMENSIONS: u32 = 0x2550;
const HD_USABLE_WORKSPACE_DIMENSIONS: u32 = 0x2551;
const HD_INPUT_DOF: u32 = 0x2553;
const HD_OUTPUT_DOF: u32 = 0x2554;
const HD_UPDATE_RATE: u32 = 0x2600;
const HD_NOMINAL_MAX_STIFFNESS: u32 = 0x2602;
const HD_NOMINAL_MAX_FORCE: u32 = 0x2603;
const HD_NOMINAL_MAX_CONTINUOUS_FORCE: u32 = 0x2604;
const HD_CURRENT_FORCE: u32 = 0x2700;
const HD_FORCE_OUTPUT: u32 = 0x4000;
const HD_CALLBACK_DONE: u32 = 0;
const HD_INVALID_HANDLE: u32 = 0xFFFF_FFFF;

const HANDLE: Hhd = 1;
const MAX_FORCE: f64 = 3.3;
const CONTINUOUS_FORCE: f64 = 0.88;
const STIFFNESS_N_PER_MM: f64 = 1.02;
/// Usable workspace (mm): min x, y, z, max x, y, z, centred on the home position.
const WORKSPACE: [f64; 6] = [-80.0, -60.0, -35.0, 80.0, 60.0, 35.0];

#[derive(Clone, Copy)]
struct Scheduled {
    handle: HdSchedulerHandle,
    callback: HdSchedulerCallback,
    user: *mut c_void,
}

// SAFETY: the user data pointer is only handed back to the callback the
// caller scheduled, on the servo thread, as libHD does.
unsafe impl Send for Scheduled {}

struct State {
    present: bool,
    unplugged: bool,
    initialized: bool,
    force_output: bool,
    in_frame: bool,
    arm: Arm,
    rotation: [f64; 9],
    buttons: c_int,
    frame_force: [f64; 3],
    commanded: [f64; 3],
    commanded_at: f64,
    max_applied: f64,
    errors: Vec<HdErrorInfo>,
    callbacks: Vec<Scheduled>,
    next_handle: HdSchedulerHandle,
}

const IDENTITY: [f64; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

impl State {
    const fn new() -> Self {
        State {
            present: true,
            unplugged: false,
            initialized: false,
            force_output: false,
            in_frame: false,
            arm: Arm::new(0.045, 1.0),
            rotation: IDENTITY,
            buttons: 0,
            frame_force: [0.0; 3],
            commanded: [0.0; 3],
            commanded_at: 0.0,
            max_applied: 0.0,
            errors: Vec::new(),
            callbacks: Vec::new(),
            next_handle: 1,
        }
    }

    fn error(&mut self, code: u32) {
        self.errors.push(HdErrorInfo {
            error_code: code,
            internal_error_code: 0,
            hhd: HANDLE,
        });
    }
}

static STATE: Mutex<State> = Mutex::new(State::new());
static SCHEDULER: Mutex<Option<(Arc<AtomicBool>, JoinHandle<()>)>> = Mutex::new(None);

/// `HHD hdInitDevice(HDstring pConfigName)`: `HD_DEFAULT_DEVICE` (NULL) or any name.
#[no_mangle]
pub extern "C" fn hdInitDevice(_config_name: *const c_char) -> Hhd {
    let mut s = lock(&STATE);
    if !s.present {
        s.error(HD_COMM_CONFIG_ERROR);
        return HD_INVALID_HANDLE;
    }
    if s.initialized {
        s.error(HD_DEVICE_ALREADY_INITIATED);
        return HD_INVALID_HANDLE;
    }
    s.initialized = true;
    HANDLE
}

/// `void hdMakeCurrentDevice(HHD hHD)`.
#[no_mangle]
pub extern "C" fn hdMakeCurrentDevice(hhd: Hhd) {
    let mut s = lock(&STATE);
    if hhd != HANDLE || !s.initialized {
        s.error(HD_BAD_HANDLE);
    }
}

/// `void hdDisableDevice(HHD hHD)`: releases the device; the motors go limp.
#[no_mangle]
pub extern "C" fn hdDisableDevice(hhd: Hhd) {
    let mut s = lock(&STATE);
    if hhd != HANDLE || !s.initialized {
        s.error(HD_BAD_HANDLE);
        return;
    }
    s.initialized = false;
    s.force_output = false;
    s.arm.motor = [0.0; 3];
}

/// `void hdEnable(HDenum cap)`.
#[no_mangle]
pub extern "C" fn hdEnable(cap: HdEnum) {
    if cap == HD_FORCE_OUTPUT {
        lock(&STATE).force_output = true;
    }
}

/// `void hdDisable(HDenum cap)`: disabling force output zeroes the motors.
#[no_mangle]
pub extern "C" fn hdDisable(cap: HdEnum) {
    if cap == HD_FORCE_OUTPUT {
        let mut s = lock(&STATE);
        s.force_output = false;
        s.arm.motor = [0.0; 3];
    }
}

/// `void hdBeginFrame(HHD hHD)`.
#[no_mangle]
pub extern "C" fn hdBeginFrame(hhd: Hhd) {
    let mut s = lock(&STATE);
    if hhd != HANDLE || !s.initialized {
        s.error(HD_BAD_HANDLE);
    } else if s.in_frame {
        s.error(HD_ILLEGAL_BEGIN);
    } else if s.unplugged {
        s.error(HD_COMM_ERROR);
    } else {
        s.in_frame = true;
        s.frame_force = s.arm.motor;
    }
}

/// `void hdEndFrame(HHD hHD)`: the frame's force goes to the motors.
#[no_mangle]
pub extern "C" fn hdEndFrame(hhd: Hhd) {
    let mut s = lock(&STATE);
    if hhd != HANDLE || !s.in_frame {
        s.error(HD_ILLEGAL_END);
        return;
    }
    s.in_frame = false;
    if s.unplugged {
        s.error(HD_COMM_ERROR);
        return;
    }
    let f = s.frame_force;
    let norm = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    if !s.force_output {
        s.arm.motor = [0.0; 3];
    } else if norm.is_nan() || norm > MAX_FORCE {
        s.error(HD_EXCEEDED_MAX_FORCE);
        s.arm.motor = [0.0; 3];
    } else {
        s.arm.motor = f;
        s.max_applied = s.max_applied.max(norm);
    }
}

/// `void hdGetDoublev(HDenum pname, HDdouble *params)`.
///
/// # Safety
/// `params` must point to as many doubles as `pname` returns (3, 6 or 16).
#[no_mangle]
pub unsafe extern "C" fn hdGetDoublev(pname: HdEnum, params: *mut f64) {
    let mut s = lock(&STATE);
    if params.is_null() {
        s.error(HD_INVALID_VALUE);
        return;
    }
    let a = s.arm;
    let mm = |v: [f64; 3]| [v[0] * 1e3, v[1] * 1e3, v[2] * 1e3];
    let mut out = [0.0; 16];
    let n = match pname {
        HD_CURRENT_POSITION => {
            out[..3].copy_from_slice(&mm(a.position));
            3
        }
        HD_CURRENT_VELOCITY => {
            out[..3].copy_from_slice(&mm(a.velocity));
            3
        }
        HD_CURRENT_TRANSFORM => {
            // Column-major: column j holds R[.., j]; the last column the translation.
            let r = s.rotation;
            for j in 0..3 {
                for i in 0..3 {
                    out[4 * j + i] = r[3 * i + j];
                }
            }
            out[12..15].copy_from_slice(&mm(a.position));
            out[15] = 1.0;
            16
        }
        HD_CURRENT_FORCE => {
            out[..3].copy_from_slice(&s.frame_force);
            3
        }
        HD_NOMINAL_MAX_FORCE => {
            out[0] = MAX_FORCE;
            1
        }
        HD_NOMINAL_MAX_CONTINUOUS_FORCE => {
            out[0] = CONTINUOUS_FORCE;
            1
        }
        HD_NOMINAL_MAX_STIFFNESS => {
            out[0] = STIFFNESS_N_PER_MM;
            1
        }
        HD_USABLE_WORKSPACE_DIMENSIONS | HD_MAX_WORKSPACE_DIMENSIONS => {
            out[..6].copy_from_slice(&WORKSPACE);
            6
        }
        _ => {
            s.error(HD_INVALID_ENUM);
            return;
        }
    };
    // SAFETY: the caller provides room for `n` doubles for this `pname`.
    unsafe { std::ptr::copy_nonoverlapping(out.as_ptr(), params, n) };
}

/// `void hdGetIntegerv(HDenum pname, HDint *params)`.
///
/// # Safety
/// `params` must point to at least one `int`.
#[no_mangle]
pub unsafe extern "C" fn hdGetIntegerv(pname: HdEnum, params: *mut c_int) {
    let mut s = lock(&STATE);
    let value = match pname {
        HD_CURRENT_BUTTONS => s.buttons,
        HD_UPDATE_RATE => 1000,
        HD_INPUT_DOF => 6,
        HD_OUTPUT_DOF => 3,
        _ => {
            s.error(HD_INVALID_ENUM);
            return;
        }
    };
    if params.is_null() {
        s.error(HD_INVALID_VALUE);
        return;
    }
    // SAFETY: non-null, the caller provides one int.
    unsafe { *params = value };
}

/// `HDstring hdGetString(HDenum pname)`.
#[no_mangle]
pub extern "C" fn hdGetString(pname: HdEnum) -> *const c_char {
    let text: &'static CStr = match pname {
        HD_DEVICE_MODEL_TYPE => c"Touch",
        HD_DEVICE_VENDOR => c"echothigh HD emulator",
        HD_DEVICE_SERIAL_NUMBER => c"EMU-00001",
        _ => {
            lock(&STATE).error(HD_INVALID_ENUM);
            return std::ptr::null();
        }
    };
    text.as_ptr()
}

/// `void hdSetDoublev(HDenum pname, const HDdouble *params)`: `HD_CURRENT_FORCE` (N).
///
/// # Safety
/// `params` must point to three doubles.
#[no_mangle]
pub unsafe extern "C" fn hdSetDoublev(pname: HdEnum, params: *const f64) {
    let mut s = lock(&STATE);
    if pname != HD_CURRENT_FORCE {
        s.error(HD_INVALID_ENUM);
        return;
    }
    if params.is_null() || !s.in_frame {
        s.error(HD_INVALID_VALUE);
        return;
    }
    // SAFETY: the caller provides three doubles.
    let f = unsafe { [*params, *params.add(1), *params.add(2)] };
    s.frame_force = f;
    s.commanded = f;
    s.commanded_at = now();
}

/// `HDErrorInfo hdGetError(void)`: pops the most recent error.
#[no_mangle]
pub extern "C" fn hdGetError() -> HdErrorInfo {
    lock(&STATE).errors.pop().unwrap_or(HdErrorInfo {
        error_code: HD_SUCCESS,
        internal_error_code: 0,
        hhd: HANDLE,
    })
}

/// `HDstring hdGetErrorString(HDerror errorCode)`.
#[no_mangle]
pub extern "C" fn hdGetErrorString(code: HdEnum) -> *const c_char {
    let text: &'static CStr = match code {
        HD_SUCCESS => c"No error",
        HD_INVALID_ENUM => c"Invalid enumerant",
        HD_INVALID_VALUE => c"Invalid value",
        HD_BAD_HANDLE => c"Invalid device handle",
        HD_EXCEEDED_MAX_FORCE => c"Exceeded max force",
        HD_DEVICE_ALREADY_INITIATED => c"Device already initiated",
        HD_COMM_ERROR => c"Communication error",
        HD_COMM_CONFIG_ERROR => c"Communication configuration error (no device)",
        HD_ILLEGAL_BEGIN => c"Illegal begin frame",
        HD_ILLEGAL_END => c"Illegal end frame",
        _ => c"Unknown error",
    };
    text.as_ptr()
}

/// `HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback, void *pUserData, HDushort nPriority)`.
#[no_mangle]
pub extern "C" fn hdScheduleAsynchronous(
    callback: HdSchedulerCallback,
    user: *mut c_void,
    _priority: u16,
) -> HdSchedulerHandle {
    let mut s = lock(&STATE);
    let handle = s.next_handle;
    s.next_handle += 1;
    s.callbacks.push(Scheduled {
        handle,
        callback,
        user,
    });
    handle
}

/// `void hdUnschedule(HDSchedulerHandle)`.
#[no_mangle]
pub extern "C" fn hdUnschedule(handle: HdSchedulerHandle) {
    lock(&STATE).callbacks.retain(|c| c.handle != handle);
}

/// `void hdStartScheduler(void)`: starts the 1 kHz servo thread.
#[no_mangle]
pub extern "C" fn hdStartScheduler() {
    let mut sched = lock(&SCHEDULER);
    if sched.is_some() {
        return;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let spawned = std::thread::Builder::new()
        .name("hd-emu-servo".into())
        .spawn(move || servo_loop(&flag));
    match spawned {
        Ok(handle) => *sched = Some((stop, handle)),
        Err(_) => lock(&STATE).error(HD_COMM_ERROR),
    }
}

/// `void hdStopScheduler(void)`: stops and joins the servo thread.
#[no_mangle]
pub extern "C" fn hdStopScheduler() {
    let taken = lock(&SCHEDULER).take();
    if let Some((stop, handle)) = taken {
        stop.store(true, Ordering::Release);
        let _ = handle.join();
    }
}

fn servo_loop(stop: &AtomicBool) {
    let period = Duration::from_millis(1);
    let mut next = Instant::now();
    let mut due: Vec<Scheduled> = Vec::with_capacity(16);
    while !stop.load(Ordering::Acquire) {
        {
            let mut s = lock(&STATE);
            if s.unplugged || !s.force_output {
                s.arm.motor = [0.0; 3];
            }
            s.arm.advance(period.as_secs_f64());
            due.clear();
            due.extend(s.callbacks.iter().copied());
        }
        for c in &due {
            if (c.callback)(c.user) == HD_CALLBACK_DONE {
                hdUnschedule(c.handle);
            }
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

// ---- controls for tests (not part of the HD API) ----

/// Resets the emulated Touch to rest at its home position, present, with no
/// hand, buttons or errors, and nothing scheduled. Call with the scheduler stopped.
#[no_mangle]
pub extern "C" fn echothigh_emu_hd_reset() {
    *lock(&STATE) = State::new();
}

/// Makes the next `hdInitDevice` find (1) or not find (0) a device.
#[no_mangle]
pub extern "C" fn echothigh_emu_hd_set_present(present: c_int) {
    lock(&STATE).present = present != 0;
}

/// Drops the device (USB unplugged): frames fail with `HD_COMM_ERROR`, the motors stop.
#[no_mangle]
pub extern "C" fn echothigh_emu_hd_unplug() {
    let mut s = lock(&STATE);
    s.unplugged = true;
    s.arm.motor = [0.0; 3];
}

/// The emulated hand grips the stylus and pulls it to `target` (mm, device
/// frame) with stiffness `k` (N/m) and damping `c` (N·s/m); a null target releases it.
///
/// # Safety
/// `target` is null or points to three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_hd_set_hand(target: *const f64, k: f64, c: f64) {
    let hand = if target.is_null() {
        None
    } else {
        // SAFETY: non-null, three doubles.
        let t = unsafe { [*target, *target.add(1), *target.add(2)] };
        Some(([t[0] * 1e-3, t[1] * 1e-3, t[2] * 1e-3], k, c))
    };
    lock(&STATE).arm.hand = hand;
}

/// Sets the stylus (gimbal) rotation, row-major 3×3, device ← stylus.
///
/// # Safety
/// `r` points to nine doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_hd_set_rotation(r: *const f64) {
    if r.is_null() {
        return;
    }
    let mut m = [0.0; 9];
    // SAFETY: nine doubles.
    unsafe { std::ptr::copy_nonoverlapping(r, m.as_mut_ptr(), 9) };
    lock(&STATE).rotation = m;
}

/// Sets the stylus button mask (`HD_DEVICE_BUTTON_1` = 1, `_2` = 2).
#[no_mangle]
pub extern "C" fn echothigh_emu_hd_set_buttons(mask: c_int) {
    lock(&STATE).buttons = mask;
}

/// Writes the last force commanded with `hdSetDoublev(HD_CURRENT_FORCE)` (N)
/// into `force` and returns the emulator time (s) it was commanded at.
///
/// # Safety
/// `force` is null or points to room for three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_hd_last_force(force: *mut f64) -> f64 {
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
/// `force` points to room for three doubles.
#[no_mangle]
pub unsafe extern "C" fn echothigh_emu_hd_applied_force(force: *mut f64) {
    let s = lock(&STATE);
    if !force.is_null() {
        // SAFETY: room for three doubles.
        unsafe { std::ptr::copy_nonoverlapping(s.arm.motor.as_ptr(), force, 3) };
    }
}

/// Largest force magnitude applied to the motors since reset (N).
#[no_mangle]
pub extern "C" fn echothigh_emu_hd_max_applied_force() -> f64 {
    lock(&STATE).max_applied
}

/// The emulators' clock (s).
#[no_mangle]
pub extern "C" fn echothigh_emu_now() -> f64 {
    now()
}
