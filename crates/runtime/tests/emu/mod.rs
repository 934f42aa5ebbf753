//! The emulated OpenHaptics Touch for the live system's device tests: the
//! `echothigh-device-emu` cdylib (the HD C functions with the vendor's
//! signatures, simulating a Touch; no hardware on these machines), found
//! where cargo built it for this test, and its test controls.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

static SERIAL: Mutex<()> = Mutex::new(());

/// Serialises the tests of one binary (the emulator is one device,
/// process-wide); survives a poisoned lock.
pub fn serial() -> MutexGuard<'static, ()> {
    SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The emulator library: next to this test executable or above it, up to `target`.
pub fn emulator_path() -> PathBuf {
    let name = libloading::library_filename("echothigh_device_emu");
    let exe = std::env::current_exe().expect("test executable path");
    let mut dir = exe.parent().map(PathBuf::from);
    while let Some(d) = dir {
        if d.join(&name).is_file() {
            return d.join(&name);
        }
        if d.file_name().is_some_and(|n| n == "target") {
            break;
        }
        dir = d.parent().map(PathBuf::from);
    }
    panic!("emulator library {name:?} not found above {exe:?}: build echothigh-device-emu");
}

/// The libHD emulator's test controls.
pub struct Touch {
    lib: libloading::Library,
}

impl Touch {
    /// Points `ECHOTHIGH_HD_LIB` at the emulator and resets it (present, at
    /// rest at its home, no hand, no buttons).
    pub fn load() -> Touch {
        std::env::set_var("ECHOTHIGH_HD_LIB", emulator_path());
        // SAFETY: our own emulator library; no initialisers with preconditions.
        let lib = unsafe { libloading::Library::new(emulator_path()) }.expect("load emulator");
        let t = Touch { lib };
        // SAFETY: () -> ().
        unsafe { t.f::<unsafe extern "C" fn()>("reset")() };
        t
    }

    fn f<T: Copy>(&self, name: &str) -> T {
        let full = format!("echothigh_emu_hd_{name}\0");
        // SAFETY: the callers give each control's exact signature.
        unsafe {
            *self
                .lib
                .get::<T>(full.as_bytes())
                .expect("emulator control")
        }
    }

    /// The emulated hand pulls the stylus to `target` (mm, device frame)
    /// with stiffness `k` (N/m) and damping `c` (N·s/m).
    pub fn hand(&self, target: [f64; 3], k: f64, c: f64) {
        // SAFETY: (const double*, double, double) -> ().
        unsafe {
            self.f::<unsafe extern "C" fn(*const f64, f64, f64)>("set_hand")(target.as_ptr(), k, c)
        }
    }

    /// Buttons held (bit mask).
    pub fn buttons(&self, mask: u32) {
        // SAFETY: (int) -> (); same size and passing on every supported ABI.
        unsafe { self.f::<unsafe extern "C" fn(u32)>("set_buttons")(mask) }
    }

    /// USB unplugged: frames fail with `HD_COMM_ERROR`, the motors stop.
    pub fn unplug(&self) {
        // SAFETY: () -> ().
        unsafe { self.f::<unsafe extern "C" fn()>("unplug")() }
    }

    /// Last force commanded (N, device frame) and the emulator time (s) of the command.
    pub fn last_force(&self) -> ([f64; 3], f64) {
        let mut f = [0.0; 3];
        // SAFETY: (double*) -> double.
        let t = unsafe {
            self.f::<unsafe extern "C" fn(*mut f64) -> f64>("last_force")(f.as_mut_ptr())
        };
        (f, t)
    }

    /// Force the motors apply now (N, device frame).
    pub fn applied_force(&self) -> [f64; 3] {
        let mut f = [0.0; 3];
        // SAFETY: (double*) -> ().
        unsafe { self.f::<unsafe extern "C" fn(*mut f64)>("applied_force")(f.as_mut_ptr()) };
        f
    }

    /// Largest force magnitude the motors applied since the reset (N).
    pub fn max_applied_force(&self) -> f64 {
        // SAFETY: () -> double.
        unsafe { self.f::<unsafe extern "C" fn() -> f64>("max_applied_force")() }
    }

    /// The emulator's clock (s).
    pub fn now(&self) -> f64 {
        // SAFETY: () -> double.
        unsafe {
            (*self
                .lib
                .get::<unsafe extern "C" fn() -> f64>(b"echothigh_emu_now\0")
                .expect("now"))()
        }
    }
}

/// |v| (N or m).
pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}
