//! `echothigh devices calibrate`: places a real device relative to the
//! leg by touching landmarks (`echothigh_devices_hw::landmarks`), and
//! writes the result as a `--hardware` file for `run` and `haptic-client`.

use super::device_arg::DeviceArgs;
use super::run::load_scenario;
use anyhow::{bail, Context, Result};
use echothigh_devices_hw::{
    capture_landmarks, open_hardware, CaptureConfig, CaptureEvent, HardwareConfig, Landmark, Vec3,
};
use echothigh_model::{LegSurface, ThighGeometry};
use echothigh_runtime::signals::stop_on_signals;
use std::path::PathBuf;

/// Arguments of `echothigh devices calibrate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The device (`openhaptics` or `forcedimension`) and its settings.
    #[command(flatten)]
    device: DeviceArgs,
    /// Scenario whose thigh is touched (default: the built-in one).
    #[arg(long)]
    scenario: Option<PathBuf>,
    /// Where to write the settings with the fitted placement (TOML, for
    /// `--hardware`); an existing file is not overwritten.
    #[arg(long)]
    out: PathBuf,
    /// Seconds to wait for each landmark.
    #[arg(long, default_value_t = 120.0)]
    timeout: f64,
}

/// Four landmarks on the scenario's thigh, not collinear: the top at
/// mid-thigh (z = 0), `dz` towards the groin and the knee of it (10 cm, or
/// less on a short thigh), and the lateral side at mid-thigh. On the
/// elliptic cylinder (semi-axes `a` lateral, `b` anterior, m) they are
/// `(0, b, 0)`, `(0, b, ±dz)`, `(a, 0, 0)`; on a patient's leg
/// (`thigh.patient`) the skin points of the model's mesh there.
pub fn thigh_landmarks(thigh: &ThighGeometry) -> Result<Vec<Landmark>> {
    let dz = (0.5 * thigh.length - 0.03).clamp(0.02, 0.1);
    let leg = LegSurface::new(thigh, "thigh").map_err(anyhow::Error::msg)?;
    // Model ring angles: π/2 anterior (the top), 0 lateral.
    let at = |theta: f64, z: f64| -> Vec3 {
        match &leg {
            Some(l) => l.node(theta, z).position,
            None => Vec3::new(
                thigh.semi_axis_x * theta.cos(),
                thigh.semi_axis_y * theta.sin(),
                z,
            ),
        }
    };
    let top = std::f64::consts::FRAC_PI_2;
    let cm = dz * 100.0;
    Ok([
        (
            "the top of the thigh at mid-thigh".to_string(),
            at(top, 0.0),
        ),
        (
            format!("the top of the thigh, {cm:.0} cm towards the groin"),
            at(top, dz),
        ),
        (
            format!("the top of the thigh, {cm:.0} cm towards the knee"),
            at(top, -dz),
        ),
        (
            "the outer (lateral) side at mid-thigh".to_string(),
            at(0.0, 0.0),
        ),
    ]
    .into_iter()
    .map(|(name, leg)| Landmark { name, leg })
    .collect())
}

/// Runs the calibration.
pub fn run(args: Args) -> Result<()> {
    let Some(kind) = args.device.device.and_then(|d| d.kind()) else {
        bail!("calibrate needs a real device: --device openhaptics|forcedimension|haply")
    };
    if args.out.exists() {
        bail!(
            "{} exists: choose another --out (nothing was overwritten)",
            args.out.display()
        );
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!(
            "--timeout must be a positive number of seconds, got {}",
            args.timeout
        );
    }
    let scenario = load_scenario(args.scenario.as_deref(), None, None)?;
    let mut config = match &args.device.hardware {
        None => HardwareConfig::default(),
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            toml::from_str(&text).with_context(|| format!("{}", path.display()))?
        }
    };
    let mut device = open_hardware(kind, &config).with_context(|| {
        format!("opening the {kind} device (`echothigh devices` lists what is installed)")
    })?;
    let landmarks = thigh_landmarks(&scenario.thigh)?;
    let capture = CaptureConfig {
        timeout: args.timeout,
        ..CaptureConfig::default()
    };
    let stop = stop_on_signals()?;
    let (_, fit) = capture_landmarks(&mut device, &landmarks, &capture, &stop, |ev| match ev {
        CaptureEvent::Touch {
            landmark,
            index,
            total,
        } => eprintln!(
            "({index}/{total}) touch {} with the probe, then press and hold the clutch button",
            landmark.name
        ),
        CaptureEvent::Moved { motion, .. } => eprintln!(
            "  the probe moved {:.1} mm while held: hold it still and press again",
            motion * 1e3
        ),
        CaptureEvent::Captured { .. } => eprintln!("  captured: release the button"),
    })
    .context("calibrating")?;
    config.calibration = fit.transform;
    let text = format!(
        "# echothigh devices calibrate --device {kind}: four landmarks, RMS residual \
         {:.2} mm, largest {:.2} mm\n{}",
        fit.rms_residual * 1e3,
        fit.max_residual * 1e3,
        toml::to_string(&config).context("serializing the settings")?
    );
    std::fs::write(&args.out, text).with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "placement written to {} (RMS residual {:.2} mm): pass it as --hardware",
        args.out.display(),
        fit.rms_residual * 1e3
    );
    Ok(())
}
