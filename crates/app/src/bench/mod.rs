//! `echothigh bench ...`: benchmarks that print and write JSON reports.

pub mod clock;
pub mod contact;
pub mod device_tick;
pub mod direct_compare;
pub mod doppler;
pub mod haptics;
pub mod haptics_cases;
pub mod image;
pub mod link;
pub mod physics;
pub mod physics_cases;
pub mod physics_compare;

use clap::Subcommand;

/// Which benchmark to run.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Implicit physics step versus mesh size (and contact, queries).
    Physics(physics::Args),
    /// Haptic tick and model-manager fit times; loop period error.
    Haptics(haptics::Args),
    /// Echographic frame rate.
    Image(image::Args),
    /// Physics–haptics link: round-trip latency, achieved rates per deployment.
    Link(link::Args),
}

/// Runs the chosen benchmark.
pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Physics(a) => physics::run(a),
        BenchCommand::Haptics(a) => haptics::run(a),
        BenchCommand::Image(a) => image::run(a),
        BenchCommand::Link(a) => link::run(a),
    }
}
