//! The OpenHaptics backend against the libHD emulator (no hardware here).

mod common;

use common::{norm, run_paced, serial, settled_medians, tick_until, Emu};
use echothigh_device::HapticDevice;
use echothigh_devices_hw::{
    open_device, open_hardware, probe, DeviceError, DeviceKind, DeviceToLeg, HardwareConfig, Vec3,
};
use echothigh_testkit::{count_allocations, CountingAllocator};
use nalgebra::{Rotation3, UnitQuaternion};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const KIND: DeviceKind = DeviceKind::Openhaptics;

fn emulator() -> Emu {
    std::env::set_var("ECHOTHIGH_HD_LIB", common::emulator_path());
    let emu = Emu::load("hd");
    emu.reset();
    emu
}

/// Calibration rotating device axes 90° about y: device +x ↦ leg −z, device +z ↦ leg +x.
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

#[test]
fn missing_library_names_the_file_and_the_variable() {
    let _g = serial();
    std::env::set_var("ECHOTHIGH_HD_LIB", "/nonexistent/libHD.so");
    let err = open_device(&KIND, &HardwareConfig::default())
        .err()
        .expect("must fail");
    assert!(matches!(err, DeviceError::LibraryNotFound { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("/nonexistent/libHD.so") && msg.contains("ECHOTHIGH_HD_LIB"),
        "{msg}"
    );
    let report = probe(KIND, &HardwareConfig::default());
    assert!(!report.found && report.devices.is_empty());
    assert!(report.reason.unwrap().contains("ECHOTHIGH_HD_LIB"));
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
    let report = probe(KIND, &HardwareConfig::default());
    assert!(report.found, "the library is there");
    assert!(report.devices.is_empty() && report.reason.is_some());
}

#[test]
fn stylus_motion_and_orientation_arrive_through_the_calibration() {
    let _g = serial();
    let emu = emulator();
    let config = turned();
    let mut dev = open_hardware(KIND, &config).unwrap();
    assert_eq!(dev.info().model, "Touch");
    assert_eq!(dev.info().limits.peak_force, 3.3);
    // Hold the stylus at home, then push it 30 mm along the device's +x with
    // a critically damped hand (k 200 N/m, c 5 N·s/m with the 45 g arm's
    // 1 N·s/m: ζ = 6 / (2 √(200 × 0.045)) = 1.0); after 0.6 s (40 time
    // constants of 1/ω = 15 ms) it rests within 1e-9 m of the target.
    emu.set_hand(Some([0.0; 3]), 200.0, 5.0);
    run_paced(&mut dev, 300, |_, _| Vec3::zeros());
    let start = dev.position();
    emu.set_hand(Some([30.0, 0.0, 0.0]), 200.0, 5.0);
    let r = Rotation3::from_axis_angle(&Vec3::z_axis(), 0.5);
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
    // Device +x maps to leg −z; 1e-6 m allows the servo's 1 ms staleness at
    // the residual velocity (≪ 1 mm/s) and the emulator's 10 kHz Euler error.
    assert!(
        (moved - Vec3::new(0.0, 0.0, -0.030)).norm() < 1e-6,
        "moved {moved:?}"
    );
    let expected =
        config.calibration.isometry().rotation * UnitQuaternion::from_rotation_matrix(&r);
    let got = dev
        .orientation()
        .expect("the Touch's gimbal senses orientation");
    assert!(got.angle_to(&expected) < 1e-9, "{got:?} vs {expected:?}");
}

#[test]
fn forces_reach_the_device_frame_and_a_wall_pushes_back() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &turned()).unwrap();
    emu.set_hand(Some([0.0; 3]), 2000.0, 20.0);
    // After the 0.5 s ramp, a leg-frame +z force of 0.5 N is the device's −x
    // (R_y(90°)ᵀ ẑ = −x̂), in newtons.
    run_paced(&mut dev, 600, |_, _| Vec3::new(0.0, 0.0, 0.5));
    let (f, _) = emu.last_force();
    assert!(
        (Vec3::from(f) - Vec3::new(-0.5, 0.0, 0.0)).norm() < 1e-12,
        "{f:?}"
    );
    drop(dev);

    // A virtual wall (tissue surface) at leg y = 0.09 m, 200 N/m, pushing out
    // along +y; the hand presses towards device y = −15 mm (leg 0.085 m) with
    // 200 N/m. Equilibrium: 200 (−0.015 − y) + 200 (−0.010 − y) = 0 ⇒ device
    // y = −12.5 mm and 0.5 N on the wall. Were the sign wrong, the wall
    // would pull the stylus in and the equilibrium would not exist.
    emu.reset();
    let config = HardwareConfig {
        watchdog_timeout: echothigh_devices_hw::config::MAX_WATCHDOG,
        ..HardwareConfig::default()
    };
    let mut dev = open_hardware(KIND, &config).unwrap();
    emu.set_hand(Some([0.0, -15.0, 0.0]), 200.0, 5.0);
    // The longest watchdog, and medians over 300 settled ticks, so that an OS
    // stall of the tick on a loaded machine does not decide the result.
    let (y, f) = settled_medians(&mut dev, 1200, |d| {
        let depth = (0.09 - d.position().y).max(0.0);
        Vec3::new(0.0, 200.0 * depth, 0.0)
    });
    let y = y - 0.1;
    // ζ = 6 / (2 √(400 × 0.045)) = 0.71: after 1.2 s (≥ 80 time constants) the
    // transient is gone; 1e-5 m covers the 1–2 ms exchange delay at rest,
    // hence 200 N/m × 1e-5 m = 2e-3 N on the force.
    assert!((y + 0.0125).abs() < 1e-5, "device y {y}");
    assert!((f - 0.5).abs() < 2e-3, "{f}");
}

#[test]
fn five_seconds_at_1khz_without_allocation_within_limits_and_ramped() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    let peak = dev.info().limits.peak_force;
    // The hand presses 30 mm into a stiff (900 N/m) wall at device y = 0:
    // the command (up to ~10 N) exceeds the Touch's 3.3 N, so the clamp, the
    // thermal limiter and the ramp all act.
    emu.set_hand(Some([0.0, -30.0, 0.0]), 300.0, 5.0);
    let mut records: Vec<(f64, f64, f64)> = Vec::with_capacity(5000);
    let (elapsed, allocations) = count_allocations(|| {
        run_paced(&mut dev, 5000, |i, d| {
            let depth = (0.1 - d.position().y).max(0.0);
            let cmd = Vec3::new(0.0, 900.0 * depth, 0.0);
            if let Some(&mut (_, ref mut rendered, _)) = records.last_mut() {
                *rendered = d.force().norm();
            }
            records.push((i as f64 * 1e-3, 0.0, cmd.norm()));
            cmd
        })
    });
    assert_eq!(allocations, 0, "the tick allocated {allocations} times");
    let rate = 5000.0 / elapsed;
    println!("openhaptics emulator: 5000 ticks in {elapsed:.3} s, achieved {rate:.1} Hz, {} servo frames", dev.servo_ticks());
    for w in records.windows(2) {
        // records[i] = (i ms, force rendered for tick i's command, that
        // command); tick i's set_force follows i advances of 1 ms, so its ramp
        // gain is i ms / 0.5 s. The last record's rendered force is unread.
        let (t, rendered, cmd) = w[0];
        assert!(
            rendered <= peak + 1e-12,
            "{rendered} N over the {peak} N peak at {t} s"
        );
        let gain = (t / 0.5).min(1.0);
        assert!(
            rendered <= gain * cmd.min(peak) + 1e-12,
            "not ramped at {t} s: {rendered} > {gain} × {cmd}"
        );
    }
    assert!(records[1000].1 > 0.0, "force rendered after the ramp");
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
    let timeout = HardwareConfig::default().watchdog_timeout;
    emu.set_hand(Some([0.0, -15.0, 0.0]), 200.0, 5.0);
    let wall = |d: &dyn HapticDevice| Vec3::new(0.0, 200.0 * (0.09 - d.position().y).max(0.0), 0.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    // Rendering (checked while ticking: an OS stall of this thread beyond
    // the 10 ms watchdog zeroes the force until the next tick).
    assert!(
        tick_until(&mut dev, 2000, wall, |_| norm(emu.applied_force()) > 0.3),
        "{:?}",
        emu.applied_force()
    );
    // Stall the tick for 50 ms; watch the motors.
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
        "openhaptics: watchdog zeroed the force {:.1} ms into the stall (timeout {:.1} ms)",
        zero_after * 1e3,
        timeout * 1e3
    );
    assert!(dev.watchdog_trips() > 0);
    // Ticking again renders force again.
    run_paced(&mut dev, 50, |_, d| wall(d));
    assert!(tick_until(&mut dev, 2000, wall, |_| norm(
        emu.applied_force()
    ) > 0.3));
    drop(dev);
    assert_eq!(emu.applied_force(), [0.0; 3]);
    assert_eq!(
        emu.last_force().0,
        [0.0; 3],
        "the last force commanded is zero"
    );
}

#[test]
fn panic_in_the_haptic_thread_leaves_zero_force() {
    let _g = serial();
    let emu = emulator();
    emu.set_hand(Some([0.0, -15.0, 0.0]), 200.0, 5.0);
    let dev = open_device(&KIND, &HardwareConfig::default()).unwrap();
    let joined = std::thread::spawn(move || {
        let mut dev = dev;
        run_paced(&mut *dev, 700, |_, d| {
            Vec3::new(0.0, 200.0 * (0.09 - d.position().y).max(0.0), 0.0)
        });
        assert!(norm(Emu::load("hd").applied_force()) > 0.3);
        panic!("simulated failure elsewhere in the haptic thread");
    })
    .join();
    assert!(joined.is_err());
    assert_eq!(emu.applied_force(), [0.0; 3]);
    assert_eq!(emu.last_force().0, [0.0; 3]);
}

#[test]
fn unplugged_device_faults_cleanly_and_clutch_reengages_without_a_jump() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    emu.set_hand(Some([0.0; 3]), 300.0, 5.0);
    run_paced(&mut dev, 600, |_, _| Vec3::new(0.0, 0.2, 0.0));
    // Clutch (button 2 held): force zero, probe still, while the hand moves 40 mm along z.
    emu.set_buttons(2);
    run_paced(&mut dev, 20, |_, _| Vec3::new(0.0, 0.2, 0.0));
    let before = dev.position();
    emu.set_hand(Some([0.0, 0.0, 40.0]), 300.0, 5.0);
    run_paced(&mut dev, 400, |_, _| Vec3::new(0.0, 0.2, 0.0));
    assert!(dev.clutched());
    assert_eq!(dev.force(), Vec3::zeros());
    assert_eq!(dev.position(), before);
    emu.set_buttons(0);
    // The first tick that sees the release (the servo thread publishes it
    // within a servo period, later on a loaded machine).
    let push = |_: &dyn HapticDevice| Vec3::new(0.0, 0.2, 0.0);
    assert!(tick_until(&mut dev, 2000, push, |d| !d.clutched()));
    // Re-engaged where it was held: the hand rests (it settled 0.4 s ago), so
    // 1e-6 m bounds its motion since.
    assert!(
        (dev.position() - before).norm() < 1e-6,
        "{:?}",
        dev.position() - before
    );
    assert!(
        dev.ramp_gain() <= 0.002 + 1e-12,
        "ramp restarted: at most 1 ms of 0.5 s"
    );
    run_paced(&mut dev, 4, |_, d| push(d));
    // The device disappears: the fault latches, the force goes to zero, the pose holds.
    emu.unplug();
    // Latched within a servo period, later on a loaded machine.
    for _ in 0..2000 {
        if dev.fault().is_some() {
            break;
        }
        run_paced(&mut dev, 1, |_, d| push(d));
    }
    assert!(dev.fault().is_some());
    let held = dev.position();
    run_paced(&mut dev, 5, |_, _| Vec3::new(0.0, 0.2, 0.0));
    assert_eq!(dev.force(), Vec3::zeros());
    assert_eq!(dev.position(), held);
    drop(dev);
    assert_eq!(emu.applied_force(), [0.0; 3]);
}

#[test]
fn emergency_release_cuts_the_force_from_another_thread() {
    let _g = serial();
    let emu = emulator();
    let mut dev = open_hardware(KIND, &HardwareConfig::default()).unwrap();
    emu.set_hand(Some([0.0, -15.0, 0.0]), 200.0, 5.0);
    run_paced(&mut dev, 700, |_, d| {
        Vec3::new(0.0, 200.0 * (0.09 - d.position().y).max(0.0), 0.0)
    });
    let release = dev.emergency_release();
    std::thread::spawn(move || release.trigger())
        .join()
        .unwrap();
    // Without ticking: the servo obeys within a frame or two.
    std::thread::sleep(std::time::Duration::from_millis(10));
    assert_eq!(emu.applied_force(), [0.0; 3]);
    run_paced(&mut dev, 10, |_, d| {
        Vec3::new(0.0, 200.0 * (0.09 - d.position().y).max(0.0), 0.0)
    });
    assert_eq!(dev.force(), Vec3::zeros());
    assert_eq!(emu.applied_force(), [0.0; 3]);
}
