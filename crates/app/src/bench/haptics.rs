//! `echothigh bench haptics`: compute time per haptic tick (median, p99,
//! p99.9, max), per model-manager update, and the 1 kHz loop's period error
//! and missed deadlines over a real-time run. One run's numbers; the machine
//! is shared and noisy, so read them as such.

use std::path::PathBuf;

use super::haptics_cases::{self as bench, BenchOptions, BenchReport};
use anyhow::Context;
use echothigh_haptics::LoopConfig;

/// Arguments of `echothigh bench haptics`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the report as JSON on stdout (otherwise a human summary).
    #[arg(long)]
    json: bool,
    /// Also write the JSON report to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Duration of the real-time loop run, s (0 skips it).
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Loop rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// Number of individually timed ticks.
    #[arg(long, default_value_t = 200_000)]
    ticks: usize,
    /// Number of individually timed model-manager updates.
    #[arg(long, default_value_t = 20_000)]
    fits: usize,
    /// Instead: time the tick through this device (`openhaptics`,
    /// `forcedimension`, `haply`; point it at an emulator with
    /// ECHOTHIGH_HD_LIB / ECHOTHIGH_DHD_LIB / ECHOTHIGH_HAPLY_URL) beside
    /// the simulated device, `--device-ticks` paced ticks each.
    #[command(flatten)]
    device: crate::cmd::device_arg::DeviceArgs,
    /// Paced 1 kHz ticks per device with `--device`.
    #[arg(long, default_value_t = 5000)]
    device_ticks: usize,
}

/// Runs the benchmark and prints/writes its report.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(choice) = args.device.device {
        let real = args
            .device
            .open(echothigh_device::DeviceKindSetting::Simulated)?;
        let Some(mut real) = real else {
            anyhow::bail!("--device {choice:?}: name a real device (openhaptics, forcedimension, haply) to compare with the simulated one");
        };
        let name = format!("{choice:?}").to_lowercase();
        let results = super::device_tick::compare(&name, &mut *real, args.device_ticks)?;
        drop(real);
        let json = serde_json::json!({
            "bench": "haptics-device",
            "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
            "results": results,
        });
        let text = serde_json::to_string_pretty(&json)?;
        if let Some(path) = &args.out {
            std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
        }
        println!("{text}");
        return Ok(());
    }
    let opts = BenchOptions {
        ticks: args.ticks,
        fits: args.fits,
        loop_seconds: args.seconds,
        loop_config: LoopConfig {
            rate_hz: args.rate,
            ..LoopConfig::default()
        },
    };
    let report = bench::run(&opts).context("invalid benchmark options")?;
    let json = serde_json::json!({
        "bench": "haptics",
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "goals": { "tick_median_us": 2.0, "tick_p999_us": 20.0, "fit_median_us": 50.0 },
        "report": report,
    });
    let text = serde_json::to_string_pretty(&json)?;
    if let Some(path) = &args.out {
        std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
    }
    if args.json {
        println!("{text}");
    } else {
        print_summary(&report);
    }
    Ok(())
}

fn print_summary(r: &BenchReport) {
    let line = |name: &str, m: &bench::Micros| {
        println!(
            "{name:<22} n={:<8} median {:>8.3} µs  p99 {:>8.3} µs  p99.9 {:>8.3} µs  max {:>9.3} µs",
            m.count, m.median_us, m.p99_us, m.p999_us, m.max_us
        );
    };
    line("tick compute", &r.tick);
    line("fit (model manager)", &r.fit);
    println!("fit mean iterations    {:.2}", r.fit_mean_iterations);
    if let Some(l) = &r.loop_run {
        line("loop compute", &l.compute);
        line("loop |period error|", &l.period_error);
        println!(
            "loop {:.0} Hz over {:.1} s: {} ticks, {} missed deadlines ({:.2} per 10 000), real-time priority: {}",
            l.rate_hz, l.seconds, l.ticks, l.missed_deadlines, l.missed_per_10k, l.realtime_priority
        );
    }
}
