//! Shared by the backend tests: finding the emulator library that cargo
//! built for this test (it is a dev-dependency with a `cdylib` target), its
//! control functions, a paced tick loop, and a lock that serialises the tests
//! of one binary (each emulator emulates one device, process-wide).
#![allow(dead_code)]

use echothigh_device::HapticDevice;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

static SERIAL: Mutex<()> = Mutex::new(());

/// Serialises the tests of one binary; survives a poisoned lock.
pub fn serial() -> MutexGuard<'static, ()> {
    SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The emulator library: next to this test executable (`target/<profile>/deps`)
/// or one level up (`target/<profile>`), where cargo puts a dependency's cdylib.
pub fn emulator_path() -> PathBuf {
    let name = libloading::library_filename("echothigh_device_emu");
    let exe = std::env::current_exe().expect("test executable path");
    let mut dir = exe.parent().map(PathBuf::from);
    while let Some(d) = dir {
        let candidate = d.join(&name);
        if candidate.is_file() {
            return candidate;
        }
        dir = d.parent().map(PathBuf::from);
        if d.file_name().is_some_and(|n| n == "target") {
            break;
        }
    }
    panic!("emulator library {name:?} not found above {exe:?}: build echothigh-device-emu");
}

/// The emulator's test controls for one API (`hd` or `dhd`).
pub struct Emu {
    lib: libloading::Library,
    prefix: &'static str,
}

impl Emu {
    /// Loads the controls of the `hd` or `dhd` emulator.
    pub fn load(prefix: &'static str) -> Emu {
        // SAFETY: our own emulator library; no initialisers with preconditions.
        let lib = unsafe { libloading::Library::new(emulator_path()) }.expect("load emulator");
        Emu { lib, prefix }
    }

    fn f<T: Copy>(&self, name: &str) -> T {
        let full = format!("echothigh_emu_{}_{name}\0", self.prefix);
        // SAFETY: the callers below give each control's exact signature.
        unsafe {
            *self
                .lib
                .get::<T>(full.as_bytes())
                .expect("emulator control")
        }
    }

    pub fn reset(&self) {
        // SAFETY: () -> ().
        unsafe { self.f::<unsafe extern "C" fn()>("reset")() }
    }
    pub fn set_present(&self, present: bool) {
        // SAFETY: (int) -> ().
        unsafe { self.f::<unsafe extern "C" fn(i32)>("set_present")(i32::from(present)) }
    }
    pub fn unplug(&self) {
        // SAFETY: () -> ().
        unsafe { self.f::<unsafe extern "C" fn()>("unplug")() }
    }
    /// Hand target in the API's length unit (mm for HD, m for DHD).
    pub fn set_hand(&self, target: Option<[f64; 3]>, k: f64, c: f64) {
        let p = target.as_ref().map_or(std::ptr::null(), |t| t.as_ptr());
        // SAFETY: (const double*, double, double) -> ().
        unsafe { self.f::<unsafe extern "C" fn(*const f64, f64, f64)>("set_hand")(p, k, c) }
    }
    pub fn set_rotation(&self, r: [f64; 9]) {
        // SAFETY: (const double*) -> ().
        unsafe { self.f::<unsafe extern "C" fn(*const f64)>("set_rotation")(r.as_ptr()) }
    }
    pub fn set_buttons(&self, mask: u32) {
        // SAFETY: (int / uint) -> (); same size and passing on every supported ABI.
        unsafe { self.f::<unsafe extern "C" fn(u32)>("set_buttons")(mask) }
    }
    /// Last commanded force (N) and the emulator time (s) it was commanded at.
    pub fn last_force(&self) -> ([f64; 3], f64) {
        let mut f = [0.0; 3];
        // SAFETY: (double*) -> double.
        let t = unsafe {
            self.f::<unsafe extern "C" fn(*mut f64) -> f64>("last_force")(f.as_mut_ptr())
        };
        (f, t)
    }
    /// Force the motors apply now (N).
    pub fn applied_force(&self) -> [f64; 3] {
        let mut f = [0.0; 3];
        // SAFETY: (double*) -> ().
        unsafe { self.f::<unsafe extern "C" fn(*mut f64)>("applied_force")(f.as_mut_ptr()) };
        f
    }
    pub fn max_applied_force(&self) -> f64 {
        // SAFETY: () -> double.
        unsafe { self.f::<unsafe extern "C" fn() -> f64>("max_applied_force")() }
    }
}

pub fn norm(f: [f64; 3]) -> f64 {
    (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
}

/// Runs `ticks` haptic ticks paced at 1 kHz (deadline sleeps), calling
/// `force(t, position)` for the force in the leg frame. Returns the elapsed wall time (s).
pub fn run_paced(
    device: &mut dyn HapticDevice,
    ticks: usize,
    mut force: impl FnMut(usize, &dyn HapticDevice) -> echothigh_devices_hw::Vec3,
) -> f64 {
    let start = Instant::now();
    let period = Duration::from_millis(1);
    let mut next = start;
    for i in 0..ticks {
        let f = force(i, &*device);
        device.set_force(f);
        device.advance(1e-3);
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
    }
    start.elapsed().as_secs_f64()
}

/// Runs `ticks` paced ticks with `force`, then 300 more, and returns the
/// medians over those 300 of the leg-frame position's y (m) and the rendered
/// force's y (N). The median rejects the short transients a loaded machine
/// causes when the OS stalls the tick beyond the watchdog timeout.
pub fn settled_medians(
    device: &mut dyn HapticDevice,
    ticks: usize,
    force: impl Fn(&dyn HapticDevice) -> echothigh_devices_hw::Vec3,
) -> (f64, f64) {
    run_paced(device, ticks, |_, d| force(d));
    let mut ys = Vec::with_capacity(300);
    let mut fs = Vec::with_capacity(300);
    run_paced(device, 300, |_, d| {
        ys.push(d.position().y);
        fs.push(d.force().y);
        force(d)
    });
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    (median(&mut ys), median(&mut fs))
}

/// Runs paced ticks with `force` until `done(device)` holds, at most
/// `max_ticks`; returns whether it held. For conditions that a loaded
/// machine only delays (the servo thread not scheduled for a few ms, or an
/// OS stall of the tick beyond the watchdog zeroing the force for a moment):
/// the condition asserted is the same, only the moment it is checked waits.
pub fn tick_until(
    device: &mut dyn HapticDevice,
    max_ticks: usize,
    mut force: impl FnMut(&dyn HapticDevice) -> echothigh_devices_hw::Vec3,
    mut done: impl FnMut(&dyn HapticDevice) -> bool,
) -> bool {
    for _ in 0..max_ticks {
        if done(&*device) {
            return true;
        }
        run_paced(device, 1, |_, d| force(d));
    }
    done(&*device)
}
