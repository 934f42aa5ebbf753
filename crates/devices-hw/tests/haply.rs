//! The Haply backend against the emulated Inverse Service (no hardware here).
#![cfg(feature = "haply")]

mod common;

use common::{norm, run_paced, serial, settled_medians, tick_until};
use echothigh_device::HapticDevice;
use echothigh_device_emu::inverse::InverseService;
use echothigh_devices_hw::{
    open_device, open_hardware, probe, DeviceError, DeviceKind, DeviceToLeg, HardwareConfig, Vec3,
};
use echothigh_testkit::{count_allocations, CountingAllocator};
use nalgebra::{Quaternion, UnitQuaternion};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const KIND: DeviceKind = DeviceKind::Haply;

/// The wire carries f32: a component's rounding is at most 2⁻²⁴ ≈ 6e-8 of it.
const F32_REL: f64 = 6e-8;

fn config(emu: &InverseService) -> HardwareConfig {
    std::env::remove_var("ECHOTHIGH_HAPLY_URL");
    let mut c = HardwareConfig::default();
    c.haply.url = Some(emu.url());
    c
}

/// As `config`, with the longest watchdog (31.875 ms): an OS stall of the
/// test's tick on a loaded machine rarely trips it during equilibrium tests.
fn slow_watchdog(emu: &InverseService) -> HardwareConfig {
    HardwareConfig {
        watchdog_timeout: echothigh_devices_hw::config::MAX_WATCHDOG,
        ..config(emu)
    }
}

/// A loopback address where nothing listens (a port just freed).
fn dead_url() -> String {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    format!("ws://{}", l.local_addr().unwrap())
}

/// Leg-frame wall at y = 0.09 m (device y = −10 mm with the default
/// calibration's 0.1 m offset), 400 N/m, pushing out along +y.
fn wall(d: &dyn HapticDevice) -> Vec3 {
    Vec3::new(0.0, 400.0 * (0.09 - d.position().y).max(0.0), 0.0)
}

#[test]
fn unreachable_service_names_the_address_and_the_variable() {
    let _g = serial();
    std::env::remove_var("ECHOTHIGH_HAPLY_URL");
    let url = dead_url();
    let mut c = HardwareConfig::default();
    c.haply.url = Some(url.clone());
    let err = open_device(&KIND, &c).err().expect("must fail");
    let msg = err.to_string();
    assert!(
        matches!(err, DeviceError::ServiceUnreachable { .. }),
        "{msg}"
    );
    assert!(
        msg.contains(&url) && msg.contains("ECHOTHIGH_HAPLY_URL"),
        "{msg}"
    );
    let report = probe(KIND, &c);
    assert_eq!(report.service_reachable, Some(false));
    assert!(report.found && report.devices.is_empty() && report.reason.is_some());
    assert_eq!(
        (report.library.as_str(), report.env_var),
        (url.as_str(), "ECHOTHIGH_HAPLY_URL")
    );
}

#[test]
fn the_environment_variable_overrides_the_configured_address() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut c = HardwareConfig::default();
    c.haply.url = Some(dead_url());
    std::env::set_var("ECHOTHIGH_HAPLY_URL", emu.url());
    let report = probe(KIND, &c);
    std::env::remove_var("ECHOTHIGH_HAPLY_URL");
    assert_eq!(report.service_reachable, Some(true), "{:?}", report.reason);
    assert_eq!(report.library, emu.url());
    assert_eq!(report.env_value.as_deref(), Some(emu.url().as_str()));
    let d = &report.devices[0];
    assert!(
        d.model.starts_with("inverse3 049D") && d.orientation_sensed,
        "{d:?}"
    );
    // The probe left no force behind.
    assert_eq!(emu.closed_with_force(), 0);
}

#[test]
fn a_service_without_an_inverse3_is_a_clear_error() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    emu.unplug();
    let err = open_device(&KIND, &config(&emu)).err().expect("must fail");
    assert!(matches!(err, DeviceError::NoDevice { .. }), "{err}");
    assert!(err.to_string().contains("lists no Inverse3"), "{err}");
}

#[test]
fn cursor_motion_and_grip_orientation_arrive_through_the_calibration() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let config = HardwareConfig {
        calibration: DeviceToLeg {
            rotation: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
            translation: [0.0, 0.1, 0.0],
        },
        ..slow_watchdog(&emu)
    };
    let mut dev = open_hardware(KIND, &config).unwrap();
    assert!(dev.info().orientation_sensed);
    // Critically damped hand on the 0.2 kg arm (as the DHD test): k 500 N/m,
    // c 18 + 2 N·s/m: ζ = 20 / (2 √(500 × 0.2)) = 1.0, 1/ω = 20 ms.
    emu.set_hand(Some([0.0; 3]), 500.0, 18.0);
    run_paced(&mut dev, 300, |_, _| Vec3::zeros());
    let start = dev.position();
    emu.set_hand(Some([0.03, 0.0, 0.0]), 500.0, 18.0);
    // A VerseGrip turned −0.4 rad about x: q = (cos −0.2, sin −0.2, 0, 0).
    let q = [(-0.2f64).cos(), (-0.2f64).sin(), 0.0, 0.0];
    emu.set_grip(Some(q));
    run_paced(&mut dev, 600, |_, _| Vec3::zeros());
    let moved = dev.position() - start;
    // R_y(90°) maps device +x to leg −z. 0.6 s = 30/ω leaves 9e-11 m of
    // transient; 1e-6 m covers one exchange period of lag and f32 (2e-9 m).
    assert!(
        (moved - Vec3::new(0.0, 0.0, -0.030)).norm() < 1e-6,
        "moved {moved:?}"
    );
    let grip = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
    let expected = config.calibration.isometry().rotation * grip;
    // f32 quaternion components: an angle error of order 1e-7 rad.
    let err = dev.orientation().unwrap().angle_to(&expected);
    assert!(err < 1e-6, "orientation off by {err} rad");
}

#[test]
fn grip_button_clutches_and_zeroes_the_force() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &slow_watchdog(&emu)).unwrap();
    emu.set_hand(Some([0.0, -0.0125, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    // Checked while ticking: an OS stall of this thread beyond the watchdog
    // zeroes the force until the next tick.
    assert!(
        tick_until(&mut dev, 2000, wall, |_| norm(emu.applied_force()) > 0.25),
        "{:?}",
        emu.applied_force()
    );
    // The default clutch button is index 1: the grip's `b`.
    emu.set_buttons(0b10);
    assert!(tick_until(&mut dev, 2000, wall, |d| d.clutched()));
    run_paced(&mut dev, 5, |_, d| wall(d));
    assert_eq!(emu.applied_force(), [0.0; 3]);
}

#[test]
fn forces_reach_the_device_frame_and_a_wall_pushes_back() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let turned = HardwareConfig {
        calibration: DeviceToLeg {
            rotation: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
            translation: [0.0, 0.1, 0.0],
        },
        ..slow_watchdog(&emu)
    };
    let mut dev = open_hardware(KIND, &turned).unwrap();
    emu.set_hand(Some([0.0; 3]), 5000.0, 60.0);
    // 0.5 N: under the continuous limit (0.88 N, the Touch's, which an
    // unlisted model gets), so the thermal limiter never reduces it.
    run_paced(&mut dev, 600, |_, _| Vec3::new(0.0, 0.0, 0.5));
    let (f, _) = emu.last_force();
    // Leg +z ↦ device −x, in newtons; R_y(90°) in f64 leaves ~1e-17 N on
    // the other axes, and 0.5 is exact in f32.
    assert!(
        (Vec3::from(f) - Vec3::new(-0.5, 0.0, 0.0)).norm() < 1e-12,
        "{f:?}"
    );
    drop(dev);

    // Hand towards device y = −12.5 mm (400 N/m) against the 400 N/m wall
    // at device y = −10 mm: equilibrium y = −11.25 mm, 0.5 N on the wall.
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &slow_watchdog(&emu)).unwrap();
    emu.set_hand(Some([0.0, -0.0125, 0.0]), 400.0, 16.0);
    let (y, f) = settled_medians(&mut dev, 1200, wall);
    let y = y - 0.1;
    // ζ = 18 / (2 √(800 × 0.2)) = 0.71, 1/ω = 16 ms: settled after 1.2 s;
    // 1e-5 m for the exchange delay, hence 400 N/m × 1e-5 m = 4e-3 N.
    assert!((y + 0.01125).abs() < 1e-5, "device y {y}");
    assert!((f - 0.5).abs() < 4e-3, "{f}");
}

#[test]
fn five_seconds_at_1khz_without_allocation_within_limits_and_ramped() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &config(&emu)).unwrap();
    let peak = dev.info().limits.peak_force;
    // The hand presses 60 mm into a 600 N/m wall: commands up to ~20 N.
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
    // Counted on this (the tick's) thread only: the exchange thread's JSON
    // frames allocate on their own thread, off the tick.
    assert_eq!(allocations, 0, "the tick allocated {allocations} times");
    println!(
        "haply emulator: 5000 ticks in {elapsed:.3} s, achieved {:.1} Hz, {} exchange round trips",
        5000.0 / elapsed,
        dev.servo_ticks()
    );
    for w in records.windows(2) {
        // Tick i's ramp gain is i ms / 0.5 s (as in the OpenHaptics test).
        let (t, rendered, cmd) = w[0];
        assert!(rendered <= peak + 1e-12, "{rendered} N at {t} s");
        assert!(
            rendered <= (t / 0.5).min(1.0) * cmd.min(peak) + 1e-12,
            "not ramped at {t} s"
        );
    }
    assert!(records[1000].1 > 0.0);
    let max = emu.max_applied_force();
    // The service saw f32 components: at most (1 + F32_REL) × the f64 norm.
    assert!(max <= peak * (1.0 + F32_REL), "{max}");
}

#[test]
fn stalled_tick_zeroes_force_and_drop_leaves_zero() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &config(&emu)).unwrap();
    emu.set_hand(Some([0.0, -0.0125, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    // Checked while ticking: an OS stall of this thread beyond the watchdog
    // zeroes the force until the next tick.
    assert!(
        tick_until(&mut dev, 2000, wall, |_| norm(emu.applied_force()) > 0.25),
        "{:?}",
        emu.applied_force()
    );
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
        "haply: force zeroed {:.1} ms into the stall (timeout 10 ms)",
        zero_after * 1e3
    );
    assert!(dev.watchdog_trips() > 0);
    run_paced(&mut dev, 50, |_, d| wall(d));
    assert!(tick_until(&mut dev, 2000, wall, |_| norm(
        emu.applied_force()
    ) > 0.25));
    drop(dev);
    // Dropping sent a zero-force frame before closing the session.
    assert_eq!(emu.last_force().0, [0.0; 3]);
    assert_eq!(emu.closed_with_force(), 0);
}

#[test]
fn unplugged_device_faults_cleanly() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &config(&emu)).unwrap();
    emu.set_hand(Some([0.0, -0.0125, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    emu.unplug();
    // Latched on the next round trip, later on a loaded machine.
    for _ in 0..2000 {
        if dev.fault().is_some() {
            break;
        }
        run_paced(&mut dev, 1, |_, d| wall(d));
    }
    assert!(dev.fault().is_some());
    let held = dev.position();
    run_paced(&mut dev, 5, |_, d| wall(d));
    assert_eq!(dev.force(), Vec3::zeros());
    assert_eq!(dev.position(), held);
    drop(dev);
    assert_eq!(emu.applied_force(), [0.0; 3]);
    assert_eq!(emu.closed_with_force(), 0);
}

#[test]
fn a_dying_service_faults_the_device_without_hanging() {
    let _g = serial();
    let emu = InverseService::start().unwrap();
    let mut dev = open_hardware(KIND, &config(&emu)).unwrap();
    emu.set_hand(Some([0.0, -0.0125, 0.0]), 400.0, 16.0);
    run_paced(&mut dev, 700, |_, d| wall(d));
    emu.kill();
    // The next round trip fails at once (reset) or after the 0.1 s reply timeout.
    run_paced(&mut dev, 200, |_, d| wall(d));
    assert!(dev.fault().is_some());
    assert_eq!(dev.force(), Vec3::zeros());
    let t = std::time::Instant::now();
    drop(dev);
    println!(
        "haply: closed {:.1} ms after the service died",
        t.elapsed().as_secs_f64() * 1e3
    );
}
