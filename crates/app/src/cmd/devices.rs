//! `echothigh devices [--json]`: lists every real-device backend, whether its
//! SDK library was found (which file, which environment variable overrides
//! it), the devices connected with model, workspace and limits, and why a
//! backend cannot start. Exits 0 whether or not a device is present.
//!
//! `echothigh devices calibrate --device NAME --out FILE`: the trainee
//! touches four landmarks of the thigh with the probe, pressing the clutch
//! button on each; the fitted device → leg placement is written as a
//! `--hardware` file.

use anyhow::{Context, Result};
use echothigh_devices_hw::{probe_all, BackendReport, HardwareConfig};

/// Arguments of `echothigh devices`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the report as JSON (one array, one object per backend).
    #[arg(long)]
    json: bool,
    /// Calibrate a device instead of listing them.
    #[command(subcommand)]
    action: Option<Action>,
}

/// What `devices` does besides listing.
#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Touch four landmarks of the thigh with the probe (clutch button on
    /// each, held still 0.3 s) and write the device's placement.
    Calibrate(super::calibrate_device::Args),
}

/// Probes every backend and prints the report.
pub fn run(args: Args) -> Result<()> {
    if let Some(Action::Calibrate(a)) = args.action {
        return super::calibrate_device::run(a);
    }
    let reports = probe_all(&HardwareConfig::default());
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&reports).context("serialising the device report")?
        );
    } else {
        for r in &reports {
            print_text(r);
        }
    }
    Ok(())
}

fn print_text(r: &BackendReport) {
    let env = match &r.env_value {
        Some(v) => format!("{}={v}", r.env_var),
        None => format!("{} unset", r.env_var),
    };
    let state = if !r.devices.is_empty() {
        "ready"
    } else if r.service_reachable == Some(false) {
        "service unreachable"
    } else if r.service_reachable == Some(true) {
        "service reachable, no device"
    } else if r.found {
        "library found, no device"
    } else {
        "absent"
    };
    println!("{} ({}): {state}", r.backend, r.sdk);
    if r.service_reachable.is_some() {
        println!("  service: {} ({env})", r.library);
    } else {
        println!("  library: {} ({env})", r.library);
    }
    for d in &r.devices {
        let l = &d.limits;
        println!(
            "  device: {}: peak {} N, continuous {} N, stiffness {} N/m ({}); orientation {}; servo {} Hz; watchdog: {}",
            d.model,
            l.peak_force,
            l.continuous_force,
            l.max_stiffness,
            l.source,
            if d.orientation_sensed { "sensed" } else { "not sensed" },
            d.servo_rate,
            d.watchdog
        );
        if let (Some(lo), Some(hi)) = (d.workspace_min, d.workspace_max) {
            println!("  workspace (m, device frame): {lo:?} .. {hi:?}");
        }
    }
    if let Some(reason) = &r.reason {
        println!("  reason: {reason}");
    }
}
