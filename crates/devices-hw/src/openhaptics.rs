//! OpenHaptics HD backend: 3D Systems Touch / Touch X / PHANTOM Premium.
//!
//! `libHD` is loaded at run time (`ECHOTHIGH_HD_LIB` overrides the path).
//! HD's threading rule: device state is read and forces written only inside
//! a frame (`hdBeginFrame` … `hdEndFrame`) on HD's own servo thread, from a
//! callback scheduled with `hdScheduleAsynchronous`. Our callback reads the
//! pose and buttons, publishes them to the tick and applies the tick's
//! latest force through the watchdog ([`crate::servo`]); it never blocks or
//! allocates. Units at the HD boundary: mm, mm/s, N, N/mm; converted to SI.
//! Frames: HD's (x right, y up, z towards the user), mapped to the leg by
//! the calibration. Signatures and constants: `hd.h`, `hdDefines.h`,
//! `hdScheduler.h` (OpenHaptics 3.x).

use crate::config::HardwareConfig;
use crate::hardware::{Backend, DeviceInfo, HardwareDevice};
use crate::library::LibrarySpec;
use crate::safety::ModelLimits;
use crate::servo::{exchange, wait_for_zero_frames, ServoSide, ServoState, Shared, FAULT_LOST};
use crate::{DeviceError, DeviceKind};
use std::ffi::{c_char, c_int, c_ulong, c_void, CStr, CString};
use std::sync::atomic::Ordering;
use std::sync::Arc;

const HD_SUCCESS: u32 = 0;
const HD_CURRENT_BUTTONS: u32 = 0x2000;
const HD_CURRENT_POSITION: u32 = 0x2050;
const HD_CURRENT_VELOCITY: u32 = 0x2051;
const HD_CURRENT_TRANSFORM: u32 = 0x2052;
const HD_DEVICE_MODEL_TYPE: u32 = 0x2501;
const HD_USABLE_WORKSPACE_DIMENSIONS: u32 = 0x2551;
const HD_INPUT_DOF: u32 = 0x2553;
const HD_NOMINAL_MAX_STIFFNESS: u32 = 0x2602;
const HD_NOMINAL_MAX_FORCE: u32 = 0x2603;
const HD_NOMINAL_MAX_CONTINUOUS_FORCE: u32 = 0x2604;
const HD_CURRENT_FORCE: u32 = 0x2700;
const HD_FORCE_OUTPUT: u32 = 0x4000;
const HD_MAX_FORCE_CLAMPING: u32 = 0x4001;
const HD_CALLBACK_CONTINUE: u32 = 1;
const HD_INVALID_HANDLE: u32 = 0xFFFF_FFFF;
const HD_MAX_SCHEDULER_PRIORITY: u16 = u16::MAX;

/// `HDErrorInfo` (hdDefines.h).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
struct HdErrorInfo {
    error_code: u32,
    internal_error_code: c_int,
    hhd: u32,
}

type Callback = extern "C" fn(*mut c_void) -> u32;

/// The HD functions echothigh calls, copied out of the loaded library.
struct HdApi {
    init_device: unsafe extern "C" fn(*const c_char) -> u32,
    disable_device: unsafe extern "C" fn(u32),
    make_current_device: unsafe extern "C" fn(u32),
    enable: unsafe extern "C" fn(u32),
    disable: unsafe extern "C" fn(u32),
    begin_frame: unsafe extern "C" fn(u32),
    end_frame: unsafe extern "C" fn(u32),
    get_doublev: unsafe extern "C" fn(u32, *mut f64),
    get_integerv: unsafe extern "C" fn(u32, *mut c_int),
    get_string: unsafe extern "C" fn(u32) -> *const c_char,
    set_doublev: unsafe extern "C" fn(u32, *const f64),
    get_error: unsafe extern "C" fn() -> HdErrorInfo,
    get_error_string: unsafe extern "C" fn(u32) -> *const c_char,
    schedule_asynchronous: unsafe extern "C" fn(Callback, *mut c_void, u16) -> c_ulong,
    unschedule: unsafe extern "C" fn(c_ulong),
    start_scheduler: unsafe extern "C" fn(),
    stop_scheduler: unsafe extern "C" fn(),
    // Declared last: dropped after the pointers above are no longer used.
    _lib: libloading::Library,
}

/// Where the HD backend looks for `libHD`.
pub fn library_spec() -> LibrarySpec {
    LibrarySpec {
        backend: DeviceKind::Openhaptics,
        sdk: "OpenHaptics (3D Systems) HD",
        env_var: "ECHOTHIGH_HD_LIB",
        default_name: libloading::library_filename("HD")
            .to_string_lossy()
            .into_owned(),
    }
}

impl HdApi {
    fn load(spec: &LibrarySpec, path: &str) -> Result<Self, DeviceError> {
        let lib = spec.load(path)?;
        // SAFETY: each type is the C signature of hd.h / hdScheduler.h, and
        // the pointers live in the same struct as `lib`, which outlives them.
        unsafe {
            Ok(HdApi {
                init_device: spec.symbol(&lib, path, "hdInitDevice")?,
                disable_device: spec.symbol(&lib, path, "hdDisableDevice")?,
                make_current_device: spec.symbol(&lib, path, "hdMakeCurrentDevice")?,
                enable: spec.symbol(&lib, path, "hdEnable")?,
                disable: spec.symbol(&lib, path, "hdDisable")?,
                begin_frame: spec.symbol(&lib, path, "hdBeginFrame")?,
                end_frame: spec.symbol(&lib, path, "hdEndFrame")?,
                get_doublev: spec.symbol(&lib, path, "hdGetDoublev")?,
                get_integerv: spec.symbol(&lib, path, "hdGetIntegerv")?,
                get_string: spec.symbol(&lib, path, "hdGetString")?,
                set_doublev: spec.symbol(&lib, path, "hdSetDoublev")?,
                get_error: spec.symbol(&lib, path, "hdGetError")?,
                get_error_string: spec.symbol(&lib, path, "hdGetErrorString")?,
                schedule_asynchronous: spec.symbol(&lib, path, "hdScheduleAsynchronous")?,
                unschedule: spec.symbol(&lib, path, "hdUnschedule")?,
                start_scheduler: spec.symbol(&lib, path, "hdStartScheduler")?,
                stop_scheduler: spec.symbol(&lib, path, "hdStopScheduler")?,
                _lib: lib,
            })
        }
    }

    /// Pops every pending error; returns the first (most recent) with its text.
    fn take_error(&self) -> Option<(u32, String)> {
        let mut first = None;
        for _ in 0..16 {
            // SAFETY: no arguments; returns the struct by value.
            let e = unsafe { (self.get_error)() };
            if e.error_code == HD_SUCCESS {
                break;
            }
            if first.is_none() {
                // SAFETY: returns a static NUL-terminated string or null.
                let text = unsafe { (self.get_error_string)(e.error_code) };
                let text = if text.is_null() {
                    String::new()
                } else {
                    // SAFETY: non-null C string owned by the library.
                    unsafe { CStr::from_ptr(text) }
                        .to_string_lossy()
                        .into_owned()
                };
                first = Some((
                    e.error_code,
                    format!("HD error 0x{:04x}: {text}", e.error_code),
                ));
            }
        }
        first
    }

    fn check(&self, call: &'static str) -> Result<(), DeviceError> {
        match self.take_error() {
            None => Ok(()),
            Some((_, detail)) => Err(DeviceError::Sdk {
                backend: DeviceKind::Openhaptics,
                call,
                detail,
            }),
        }
    }

    fn double(&self, param: u32) -> f64 {
        let mut v = [f64::NAN; 16];
        // SAFETY: 16 doubles is the largest any parameter returns.
        unsafe { (self.get_doublev)(param, v.as_mut_ptr()) };
        let _ = self.take_error();
        v[0]
    }
}

/// The servo callback's context, owned by the backend, lent to HD.
struct ServoContext {
    api: Arc<HdApi>,
    handle: u32,
    side: ServoSide,
    ticks: u64,
    fault: u32,
}

/// HD servo callback: one frame per servo tick (1 kHz), on HD's thread.
extern "C" fn servo_callback(user: *mut c_void) -> u32 {
    // Never unwind into C: a panic here renders nothing more; HD keeps the
    // servo loop and our watchdog-less state is reported as lost.
    let ok = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // SAFETY: `user` is the `ServoContext` the backend scheduled and keeps
        // alive until after `hdStopScheduler`; only this thread touches it.
        let ctx = unsafe { &mut *(user as *mut ServoContext) };
        servo_frame(ctx);
    }));
    let _ = ok;
    HD_CALLBACK_CONTINUE
}

fn servo_frame(ctx: &mut ServoContext) {
    let api = &*ctx.api;
    let mut p = [0.0; 3];
    let mut v = [0.0; 3];
    let mut t = [0.0; 16];
    let mut buttons: c_int = 0;
    // SAFETY: HD calls inside a frame on the servo thread, buffers sized per hdDefines.h.
    unsafe {
        (api.begin_frame)(ctx.handle);
        (api.get_doublev)(HD_CURRENT_POSITION, p.as_mut_ptr());
        (api.get_doublev)(HD_CURRENT_VELOCITY, v.as_mut_ptr());
        (api.get_doublev)(HD_CURRENT_TRANSFORM, t.as_mut_ptr());
        (api.get_integerv)(HD_CURRENT_BUTTONS, &mut buttons);
    }
    let force = if ctx.fault != 0 {
        [0.0; 3]
    } else {
        ctx.side.force_to_apply()
    };
    // SAFETY: three doubles; ends the frame begun above.
    unsafe {
        (api.set_doublev)(HD_CURRENT_FORCE, force.as_ptr());
        (api.end_frame)(ctx.handle);
    }
    if let Some(code) = first_error(api) {
        ctx.fault = if code == HD_SUCCESS { FAULT_LOST } else { code };
    }
    ctx.ticks += 1;
    let mut rotation = [0.0; 9];
    // Column-major 4×4 → row-major 3×3: R[i][j] = T[4 j + i].
    for i in 0..3 {
        for j in 0..3 {
            rotation[3 * i + j] = t[4 * j + i];
        }
    }
    ctx.side.publish(ServoState {
        position: p.map(|x| x * 1e-3),
        velocity: v.map(|x| x * 1e-3),
        rotation,
        buttons: buttons as u32,
        ticks: ctx.ticks,
        fault: ctx.fault,
    });
}

/// Pops pending errors without allocating; returns the most recent code.
fn first_error(api: &HdApi) -> Option<u32> {
    let mut first = None;
    for _ in 0..16 {
        // SAFETY: no arguments.
        let e = unsafe { (api.get_error)() };
        if e.error_code == HD_SUCCESS {
            break;
        }
        first.get_or_insert(e.error_code);
    }
    first
}

struct HdBackend {
    api: Arc<HdApi>,
    handle: u32,
    scheduled: c_ulong,
    context: *mut ServoContext,
    shared: Arc<Shared>,
    closed: bool,
}

// SAFETY: the raw context pointer is only dereferenced by HD's servo thread
// (through the callback) and freed by `close` after the scheduler stopped.
unsafe impl Send for HdBackend {}

impl Backend for HdBackend {
    fn close(&mut self) {
        if self.closed {
            return;
        }
        self.closed = true;
        self.shared.stop.store(true, Ordering::Release);
        wait_for_zero_frames(&self.shared, 0.05);
        let api = &*self.api;
        // SAFETY: HD teardown in the documented order; after
        // `hdStopScheduler` returns the callback no longer runs, so the
        // context can be freed.
        unsafe {
            (api.stop_scheduler)();
            (api.unschedule)(self.scheduled);
            (api.disable)(HD_FORCE_OUTPUT);
            (api.disable_device)(self.handle);
            drop(Box::from_raw(self.context));
        }
        let _ = api.take_error();
    }
}

impl Drop for HdBackend {
    fn drop(&mut self) {
        self.close();
    }
}

/// Reads the model, limits and workspace of the current device.
fn describe(api: &HdApi) -> DeviceInfo {
    // SAFETY: returns a static C string or null.
    let model = unsafe { (api.get_string)(HD_DEVICE_MODEL_TYPE) };
    let model = if model.is_null() {
        "unknown".to_string()
    } else {
        // SAFETY: non-null C string owned by the library.
        unsafe { CStr::from_ptr(model) }
            .to_string_lossy()
            .into_owned()
    };
    let _ = api.take_error();
    let limits = ModelLimits::for_model(&model).tightened(
        api.double(HD_NOMINAL_MAX_FORCE),
        api.double(HD_NOMINAL_MAX_CONTINUOUS_FORCE),
        api.double(HD_NOMINAL_MAX_STIFFNESS) * 1e3, // N/mm → N/m
    );
    let mut ws = [f64::NAN; 16];
    let mut dof: c_int = 3;
    // SAFETY: six doubles (16 provided); one int.
    unsafe {
        (api.get_doublev)(HD_USABLE_WORKSPACE_DIMENSIONS, ws.as_mut_ptr());
        (api.get_integerv)(HD_INPUT_DOF, &mut dof);
    }
    let _ = api.take_error();
    let known = ws[..6].iter().all(|x| x.is_finite());
    DeviceInfo {
        backend: DeviceKind::Openhaptics,
        model,
        workspace_min: known.then(|| [ws[0] * 1e-3, ws[1] * 1e-3, ws[2] * 1e-3]),
        workspace_max: known.then(|| [ws[3] * 1e-3, ws[4] * 1e-3, ws[5] * 1e-3]),
        limits,
        orientation_sensed: dof >= 6,
        servo_rate: 1000.0,
        watchdog: "HD servo callback (zeroes a command older than watchdog_timeout)",
    }
}

/// Opens the device, schedules the servo callback and starts HD's scheduler.
pub fn open(config: &HardwareConfig) -> Result<HardwareDevice, DeviceError> {
    config.validate("device.hardware")?;
    let spec = library_spec();
    let path = spec.resolve(config.openhaptics.library.as_ref());
    let api = Arc::new(HdApi::load(&spec, &path)?);
    let name = match &config.openhaptics.device_name {
        Some(n) => Some(CString::new(n.as_str()).map_err(|_| DeviceError::Sdk {
            backend: DeviceKind::Openhaptics,
            call: "hdInitDevice",
            detail: "the device name contains a NUL byte".into(),
        })?),
        None => None,
    };
    // SAFETY: a C string or HD_DEFAULT_DEVICE (NULL).
    let handle =
        unsafe { (api.init_device)(name.as_ref().map_or(std::ptr::null(), |n| n.as_ptr())) };
    if handle == HD_INVALID_HANDLE {
        let detail = api
            .take_error()
            .map(|e| e.1)
            .unwrap_or_else(|| "hdInitDevice returned HD_INVALID_HANDLE".into());
        return Err(DeviceError::NoDevice {
            backend: DeviceKind::Openhaptics,
            detail: format!(
                "{detail}; is the Touch connected and configured (Touch Setup / Touch_Diagnostic)?"
            ),
        });
    }
    // SAFETY: a valid handle.
    unsafe {
        (api.make_current_device)(handle);
        (api.enable)(HD_MAX_FORCE_CLAMPING);
    }
    let _ = api.take_error();
    let info = describe(&api);
    let (tick, side, shared) = exchange(config.watchdog_timeout);
    let context = Box::into_raw(Box::new(ServoContext {
        api: Arc::clone(&api),
        handle,
        side,
        ticks: 0,
        fault: 0,
    }));
    // SAFETY: the callback has the HDSchedulerCallback ABI; `context` stays
    // valid until `close` frees it after stopping the scheduler.
    let scheduled = unsafe {
        (api.enable)(HD_FORCE_OUTPUT);
        let h =
            (api.schedule_asynchronous)(servo_callback, context.cast(), HD_MAX_SCHEDULER_PRIORITY);
        (api.start_scheduler)();
        h
    };
    let backend = HdBackend {
        api: Arc::clone(&api),
        handle,
        scheduled,
        context,
        shared: Arc::clone(&shared),
        closed: false,
    };
    if let Err(e) = api.check("hdStartScheduler") {
        drop(backend);
        return Err(e);
    }
    Ok(HardwareDevice::new(
        Box::new(backend),
        tick,
        shared,
        info,
        config,
    ))
}
