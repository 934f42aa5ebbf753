//! Release-profile measurement of the haptic tick, the model manager and the
//! loop, printed as JSON (the same numbers as `echothigh bench haptics`):
//! `cargo run --release -p echothigh-haptics --example bench_haptics -- [seconds]`.

use echothigh_haptics::bench::{run, BenchOptions};

fn main() {
    let seconds = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10.0);
    let opts = BenchOptions {
        loop_seconds: seconds,
        ..BenchOptions::default()
    };
    match run(&opts) {
        Ok(report) => match serde_json::to_string_pretty(&report) {
            Ok(text) => println!("{text}"),
            Err(e) => eprintln!("error: {e}"),
        },
        Err(e) => eprintln!("error: {e}"),
    }
}
