//! Time per 1 ms haptic tick of `advance` (simulated device with scripted
//! hand, 10 sub-steps; and replay), over the whole default exam against a
//! linear tissue. Prints one JSON object: median, p99 and max in µs.
//!
//! `cargo bench -p echothigh-device --bench advance`

use echothigh_device::{
    DeviceConfig, ExamConfig, ExamScript, HandConfig, HapticDevice, ReplayDevice, SimulatedDevice,
    SimulatedHand, Vec3,
};
use std::time::Instant;

const TICKS: usize = 10_000;

fn percentiles(mut ns: Vec<u64>) -> String {
    ns.sort_unstable();
    let at = |q: f64| ns[((ns.len() - 1) as f64 * q).round() as usize] as f64 / 1e3;
    format!(
        "{{\"ticks\": {}, \"median_us\": {:.3}, \"p99_us\": {:.3}, \"max_us\": {:.3}}}",
        ns.len(),
        at(0.5),
        at(0.99),
        ns[ns.len() - 1] as f64 / 1e3
    )
}

fn run(device: &mut dyn HapticDevice) -> Vec<u64> {
    let scale = DeviceConfig::default().force_scale();
    let mut times = Vec::with_capacity(TICKS);
    for _ in 0..TICKS {
        let depth = (0.072 - device.position().y).max(0.0);
        let f = scale.tissue_to_device(Vec3::new(0.0, 800.0 * depth, 0.0));
        let start = Instant::now();
        device.set_force(f);
        device.advance(1e-3);
        times.push(start.elapsed().as_nanos() as u64);
    }
    times
}

fn main() {
    let config = DeviceConfig::default();
    let script = ExamScript::new(ExamConfig::default()).expect("default script");
    let hand = SimulatedHand::scripted(HandConfig::default(), script).expect("default hand");
    let mut device = SimulatedDevice::with_hand(config, hand).expect("default device");
    let simulated = percentiles(run(&mut device));

    let times: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
    let points = times
        .iter()
        .map(|t| Vec3::new(0.0, 0.09 - 0.002 * t, 0.15 + 0.001 * t))
        .collect();
    let mut replay = ReplayDevice::from_samples(times, points, config).expect("replay");
    let replayed = percentiles(run(&mut replay));
    println!(
        "{{\"bench\": \"device_advance_1ms\", \"substeps_per_tick\": {}, \"simulated\": {simulated}, \"replay\": {replayed}}}",
        (config.substep_rate * 1e-3).round()
    );
}
