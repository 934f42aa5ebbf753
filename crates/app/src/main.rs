//! `echothigh`: a real-time simulator of the echographic compression exam of
//! the thigh with force feedback (d'Aulignac, Balaniuk & Laugier). The binary
//! is thin: each subcommand parses its arguments and calls the library crates.

mod bench;
mod cmd;
#[allow(dead_code)] // used by the runtime and the viewer as they land
mod live;
#[allow(dead_code)] // used by the commands that write plots as they land
mod plot;
mod view;

use clap::{Parser, Subcommand};

/// Echographic compression exam of the thigh, with force feedback.
#[derive(Parser, Debug)]
#[command(name = "echothigh", version, about, long_about = None)]
struct Cli {
    /// Log filter (tracing `EnvFilter` syntax), e.g. `info` or `echothigh=debug`.
    #[arg(long, global = true, default_value = "info")]
    log: String,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Benchmarks that write JSON reports (medians and percentiles of one run).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Fit the tissue springs to a force–indentation curve (CSV).
    Calibrate(cmd::calibrate::Args),
    /// Render B-mode echographic frames under the probe.
    Image(cmd::image::Args),
    /// The trainee's live web viewer (3D thigh, probe, image, force, exam mode).
    View(view::Args),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_new(&cli.log)
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
    let result = match cli.command {
        Command::Bench(b) => bench::run(b),
        Command::Calibrate(a) => cmd::calibrate::run(a),
        Command::Image(a) => cmd::image::run(a),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
