//! `echothigh calibrate --data FILE.csv [--out PLOT.png]`: fits the tissue
//! springs to a force–indentation curve (Levenberg–Marquardt over the
//! simulated indentation experiment), prints the fitted parameters and the
//! residual, and plots data against model.

use anyhow::{Context, Result};
use echothigh_contact::calibration::{calibrate, Calibration, FitParameter, IndentationCurve};
use echothigh_experiments::plot::{Figure, Panel, Series, PALETTE};
use std::path::PathBuf;

/// Arguments of `echothigh calibrate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Force–indentation CSV (`depth_mm,force_n`; see data/indentation-default.md).
    #[arg(long, default_value = "data/indentation-default.csv")]
    data: PathBuf,
    /// PNG plot of data against the fitted model.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Parameters to fit: any of normal_a, normal_b, asymptote (the normal
    /// springs' asymptote as a fraction of the tissue thickness),
    /// structural_stiffness, tangential_stiffness (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "normal_b,asymptote,structural_stiffness"
    )]
    fit: Vec<String>,
    /// Physics step of the simulated experiment (s).
    #[arg(long, default_value_t = 0.05)]
    time_step: f64,
}

fn parameter(name: &str) -> Result<FitParameter> {
    Ok(match name.trim() {
        "normal_a" => FitParameter::NormalA,
        "normal_b" => FitParameter::NormalB,
        "structural_stiffness" => FitParameter::StructuralStiffness,
        "tangential_stiffness" => FitParameter::TangentialStiffness,
        "asymptote" => FitParameter::Asymptote,
        other => anyhow::bail!(
            "--fit: unknown parameter `{other}` (expected normal_a, normal_b, asymptote, \
             structural_stiffness or tangential_stiffness)"
        ),
    })
}

/// Runs the calibration.
pub fn run(args: Args) -> Result<()> {
    anyhow::ensure!(
        args.time_step.is_finite() && args.time_step > 0.0,
        "--time-step must be a positive number of seconds, got {}",
        args.time_step
    );
    let data = IndentationCurve::from_path(&args.data)
        .with_context(|| format!("reading {}", args.data.display()))?;
    let mut cal = Calibration {
        parameters: args
            .fit
            .iter()
            .map(|s| parameter(s))
            .collect::<Result<_>>()?,
        ..Calibration::default()
    };
    cal.experiment.time_step = args.time_step;
    println!(
        "fitting {} to {} points of {} ({} nodes)",
        cal.parameters
            .iter()
            .map(|p| p.key())
            .collect::<Vec<_>>()
            .join(", "),
        data.depth.len(),
        args.data.display(),
        cal.model.thigh.node_count()
    );
    for p in &cal.parameters {
        println!("  start {:<28} = {:.6e}", p.key(), p.value(&cal.model));
    }
    let rep = calibrate(&cal, &data).context("calibration")?;
    for (p, v) in &rep.fitted {
        println!("  fit   {:<28} = {:.6e}", p.key(), v);
    }
    let t = &rep.tissue;
    println!(
        "tissue: normal_a = {:.6e} m²/N, normal_b = {:.6e} m³/N, structural_stiffness = {:.4} N/m, \
         tangential_stiffness = {:.4e} N/m³",
        t.normal_a, t.normal_b, t.structural_stiffness, t.tangential_stiffness
    );
    println!(
        "residual: rms {:.4} N, max {:.4} N ({} iterations, {} experiments, {:?})",
        rep.rms, rep.max_abs, rep.iterations, rep.evaluations, rep.termination
    );
    println!(
        "initial stiffness per area 1/normal_b = {:.4e} N/m³, asymptote normal_b/normal_a = {:.2} mm",
        1.0 / rep.tissue.normal_b,
        1e3 * rep.tissue.asymptote()
    );
    if let Some(out) = &args.out {
        let data_pts = data
            .depth
            .iter()
            .zip(&data.force)
            .map(|(d, f)| (d * 1e3, *f))
            .collect();
        let model_pts = rep
            .model_curve
            .depth
            .iter()
            .zip(&rep.model_curve.force)
            .map(|(d, f)| (d * 1e3, *f))
            .collect();
        let fig = Figure::new(vec![Panel {
            title: format!(
                "Indentation, 40×10 mm probe: data vs fitted model (rms {:.3} N)",
                rep.rms
            ),
            x_label: "depth (mm)".into(),
            y_label: "force (N)".into(),
            series: vec![
                Series::line("data", data_pts, PALETTE[0]).with_markers(),
                Series::line("model", model_pts, PALETTE[1]),
            ],
            ..Panel::default()
        }]);
        fig.save_png(out)?;
        println!("wrote {}", out.display());
    }
    Ok(())
}
