//! Force Dimension DHD backend: delta / omega / sigma devices and the Novint
//! Falcon (which the DHD SDK drives).
//!
//! `libdhd` is loaded at run time (`ECHOTHIGH_DHD_LIB` overrides the path).
//! DHD has no scheduler of its own: every call is a USB exchange made on the
//! caller's thread. The tick must not do I/O, so this backend runs a servo
//! thread that reads the pose and buttons and writes the force at
//! `servo_rate`, exchanging with the tick lock-free ([`crate::servo`]). The
//! stall watchdog runs twice: in the servo thread (a stale command renders
//! zero) and in the device's firmware (`dhdSetWatchdog`: the firmware
//! disables forces when no force command arrives within its duration, in
//! multiples of 125 µs), so that even a stalled servo thread ends in zero
//! force. Units: m, m/s, N (SI already). Signatures and constants: `dhdc.h`
//! (SDK 3.x; C linkage, the C++ default `ID = -1` passed explicitly).

use crate::config::HardwareConfig;
use crate::hardware::{Backend, DeviceInfo, HardwareDevice};
use crate::library::LibrarySpec;
use crate::safety::ModelLimits;
use crate::servo::{exchange, ServoSide, ServoState, Shared, FAULT_LOST};
use crate::{DeviceError, DeviceKind};
use std::ffi::{c_char, c_int, c_uchar, c_uint, CStr};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const DHD_ON: c_uchar = 1;
const DHD_OFF: c_uchar = 0;
/// Devices whose wrist senses orientation (dhdc.h device codes): delta.6,
/// omega.6/.7 (right and left), sigma.7 (right and left), sigma.6+ (right and left).
const ORIENTATION_DEVICES: [c_int; 9] = [64, 34, 35, 36, 37, 104, 105, 106, 107];
const WATCHDOG_TICK: f64 = 125e-6;

/// The DHD functions echothigh calls, copied out of the loaded library.
struct DhdApi {
    get_device_count: unsafe extern "C" fn() -> c_int,
    open: unsafe extern "C" fn() -> c_int,
    close: unsafe extern "C" fn(c_char) -> c_int,
    enable_force: unsafe extern "C" fn(c_uchar, c_char) -> c_int,
    get_system_type: unsafe extern "C" fn(c_char) -> c_int,
    get_system_name: unsafe extern "C" fn(c_char) -> *const c_char,
    set_watchdog: unsafe extern "C" fn(c_uchar, c_char) -> c_int,
    get_position: unsafe extern "C" fn(*mut f64, *mut f64, *mut f64, c_char) -> c_int,
    get_linear_velocity: unsafe extern "C" fn(*mut f64, *mut f64, *mut f64, c_char) -> c_int,
    get_orientation_frame: unsafe extern "C" fn(*mut f64, c_char) -> c_int,
    get_button_mask: unsafe extern "C" fn(c_char) -> c_uint,
    set_force: unsafe extern "C" fn(f64, f64, f64, c_char) -> c_int,
    error_get_last: unsafe extern "C" fn() -> c_int,
    error_get_last_str: unsafe extern "C" fn() -> *const c_char,
    // Declared last: outlives the pointers above.
    _lib: libloading::Library,
}

/// Where the DHD backend looks for `libdhd`.
pub fn library_spec() -> LibrarySpec {
    LibrarySpec {
        backend: DeviceKind::Forcedimension,
        sdk: "Force Dimension DHD",
        env_var: "ECHOTHIGH_DHD_LIB",
        default_name: if cfg!(windows) {
            "dhdms64.dll".to_string()
        } else {
            libloading::library_filename("dhd")
                .to_string_lossy()
                .into_owned()
        },
    }
}

impl DhdApi {
    fn load(spec: &LibrarySpec, path: &str) -> Result<Self, DeviceError> {
        let lib = spec.load(path)?;
        // SAFETY: each type is the C signature of dhdc.h; the pointers live in
        // the same struct as `lib`, which outlives them.
        unsafe {
            Ok(DhdApi {
                get_device_count: spec.symbol(&lib, path, "dhdGetDeviceCount")?,
                open: spec.symbol(&lib, path, "dhdOpen")?,
                close: spec.symbol(&lib, path, "dhdClose")?,
                enable_force: spec.symbol(&lib, path, "dhdEnableForce")?,
                get_system_type: spec.symbol(&lib, path, "dhdGetSystemType")?,
                get_system_name: spec.symbol(&lib, path, "dhdGetSystemName")?,
                set_watchdog: spec.symbol(&lib, path, "dhdSetWatchdog")?,
                get_position: spec.symbol(&lib, path, "dhdGetPosition")?,
                get_linear_velocity: spec.symbol(&lib, path, "dhdGetLinearVelocity")?,
                get_orientation_frame: spec.symbol(&lib, path, "dhdGetOrientationFrame")?,
                get_button_mask: spec.symbol(&lib, path, "dhdGetButtonMask")?,
                set_force: spec.symbol(&lib, path, "dhdSetForce")?,
                error_get_last: spec.symbol(&lib, path, "dhdErrorGetLast")?,
                error_get_last_str: spec.symbol(&lib, path, "dhdErrorGetLastStr")?,
                _lib: lib,
            })
        }
    }

    fn last_error(&self) -> String {
        // SAFETY: returns a static C string or null.
        let s = unsafe { (self.error_get_last_str)() };
        if s.is_null() {
            "unknown DHD error".into()
        } else {
            // SAFETY: non-null C string owned by the library.
            unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
        }
    }

    fn sdk_error(&self, call: &'static str) -> DeviceError {
        DeviceError::Sdk {
            backend: DeviceKind::Forcedimension,
            call,
            detail: self.last_error(),
        }
    }
}

struct Servo {
    api: Arc<DhdApi>,
    id: c_char,
    side: ServoSide,
    orientation: bool,
    period: Duration,
}

impl Servo {
    /// The servo loop: read, publish, write force, pace. Ends on the stop
    /// flag after writing zero force.
    fn run(mut self) {
        let api = &*self.api;
        let mut state = ServoState::default();
        let mut next = Instant::now();
        loop {
            let stopping = self.side.stopping();
            if state.fault == 0 {
                let (mut p, mut v) = ([0.0; 3], [0.0; 3]);
                // SAFETY: pointers to live locals; the device ID from dhdOpen.
                let ok = unsafe {
                    let a = (api.get_position)(&mut p[0], &mut p[1], &mut p[2], self.id);
                    let b = (api.get_linear_velocity)(&mut v[0], &mut v[1], &mut v[2], self.id);
                    let c = if self.orientation {
                        (api.get_orientation_frame)(state.rotation.as_mut_ptr(), self.id)
                    } else {
                        0
                    };
                    a >= 0 && b >= 0 && c >= 0
                };
                let force = self.side.force_to_apply();
                // SAFETY: plain values and the device ID.
                let written =
                    ok && unsafe { (api.set_force)(force[0], force[1], force[2], self.id) } >= 0;
                if written {
                    state.position = p;
                    state.velocity = v;
                    // SAFETY: the device ID.
                    state.buttons = unsafe { (api.get_button_mask)(self.id) };
                } else {
                    // SAFETY: no arguments.
                    let code = unsafe { (api.error_get_last)() };
                    state.fault = if code > 0 { code as u32 } else { FAULT_LOST };
                }
            }
            state.ticks += 1;
            self.side.publish(state);
            if stopping {
                return;
            }
            next += self.period;
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
    }
}

struct DhdBackend {
    api: Arc<DhdApi>,
    id: c_char,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl Backend for DhdBackend {
    fn close(&mut self) {
        let Some(thread) = self.thread.take() else {
            return;
        };
        self.shared.stop.store(true, Ordering::Release);
        let _ = thread.join();
        // SAFETY: the device ID from dhdOpen; forces off, then release.
        unsafe {
            (self.api.set_force)(0.0, 0.0, 0.0, self.id);
            (self.api.enable_force)(DHD_OFF, self.id);
            (self.api.close)(self.id);
        }
    }
}

impl Drop for DhdBackend {
    fn drop(&mut self) {
        self.close();
    }
}

/// Opens the first device, arms the firmware watchdog, enables forces and
/// starts the servo thread.
pub fn open(config: &HardwareConfig) -> Result<HardwareDevice, DeviceError> {
    config.validate("device.hardware")?;
    let spec = library_spec();
    let path = spec.resolve(config.forcedimension.library.as_ref());
    let api = Arc::new(DhdApi::load(&spec, &path)?);
    // SAFETY: no arguments.
    if unsafe { (api.get_device_count)() } < 1 {
        return Err(DeviceError::NoDevice {
            backend: DeviceKind::Forcedimension,
            detail: "dhdGetDeviceCount found no device; is it powered and connected by USB?".into(),
        });
    }
    // SAFETY: no arguments.
    let id = unsafe { (api.open)() };
    if id < 0 {
        return Err(DeviceError::NoDevice {
            backend: DeviceKind::Forcedimension,
            detail: format!("dhdOpen: {}", api.last_error()),
        });
    }
    let id = id as c_char;
    // From here on, the backend closes the device on every error path.
    let (tick, side, shared) = exchange(config.watchdog_timeout);
    let mut backend = DhdBackend {
        api: Arc::clone(&api),
        id,
        shared: Arc::clone(&shared),
        thread: None,
    };
    // SAFETY: the device ID from dhdOpen.
    let (kind, name) = unsafe { ((api.get_system_type)(id), (api.get_system_name)(id)) };
    if kind < 0 {
        let e = api.sdk_error("dhdGetSystemType");
        // SAFETY: as above.
        unsafe { (api.close)(id) };
        return Err(e);
    }
    let model = if name.is_null() {
        format!("DHD device type {kind}")
    } else {
        // SAFETY: non-null C string owned by the library.
        unsafe { CStr::from_ptr(name) }
            .to_string_lossy()
            .into_owned()
    };
    let ticks = (config.watchdog_timeout / WATCHDOG_TICK)
        .ceil()
        .clamp(1.0, 255.0) as c_uchar;
    // SAFETY: the device ID.
    let firmware_watchdog = unsafe { (api.set_watchdog)(ticks, id) } >= 0;
    // SAFETY: the device ID.
    if unsafe { (api.enable_force)(DHD_ON, id) } < 0 {
        let e = api.sdk_error("dhdEnableForce");
        // SAFETY: as above.
        unsafe { (api.close)(id) };
        return Err(e);
    }
    let orientation = ORIENTATION_DEVICES.contains(&kind);
    let servo = Servo {
        api: Arc::clone(&api),
        id,
        side,
        orientation,
        period: Duration::from_secs_f64(1.0 / config.forcedimension.servo_rate),
    };
    let thread = std::thread::Builder::new()
        .name("dhd-servo".into())
        .spawn(move || servo.run());
    match thread {
        Ok(t) => backend.thread = Some(t),
        Err(e) => {
            // SAFETY: the device ID.
            unsafe {
                (api.enable_force)(DHD_OFF, id);
                (api.close)(id);
            }
            return Err(DeviceError::Sdk {
                backend: DeviceKind::Forcedimension,
                call: "spawn servo thread",
                detail: e.to_string(),
            });
        }
    }
    let info = DeviceInfo {
        backend: DeviceKind::Forcedimension,
        limits: ModelLimits::for_model(&model),
        model,
        workspace_min: None,
        workspace_max: None,
        orientation_sensed: orientation,
        servo_rate: config.forcedimension.servo_rate,
        watchdog: if firmware_watchdog {
            "device firmware (dhdSetWatchdog) and the servo thread"
        } else {
            "servo thread only (this device's firmware has no watchdog)"
        },
    };
    Ok(HardwareDevice::new(
        Box::new(backend),
        tick,
        shared,
        info,
        config,
    ))
}
