//! `echothigh calibrate --data FILE.csv [--out PLOT.png]`: fits the tissue
//! springs to a force–indentation curve (Levenberg–Marquardt over the
//! simulated indentation experiment), prints the fitted parameters and the
//! residual, and plots data against model.

use anyhow::{Context, Result};
use echothigh_contact::calibration::{calibrate, Calibration, FitParameter, IndentationCurve};
use echothigh_experiments::plot::{Figure, Panel, Series, PALETTE};
use std::path::{Path, PathBuf};

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
    #[arg(long, value_delimiter = ',', default_value = "normal_b,asymptote")]
    fit: Vec<String>,
    /// Physics step of the simulated experiment (s), in [1e-3, 0.1]: the
    /// experiment is quasi-static (5 mm/s), so 1 ms already resolves it, and
    /// the bound keeps an experiment to at most ~2e4 steps (each step
    /// allocates nothing, but the fit runs dozens of experiments).
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

/// Checks up front, before a fit of several seconds, that the plot can be
/// written: its directory exists and the file can be created (a file that
/// did not exist is removed again).
fn check_writable(out: &Path) -> Result<()> {
    let existed = out.exists();
    if out.is_dir() {
        anyhow::bail!(
            "--out {} is a directory; give a .png file name",
            out.display()
        );
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(out)
        .with_context(|| format!("--out {}: cannot write the plot there", out.display()))?;
    if !existed {
        // Only a probe; the plot is written after the fit.
        let _ = std::fs::remove_file(out);
    }
    Ok(())
}

/// Refuses data deeper than the tissue up front: the probe would press
/// through `thigh.tissue_thickness` (past the normal springs' asymptote
/// and onto the femur), which no parameter can fit, and each simulated
/// experiment would run `depth / (rate · time_step)` steps in vain (a
/// 200 mm row ran for minutes).
fn check_depths(data: &IndentationCurve, cal: &Calibration, path: &Path) -> Result<()> {
    let thickness = cal.model.thigh.tissue_thickness;
    if let Some((row, d)) = data
        .depth
        .iter()
        .enumerate()
        .find(|(_, d)| **d >= thickness)
    {
        anyhow::bail!(
            "{}: data row {} has depth {:.1} mm, at or past the tissue's thickness \
             (thigh.tissue_thickness = {:.1} mm): the probe would reach the femur",
            path.display(),
            row + 1,
            d * 1e3,
            thickness * 1e3
        );
    }
    Ok(())
}

/// Runs the calibration.
pub fn run(args: Args) -> Result<()> {
    anyhow::ensure!(
        (1e-3..=0.1).contains(&args.time_step),
        "--time-step must be in [0.001, 0.1] s (a quasi-static experiment), got {}",
        args.time_step
    );
    if let Some(out) = &args.out {
        check_writable(out)?;
    }
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
    check_depths(&data, &cal, &args.data)?;
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
