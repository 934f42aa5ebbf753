//! `echothigh`: a real-time simulator of the echographic compression exam of
//! the thigh with force feedback (d'Aulignac, Balaniuk & Laugier). The binary
//! is thin: each subcommand parses its arguments and calls the library crates.

mod bench;
mod cmd;

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
    /// Run a scripted compression exam (simulated hand and device) and write a run directory.
    Run(cmd::run::Args),
    /// The physics side as a UDP server (two-process deployment).
    PhysicsServer(cmd::net::ServerArgs),
    /// The haptic side as a UDP client of a physics server (two-process deployment).
    HapticClient(cmd::net::ClientArgs),
    /// Benchmarks that write JSON reports (medians and percentiles of one run).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Fit the tissue springs to a force–indentation curve (CSV).
    Calibrate(cmd::calibrate::Args),
    /// Render B-mode echographic frames under the probe.
    Image(cmd::image::Args),
    /// Pulsed-wave spectral Doppler of a case's vein or artery: spectrogram PNG, WAV, velocities JSON.
    Doppler(cmd::doppler::Args),
    /// Measure the probe's point spread function on the point phantom.
    Psf(cmd::psf::Args),
    /// Experiments: the paper's Fig. 4 and the rate, latency and damping sweeps.
    #[command(subcommand)]
    Experiment(echothigh_experiments::ExperimentCommand),
    /// The transverse section of the 3D leg anatomy under a probe (JSON or table).
    Anatomy(cmd::anatomy::Args),
    /// The case library (issue 13): list, show (ground truth), generate.
    #[command(subcommand)]
    Cases(cmd::cases::CasesCommand),
    /// The trainee's live web viewer (3D thigh, probe, image, force, exam mode).
    #[cfg(feature = "viewer")]
    View(cmd::view::ViewArgs),
    /// The scripted trainee (issue 14): an exam script on a case, headless on the virtual clock, and its score.
    Exam(cmd::exam::Args),
    /// List the real haptic-device backends: SDK found, devices, limits, or why not.
    Devices(cmd::devices::Args),
    /// A trainee's exam record as an HTML page with plots (from the records database).
    Report(cmd::report::Args),
    /// The records database: replay the fallback journal of an exam whose database failed.
    #[command(subcommand)]
    Records(cmd::records::RecordsCommand),
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
        Command::Run(a) => cmd::run::run(a),
        Command::PhysicsServer(a) => cmd::net::server(a),
        Command::HapticClient(a) => cmd::net::client(a),
        Command::Bench(b) => bench::run(b),
        Command::Calibrate(a) => cmd::calibrate::run(a),
        Command::Image(a) => cmd::image::run(a),
        Command::Psf(a) => cmd::psf::run(a),
        Command::Doppler(a) => cmd::doppler::run(a),
        Command::Experiment(c) => echothigh_experiments::run(c),
        #[cfg(feature = "viewer")]
        Command::View(a) => cmd::view::run(a),
        Command::Anatomy(a) => cmd::anatomy::run(a),
        Command::Cases(c) => cmd::cases::run(c),
        Command::Devices(a) => cmd::devices::run(a),
        Command::Exam(a) => cmd::exam::run(a),
        Command::Report(a) => cmd::report::run(a),
        Command::Records(c) => cmd::records::run(c),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
