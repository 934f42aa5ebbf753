//! `echothigh image`: B-mode frames of the thigh section under a static
//! press of the flat probe, one frame or a sweep of forces for every vein
//! state with a contact sheet.
//!
//! Until the runtime feeds the physical model's deformation, the press is a
//! flat indentation whose depth follows [`indentation_for_force`].

use anyhow::{Context, Result};
use echothigh_imaging::{
    contact_sheet, write_gray_png, FrameInput, ImagingConfig, Renderer, SectionDeformation,
    VeinState,
};
use std::path::{Path, PathBuf};

/// Arguments of `echothigh image`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Probe force (N) for a single frame.
    #[arg(long, default_value_t = 10.0)]
    pub force: f64,
    /// Vein state: healthy, acute or chronic.
    #[arg(long, default_value = "healthy", value_parser = parse_vein)]
    pub vein: VeinState,
    /// Output PNG file (single frame) or directory (with --sweep).
    #[arg(long)]
    pub out: PathBuf,
    /// Scatterer seed (overrides the configuration's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Time (s), for the arterial pulse.
    #[arg(long, default_value_t = 0.0)]
    pub time: f64,
    /// Render every vein state at each of --forces, plus a contact sheet.
    #[arg(long)]
    pub sweep: bool,
    /// Forces of the sweep (N), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0,2,5,10,15")]
    pub forces: Vec<f64>,
    /// Scenario TOML file whose `[imaging]` section configures the image.
    #[arg(long)]
    pub config: Option<PathBuf>,
}

fn parse_vein(s: &str) -> Result<VeinState, String> {
    s.parse()
        .map_err(|e: echothigh_imaging::ImagingError| e.to_string())
}

/// Initial stiffness of the tissue under the flat probe (N/m): 0.5 N/mm.
const INITIAL_STIFFNESS: f64 = 500.0;
/// Indentation at which the tissue under the probe becomes rigid (m).
const MAX_INDENTATION: f64 = 0.030;

/// Indentation (m) of the flat probe under the force `force` (N), from the
/// paper's nonlinear normal spring `f(x) = x / (a x + b)` (§3) written for
/// a compression `δ = −x`: `F = δ / (b − a δ)`, so `δ = F b / (1 + F a)`,
/// with `b = 1 / k₀` (`k₀` = 0.5 N/mm initial stiffness) and `b / a` = 30 mm
/// (the asymptote). It passes through the DESIGN.md §2 band: 0.5 N/mm at
/// first, 15 N at 15 mm. A stand-in until the physical model drives the image.
pub fn indentation_for_force(force: f64) -> f64 {
    let f = force.max(0.0);
    let b = 1.0 / INITIAL_STIFFNESS;
    let a = b / MAX_INDENTATION;
    f * b / (1.0 + f * a)
}

fn load_config(args: &Args) -> Result<ImagingConfig> {
    let mut cfg = match &args.config {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let doc: toml::Table =
                toml::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
            match doc.get("imaging") {
                Some(v) => v
                    .clone()
                    .try_into()
                    .with_context(|| format!("[imaging] in {}", path.display()))?,
                None => ImagingConfig::default(),
            }
        }
        None => ImagingConfig::default(),
    };
    if let Some(seed) = args.seed {
        cfg.seed = seed;
    }
    cfg.validate("imaging")?;
    Ok(cfg)
}

/// Renders one frame at `force` (N); returns the frame and the vein and
/// artery lumen areas relative to rest.
fn render_at(renderer: &mut Renderer, force: f64, time: f64) -> Result<(Vec<u8>, f64, f64)> {
    anyhow::ensure!(
        force.is_finite() && force >= 0.0,
        "--force must be finite and >= 0, got {force}"
    );
    let cfg = renderer.config().clone();
    let bone = renderer
        .anatomy()
        .map(|a| a.femur_top())
        .context("renderer without anatomy")?;
    let press = SectionDeformation::flat_press(
        indentation_for_force(force),
        cfg.probe_width,
        1.5e-3,
        bone,
    )?;
    let input = FrameInput {
        deformation: &press,
        probe_pressure: force / cfg.probe_area(),
        time,
    };
    let frame = renderer.render(&input)?;
    let l = renderer
        .lumens(&input)?
        .context("renderer without anatomy")?;
    Ok((
        frame,
        l.vein.area / l.vein.rest_area,
        l.artery.area / l.artery.rest_area,
    ))
}

fn write(path: &Path, cfg: &ImagingConfig, frame: &[u8]) -> Result<()> {
    write_gray_png(path, cfg.columns, cfg.rows, frame)?;
    Ok(())
}

/// Runs `echothigh image`.
pub fn run(args: Args) -> Result<()> {
    let cfg = load_config(&args)?;
    if !args.sweep {
        let mut r = Renderer::new(&cfg, args.vein)?;
        let (frame, vein, artery) = render_at(&mut r, args.force, args.time)?;
        write(&args.out, &cfg, &frame)?;
        println!(
            "{}: {} vein at {:.1} N (indentation {:.1} mm): vein lumen {:.0} % of rest, artery {:.0} %",
            args.out.display(),
            args.vein.name(),
            args.force,
            indentation_for_force(args.force) * 1e3,
            vein * 100.0,
            artery * 100.0
        );
        return Ok(());
    }
    anyhow::ensure!(!args.forces.is_empty(), "--forces is empty");
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut frames = Vec::new();
    println!("state,force_N,indentation_mm,vein_lumen_ratio,artery_lumen_ratio,file");
    for state in VeinState::ALL {
        let mut r = Renderer::new(&cfg, state)?;
        for &force in &args.forces {
            let (frame, vein, artery) = render_at(&mut r, force, args.time)?;
            let path = args
                .out
                .join(format!("{}_{:04.1}N.png", state.name(), force));
            write(&path, &cfg, &frame)?;
            println!(
                "{},{force},{:.2},{vein:.3},{artery:.3},{}",
                state.name(),
                indentation_for_force(force) * 1e3,
                path.display()
            );
            frames.push(frame);
        }
    }
    let refs: Vec<&[u8]> = frames.iter().map(|f| f.as_slice()).collect();
    let rows: Vec<String> = VeinState::ALL
        .iter()
        .map(|s| s.name().to_string())
        .collect();
    let cols: Vec<String> = args.forces.iter().map(|f| format!("{f} N")).collect();
    let rows: Vec<&str> = rows.iter().map(|s| s.as_str()).collect();
    let cols: Vec<&str> = cols.iter().map(|s| s.as_str()).collect();
    let sheet = contact_sheet(&refs, cfg.columns, cfg.rows, &rows, &cols)?;
    let path = args.out.join("contact_sheet.png");
    write_gray_png(&path, sheet.width, sheet.height, &sheet.pixels)?;
    println!("contact sheet: {}", path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indentation_law_is_in_the_design_band() {
        // Initial stiffness 0.5 N/mm (finite difference at 0).
        let k0 = 1e-3 / indentation_for_force(1e-3);
        assert!((k0 - 500.0).abs() < 1.0, "{k0}");
        let d15 = indentation_for_force(15.0);
        assert!((d15 - 0.015).abs() < 1e-12, "{d15}");
        assert!(indentation_for_force(1e6) < MAX_INDENTATION);
        assert_eq!(indentation_for_force(-1.0), 0.0);
    }
}
