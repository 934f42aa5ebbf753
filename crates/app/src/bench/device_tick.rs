//! `echothigh bench haptics --device NAME`: the haptic tick through a
//! device beside the simulated one. For each: ticks paced at 1 kHz with the
//! end-effector 1 cm above a 400 N/m wall (the same force law every tick);
//! the tick's compute time (`set_force` + `advance`, wall clock: the calls do
//! no I/O and never wait, so a preemption shows in the tail) and the period
//! error (start to start − 1 ms), as median, p99 and p99.9; the same
//! calls' thread-CPU time (`tick_thread_cpu`, the calling thread's clock
//! only: what other processes on a shared machine do not inflate; an SDK's
//! own servo thread, where it runs one, is not in it; it carries one reading
//! of that clock, whose own cost is reported as `thread_cpu_clock_read`).
//! Point the backend at an emulator (`ECHOTHIGH_HD_LIB` /
//! `ECHOTHIGH_DHD_LIB` at `libechothigh_device_emu`, `ECHOTHIGH_HAPLY_URL`
//! at an emulated Inverse Service) or at a real device. One run's numbers
//! on a shared machine.

use super::clock::thread_cpu_us;
use echothigh_device::{DeviceConfig, HapticDevice, SimulatedDevice};
use nalgebra::Vector3;
use std::time::{Duration, Instant};

fn percentiles(mut v: Vec<f64>) -> serde_json::Value {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize] * 1e6;
    serde_json::json!({ "median_us": at(0.5), "p99_us": at(0.99), "p999_us": at(0.999) })
}

/// Back-to-back readings of the thread clock, `n` of them (s): the cost of
/// one reading, which each tick's thread-CPU time carries once.
fn clock_reads(n: usize) -> Vec<f64> {
    let mut v = Vec::with_capacity(n);
    for _ in 0..n {
        let c0 = thread_cpu_us();
        v.push((thread_cpu_us() - c0) * 1e-6);
    }
    v
}

/// Times `ticks` (≥ 2) paced ticks of `device`.
pub fn measure(name: &str, device: &mut dyn HapticDevice, ticks: usize) -> serde_json::Value {
    let ticks = ticks.max(2);
    let wall_y = device.position().y - 0.01;
    let (mut compute, mut period_error) = (Vec::with_capacity(ticks), Vec::with_capacity(ticks));
    let mut cpu = Vec::with_capacity(ticks);
    let period = Duration::from_millis(1);
    let start = Instant::now();
    let (mut next, mut last) = (start, start);
    for i in 0..ticks {
        let now = Instant::now();
        if i > 0 {
            period_error.push((now - last).as_secs_f64() - 1e-3);
        }
        last = now;
        let f = Vector3::new(0.0, 400.0 * (wall_y - device.position().y).max(0.0), 0.0);
        // The thread clock (a system call, ~1 µs) read outside the wall
        // clock's window, so that neither timing carries the other's cost.
        let c0 = thread_cpu_us();
        let t0 = Instant::now();
        device.set_force(f);
        device.advance(1e-3);
        compute.push(t0.elapsed().as_secs_f64());
        cpu.push((thread_cpu_us() - c0) * 1e-6);
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
    }
    serde_json::json!({
        "device": name,
        "ticks": ticks,
        "achieved_rate_hz": ticks as f64 / start.elapsed().as_secs_f64(),
        "tick_compute": percentiles(compute),
        "tick_thread_cpu": percentiles(cpu),
        "thread_cpu_clock_read": percentiles(clock_reads(1000)),
        "period_error": percentiles(period_error),
    })
}

/// The simulated device, then `real` (already opened), `ticks` each.
pub fn compare(
    real_name: &str,
    real: &mut dyn HapticDevice,
    ticks: usize,
) -> anyhow::Result<serde_json::Value> {
    let mut sim = SimulatedDevice::new(DeviceConfig::default(), Vector3::new(0.0, 0.1, 0.0))
        .map_err(|e| anyhow::anyhow!("the simulated device: {e}"))?;
    Ok(serde_json::json!([
        measure("simulated", &mut sim, ticks),
        measure(real_name, real, ticks),
    ]))
}
