//! `cargo bench -p echothigh-devices-hw --bench haptics`: the haptic tick
//! through each backend's emulator beside the simulated device. For each:
//! 5 000 ticks paced at 1 kHz (the end-effector in free space, 1 cm above a
//! 400 N/m wall, so the same proxy-free force law runs every tick); the tick's compute time
//! (`set_force` + `advance`, wall clock around the calls, which do no I/O
//! and never wait; a preemption shows in the tail) and the period error (actual start
//! to start − 1 ms), as median, p99 and p99.9, printed as one JSON document.
//! The emulator library is the one cargo built as this crate's dev-dependency;
//! the Haply backend talks to the in-process Inverse Service emulator over
//! loopback (its round trips run on the exchange thread, off the tick).

use echothigh_device::{DeviceConfig, HapticDevice, SimulatedDevice};
use echothigh_devices_hw::{open_device, DeviceKind, HardwareConfig, Vec3};
use std::path::PathBuf;
use std::time::{Duration, Instant};

const TICKS: usize = 5000;

fn emulator_path() -> Option<PathBuf> {
    let name = libloading::library_filename("echothigh_device_emu");
    let exe = std::env::current_exe().ok()?;
    exe.ancestors()
        .skip(1)
        .take(3)
        .map(|d| d.join(&name))
        .find(|p| p.is_file())
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn stats(mut v: Vec<f64>) -> serde_json::Value {
    v.sort_by(f64::total_cmp);
    serde_json::json!({
        "median_us": percentile(&v, 0.5) * 1e6,
        "p99_us": percentile(&v, 0.99) * 1e6,
        "p999_us": percentile(&v, 0.999) * 1e6,
    })
}

fn measure(name: &str, device: &mut dyn HapticDevice, wall_y: f64) -> serde_json::Value {
    let mut compute = Vec::with_capacity(TICKS);
    let mut period_error = Vec::with_capacity(TICKS);
    let period = Duration::from_millis(1);
    let start = Instant::now();
    let mut next = start;
    let mut last = start;
    for i in 0..TICKS {
        let now = Instant::now();
        if i > 0 {
            period_error.push((now - last).as_secs_f64() - 1e-3);
        }
        last = now;
        let f = Vec3::new(0.0, 400.0 * (wall_y - device.position().y).max(0.0), 0.0);
        let t0 = Instant::now();
        device.set_force(f);
        device.advance(1e-3);
        compute.push(t0.elapsed().as_secs_f64());
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    serde_json::json!({
        "device": name,
        "ticks": TICKS,
        "achieved_rate_hz": TICKS as f64 / elapsed,
        "tick_compute": stats(compute),
        "period_error": stats(period_error),
    })
}

fn main() {
    let mut results = Vec::new();
    let mut sim = SimulatedDevice::new(DeviceConfig::default(), Vec3::new(0.0, 0.1, 0.0))
        .expect("default simulated device");
    let y0 = sim.position().y;
    results.push(measure("simulated", &mut sim, y0 - 0.01));
    match emulator_path() {
        Some(path) => {
            std::env::set_var("ECHOTHIGH_HD_LIB", &path);
            std::env::set_var("ECHOTHIGH_DHD_LIB", &path);
            #[cfg(feature = "haply")]
            let _service = match echothigh_device_emu::inverse::InverseService::start() {
                Ok(s) => {
                    std::env::set_var("ECHOTHIGH_HAPLY_URL", s.url());
                    Some(s)
                }
                Err(_) => None,
            };
            for kind in DeviceKind::ALL {
                match open_device(&kind, &HardwareConfig::default()) {
                    Ok(mut d) => {
                        let y0 = d.position().y;
                        results.push(measure(&format!("{kind} (emulator)"), &mut *d, y0 - 0.01));
                    }
                    Err(e) => results.push(serde_json::json!({ "device": kind.name(), "error": e.to_string() })),
                }
            }
        }
        None => results.push(serde_json::json!({ "error": "emulator library not found next to the bench executable" })),
    }
    println!(
        "{}",
        serde_json::to_string_pretty(
            &serde_json::json!({ "bench": "haptics", "results": results })
        )
        .unwrap_or_default()
    );
}
