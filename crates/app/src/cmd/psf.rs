//! `echothigh psf`: the point spread function of the configured probe,
//! measured on the standard point phantom (points on the axis at 10, 20, 30
//! and 40 mm) rendered by the imaging pipeline: axial and lateral FWHM per
//! depth, the peak echo before attenuation and TGC (focal gain) and the
//! side-lobe / edge-wave pedestal.

use anyhow::{Context, Result};
use echothigh_imaging::measure_psf;
use echothigh_runtime::scenario::Scenario;
use std::path::PathBuf;

/// Arguments of `echothigh psf`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the report as JSON (otherwise a table).
    #[arg(long)]
    pub json: bool,
    /// Transmit focus (mm), overriding `imaging.beam.transmit_focus`.
    #[arg(long)]
    pub focus_mm: Option<f64>,
    /// Scenario TOML file (its `[imaging]` section applies).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Also write the JSON report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `echothigh psf`.
pub fn run(args: Args) -> Result<()> {
    let scenario = Scenario::load(args.config.as_deref())?;
    let mut cfg = scenario.imaging_config();
    if let Some(f) = args.focus_mm {
        cfg.beam.transmit_focus = f * 1e-3;
    }
    cfg.validate("imaging")?;
    let report = measure_psf(&cfg)?;
    let json = serde_json::json!({
        "columns": cfg.columns,
        "rows": cfg.rows,
        "pixel_width_m": cfg.pixel_width(),
        "pixel_depth_m": cfg.pixel_depth(),
        "center_frequency_hz": cfg.center_frequency,
        "beam": cfg.beam,
        "psf": report,
    });
    let text = serde_json::to_string_pretty(&json)?;
    if args.json {
        println!("{text}");
    } else {
        println!(
            "transmit focus {:.1} mm, focal gain {:.1} dB",
            report.transmit_focus_m * 1e3,
            report.focal_gain_db
        );
        println!("depth_mm  axial_mm  lateral_mm  peak_dB  side_lobe_dB");
        for p in &report.depths {
            println!(
                "{:8.1}  {:8.3}  {:10.3}  {:7.1}  {:12.1}",
                p.depth_m * 1e3,
                p.axial_fwhm_m * 1e3,
                p.lateral_fwhm_m * 1e3,
                p.peak_db,
                p.side_lobe_db
            );
        }
    }
    if let Some(path) = &args.out {
        std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
