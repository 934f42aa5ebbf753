//! The Force Dimension backend against the libdhd emulator (no hardware here).

mod common;

use common::{norm, run_paced, serial, settled_medians, Emu};
use echothigh_device::HapticDevice;
use echothigh_devices_hw::{
    open_device, open_hardware, probe, DeviceError, DeviceKind, DeviceToLeg, HardwareConfig, Vec3,
};
use echothigh_testkit::{count_allocations, CountingAllocator};
use nalgebra::{Rotation3, UnitQuaternion};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const KIND: DeviceKind = DeviceKind::Forcedimension;

fn emulator() -> Emu {
    std::env::set_var("ECHOTHIGH_DHD_LIB", common::emulator_path());
    let emu = Emu::load("dhd");
    emu.reset();
    emu
}

fn turned() -> HardwareConfig {
    HardwareConfig {
        calibration: DeviceToLeg {
            rotation: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
            translation: [0.0, 0.1, 0.0],
        },
        // The longest watchdog: an OS stall of the test thread between the
        // last tick and reading the emulator should not zero the force.
        watchdog_timeout: echothigh_devices_hw::config::MAX_WATCHDOG,
        ..HardwareConfig::default()
    }
}

/// The longest watchdog (the DHD firmware's 31.875 ms), so that an OS stall
/// of the tick on a loaded machine rarely trips it during equilibrium tests.
fn slow_watchdog() -> HardwareConfig {
    HardwareConfig {
        watchdog_timeout: echothigh_devices_hw::config::MAX_WATCHDOG,
        ..HardwareConfig::default()
    }
}

/// Leg-frame wall at y = 0.09 m, 400 N/m, pushing out along +y.
fn wall(d: &dyn HapticDevice) -> Vec3 {
    Vec3::new(0.0, 400.0 * (0.09 - d.position().y).max(0.0), 0.0)
}

#[test]
fn missing_library_names_the_file_and_the_variable() {
    let _g = serial();
    std::env::set_var("ECHOTHIGH_DHD_LIB", "/nonexistent/libdhd.so");
    let err = open_device(&KIND, &HardwareConfig::default())
        .err()
        .expect("must fail");
    let msg = err.to_string();
    assert!(matches!(err, DeviceError::LibraryNotFound { .. }), "{msg}");
    assert!(
        msg.contains("/nonexistent/libdhd.so") && msg.contains("ECHOTHIGH_DHD_LIB"),
        "{msg}"
    );
    let report = probe(KIND, &HardwareConfig::default());
    assert!(!report.found && report.reason.is_some());
}

#[test]
fn absent_device_is_a_clear_error() {
    let _g = serial();
    let emu = emulator();
    emu.set_present(false);
    let err = open_device(&KIND, &HardwareConfig::default())
        .err()
        .expect("must fail");
    assert!(matches!(err, DeviceError::NoDevice { .. }), "{err}");
}

#[test]
fn handle_motion_and_orientation_arrive_through_the_calibration() {
    let _g = serial();
    let emu = emulator();
    let config = turned();
    let mut dev = open_hardware(KIND, &config).unwrap();
    assert_eq!(dev.info().model, "omega.6");
    assert!(
        dev.info().watchdog.contains("firmware"),
        "{}",
        dev.info().watchdog
    );
    // Critically damped hand on the 0.2 kg arm: k 500 N/m, c 18 N·s/m (+2 of
    // the arm): ζ = 20 / (2 √(500 × 0.2)) = 1.0, 1/ω = 20 ms; 0.6 s is 30 of them.
    emu.set_hand(Some([0.0; 3]), 500.0, 18.0);
    run_paced(&mut dev, 300, |_, _| Vec3::zeros());
    let start = dev.position();
    emu.set_hand(Some([0.03, 0.0, 0.0]), 500.0, 18.0);
    let r = Rotation3::from_axis_angle(&Vec3::x_axis(), -0.4);
    emu.set_rotation([
        r[(0, 0)],
        r[(0, 1)],
        r[(0, 2)],
        r[(1, 0)],
        r[(1, 1)],
        r[(1, 2)],
        r[(2, 0)],
        r[(2, 1)],
        r[(2, 2)],
    ]);
    run_paced(&mut dev, 600, |_, _| Vec3::zeros());
    let moved = dev.position() - start;
    // (1 + 30) e^-30 × 30 mm = 9e-11 m of transient left; 1e-6 m allows the
    // servo's 1 ms staleness and the emulator's Euler error.
    assert!(
        (moved - Vec3::new(0.0, 0.0, -0.030)).norm() < 1e-6,
        "moved {moved:?}"
    );
    let expected =
        config.calibration.isometry().rotation * UnitQuaternion::from_rotation_matrix(&r);
    assert!(dev.orientation().unwrap().angle_to(&expected) < 1e-9);
}

#[test]
fn forces_reach_the_device_frame_and_a_wall_pushes_back() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &turned()).unwrap();
    emu.set_hand(Some([0.0; 3]), 5000.0, 60.0);
    run_paced(&mut dev, 600, |_, _| Vec3::new(0.0, 0.0, 2.0));
    let (f, _) = emu.last_force();
    // Leg +z ↦ device −x (R_y(90°)ᵀ ẑ = −x̂), in newtons.
    assert!(
        (Vec3::from(f) - Vec3::new(-2.0, 0.0, 0.0)).norm() < 1e-12,
        "{f:?}"
    );
    drop(dev);

    // Hand towards device y = −20 mm (400 N/m) against the 400 N/m wall at
    // device y = −10 mm: equilibrium y = −15 mm, 2 N on the wall.
    emu.reset();
    let mut dev = open_hardware(KIND, &slow_watchdog()).unwrap();
    emu.set_hand(Some([0.0, -0.02, 0.0]), 400.0, 16.0);
    let (y, f) = settled_medians(&mut dev, 1200, wall);
    let y = y - 0.1;
    // ζ = 18 / (2 √(800 × 0.2)) = 0.71, 1/ω = 16 ms: settled after 1.2 s;
    // 1e-5 m for the exchange delay, hence 400 N/m × 1e-5 m = 4e-3 N.
    assert!((y + 0.015).abs() < 1e-5, "device y {y}");
    assert!((f - 2.0).abs() < 4e-3, "{f}");
}

#[test]
fn five_seconds_at_1khz_without_allocation_within_limits_and_ramped() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    let peak = dev.info().limits.peak_force;
    // The hand presses 60 mm into a 400 N/m wall: commands up to ~20 N, over the omega's 12 N.
    emu.set_hand(Some([0.0, -0.06, 0.0]), 600.0, 20.0);
    let mut records: Vec<(f64, f64, f64)> = Vec::with_capacity(5000);
    let (elapsed, allocations) = count_allocations(|| {
        run_paced(&mut dev, 5000, |i, d| {
            let cmd = Vec3::new(0.0, 600.0 * (0.1 - d.position().y).max(0.0), 0.0);
            if let Some(r) = records.last_mut() {
                r.1 = d.force().norm();
            }
            records.push((i as f64 * 1e-3, 0.0, cmd.norm()));
            cmd
        })
    });
    assert_eq!(allocations, 0, "the tick allocated {allocations} times");
    println!(
        "forcedimension emulator: 5000 ticks in {elapsed:.3} s, achieved {:.1} Hz, {} servo iterations",
        5000.0 / elapsed,
        dev.servo_ticks()
    );
    for w in records.windows(2) {
        // As in the OpenHaptics test: tick i's ramp gain is i ms / 0.5 s.
        let (t, rendered, cmd) = w[0];
        assert!(rendered <= peak + 1e-12, "{rendered} N at {t} s");
        assert!(
            rendered <= (t / 0.5).min(1.0) * cmd.min(peak) + 1e-12,
            "not ramped at {t} s"
        );
    }
    assert!(records[1000].1 > 0.0);
    assert!(
        emu.max_applied_force() <= peak,
        "{}",
        emu.max_applied_force()
    );
}

#[test]
fn stalled_tick_zeroes_force_and_drop_leaves_zero() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    // The firmware watchdog is armed at the configured 10 ms: 10 ms / 125 µs = 80.
    // SAFETY: our emulator; the control's signature is `unsigned char (void)`.
    let armed = unsafe {
        let lib = libloading::Library::new(common::emulator_path()).unwrap();
        let f = *lib
            .get::<unsafe extern "C" fn() -> u8>(b"echothigh_emu_dhd_watchdog\0")
            .unwrap();
        f()
    };
    assert_eq!(armed, 80);
    emu.set_hand(Some([0.0, -0.02, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    assert!(norm(emu.applied_force()) > 1.0, "{:?}", emu.applied_force());
    let stall = std::time::Instant::now();
    let mut zero_after = None;
    while stall.elapsed().as_secs_f64() < 0.05 {
        if zero_after.is_none() && norm(emu.applied_force()) == 0.0 {
            zero_after = Some(stall.elapsed().as_secs_f64());
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    let zero_after = zero_after.expect("the force was never zeroed during a 50 ms stall");
    println!(
        "forcedimension: force zeroed {:.1} ms into the stall (timeout 10 ms)",
        zero_after * 1e3
    );
    run_paced(&mut dev, 50, |_, d| wall(d));
    assert!(norm(emu.applied_force()) > 1.0);
    drop(dev);
    assert_eq!(emu.applied_force(), [0.0; 3]);
    assert_eq!(emu.last_force().0, [0.0; 3]);
}

#[test]
fn unplugged_device_faults_cleanly() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    emu.set_hand(Some([0.0, -0.02, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    emu.unplug();
    run_paced(&mut dev, 20, |_, d| wall(d));
    assert!(dev.fault().is_some());
    let held = dev.position();
    run_paced(&mut dev, 5, |_, d| wall(d));
    assert_eq!(dev.force(), Vec3::zeros());
    assert_eq!(dev.position(), held);
    drop(dev);
    assert_eq!(emu.applied_force(), [0.0; 3]);
}
