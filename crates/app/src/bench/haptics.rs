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
}

/// Runs the benchmark and prints/writes its report.
pub fn run(args: Args) -> anyhow::Result<()> {
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
