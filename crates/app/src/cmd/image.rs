//! `echothigh image`: B-mode frames of the thigh section under a static
//! press of the flat probe, one frame or a sweep of forces for every vein
//! state with a contact sheet.
//!
//! The press is computed on the physical model: the probe is pressed into
//! the thigh until the quasi-static contact force reaches the requested
//! force, and the skin displacement under it is carried into the image
//! (`runtime::section`), so the image and the force agree.
//!
//! `--phantom points|speckle|cyst` renders a standard test phantom through
//! the same pipeline instead (points on the axis at 10, 20, 30 and 40 mm;
//! fully developed speckle; an 8 mm anechoic cyst at 20 mm in speckle).

use super::image_site;
use anyhow::{Context, Result};
use echothigh_imaging::{
    axis_column, write_gray_png, Anatomy, FrameInput, ImagingConfig, Phantom, Renderer,
    SectionDeformation, VeinState, POINT_DEPTHS,
};
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::section::{press_to_force, StaticPress};
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
    /// Distance (m) along the skin from the vessels' line to the probe,
    /// positive along the image's lateral axis: the anatomy pans by minus
    /// this in the image (clamped to `imaging.pan_range`). The press itself
    /// stays at the exam site (the thigh is laterally uniform there).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub lateral: f64,
    /// Render every vein state at each of --forces, plus a contact sheet.
    #[arg(long)]
    pub sweep: bool,
    /// Forces of the sweep (N), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0,2,5,10,15")]
    pub forces: Vec<f64>,
    /// Scenario TOML file (its `[imaging]`, `[patient]`, tissue and probe
    /// sections apply).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Patient of the 3D leg (a preset: lean-male, average-female, obese, or
    /// a patient TOML file): with --at or --site, the image's vessels,
    /// layers and femur come from the leg's section there. Default lean-male.
    #[arg(long)]
    pub patient: Option<String>,
    /// Probe position on the 3D leg: mm below the inguinal ligament.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<f64>,
    /// Angle around the leg (degrees from the anterior line, + medial);
    /// default: centred over the deep vein at that level. Only with --at.
    #[arg(long, allow_hyphen_values = true)]
    pub angle: Option<f64>,
    /// Named exam site on the 3D leg: cfv, sfj, fv-proximal, fv-mid,
    /// fv-distal, popliteal (a level and a probe angle).
    #[arg(long)]
    pub site: Option<String>,
    /// A case (a shipped case's name, `echothigh cases list`, or a case TOML
    /// file): its patient and thrombus segments; with --at or --site, each
    /// vein of the section drawn in its segment's state there (instead of
    /// --vein). Not with --patient.
    #[arg(long, conflicts_with = "patient")]
    pub case: Option<String>,
    /// Render a test phantom instead of the thigh: points, speckle or cyst.
    #[arg(long, value_enum)]
    pub phantom: Option<PhantomKind>,
    /// Colour flow over the B-mode frame (issue 17): `color` (velocity,
    /// towards red, away blue) or `power`; an RGB PNG. Needs the leg
    /// (--case or --patient with --at or --site), one frame.
    #[arg(long, value_enum)]
    pub doppler: Option<super::doppler_color::DopplerMode>,
    /// Probe tilt on the leg (degrees, + aims distally). A transverse
    /// plane sees the flow through it at 90°, hence no Doppler shift: the
    /// beam needs a tilt. Default 0, or 20 with --doppler.
    #[arg(long, allow_hyphen_values = true)]
    pub tilt: Option<f64>,
    /// Colour gain (dB) with --doppler.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub color_gain: f64,
}

/// The standard test phantoms of `--phantom`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhantomKind {
    /// Point scatterers on the axis at 10, 20, 30 and 40 mm.
    Points,
    /// Fully developed speckle (a uniform medium).
    Speckle,
    /// An 8 mm anechoic cyst at 20 mm in speckle.
    Cyst,
}

/// Renders the phantom `kind` of `cfg` (at rest, no anatomy).
fn render_phantom(cfg: &ImagingConfig, kind: PhantomKind) -> Result<Vec<u8>> {
    let (density, seed) = (cfg.scatterer_density, cfg.seed);
    let phantom = match kind {
        PhantomKind::Points => Phantom::Points(
            POINT_DEPTHS
                .iter()
                .map(|&d| (axis_column(cfg), d))
                .collect(),
        ),
        PhantomKind::Speckle => Phantom::Uniform { density, seed },
        PhantomKind::Cyst => Phantom::Cyst {
            density,
            seed,
            depth: 0.020,
            radius: 0.004,
        },
    };
    let mut r = Renderer::phantom(cfg, &phantom)?;
    let rest = SectionDeformation::rest(1.0);
    Ok(r.render(&FrameInput {
        deformation: &rest,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    })?)
}

fn parse_vein(s: &str) -> Result<VeinState, String> {
    s.parse()
        .map_err(|e: echothigh_imaging::ImagingError| e.to_string())
}

fn load_scenario(args: &Args) -> Result<Scenario> {
    let mut s = Scenario::load(args.config.as_deref())?;
    if let Some(seed) = args.seed {
        s.imaging.seed = seed;
    }
    s.validate()?;
    Ok(s)
}

/// Renders one frame of the static `press`; returns the frame and the vein
/// and artery lumen areas relative to rest.
fn render_at(
    renderer: &mut Renderer,
    press: &StaticPress,
    face_area: f64,
    time: f64,
    lateral: f64,
) -> Result<(Vec<u8>, f64, f64)> {
    let input = FrameInput {
        deformation: &press.deformation,
        probe_pressure: press.force / face_area,
        time,
        lateral_offset: lateral,
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

/// Presses the physical model to each force (ascending, continuing from the
/// previous press).
fn presses(s: &Scenario, forces: &[f64], bone: f64) -> Result<Vec<StaticPress>> {
    let mut order: Vec<usize> = (0..forces.len()).collect();
    order.sort_by(|&a, &b| forces[a].total_cmp(&forces[b]));
    let mut physics = PhysicsSide::new(s)?;
    let mut out: Vec<Option<StaticPress>> = vec![None; forces.len()];
    for i in order {
        out[i] = Some(
            press_to_force(&mut physics, s, forces[i], bone)
                .with_context(|| format!("pressing to {} N", forces[i]))?,
        );
    }
    Ok(out.into_iter().flatten().collect())
}

fn write(path: &Path, cfg: &ImagingConfig, frame: &[u8]) -> Result<()> {
    write_gray_png(path, cfg.columns, cfg.rows, frame)?;
    Ok(())
}

/// Runs `echothigh image`.
pub fn run(args: Args) -> Result<()> {
    let scenario = load_scenario(&args)?;
    let mut cfg = scenario.imaging_config();
    let case = args
        .case
        .as_deref()
        .map(super::cases::load_case)
        .transpose()?;
    let mut on_leg = None;
    if case.is_some()
        || args.patient.is_some()
        || args.at.is_some()
        || args.site.is_some()
        || args.angle.is_some()
    {
        let (patient, mut placement) = match &case {
            Some(c) => (
                c.name().to_string(),
                image_site::place_on(c.anatomy.clone(), args.at, args.angle, args.site.as_deref())?,
            ),
            None => {
                let patient = args.patient.as_deref().unwrap_or("lean-male");
                let at = image_site::place(patient, args.at, args.angle, args.site.as_deref())?;
                (patient.to_string(), at)
            }
        };
        let tilt = args
            .tilt
            .unwrap_or(if args.doppler.is_some() { 20.0 } else { 0.0 });
        anyhow::ensure!(
            tilt.is_finite() && tilt.abs() <= 60.0,
            "--tilt must be within ±60 degrees, got {tilt}"
        );
        placement.pose.tilt = tilt.to_radians();
        cfg.anatomy = match &case {
            Some(c) => image_site::case_section_anatomy(&cfg.anatomy, &placement, &c.thrombi)?,
            None => image_site::section_anatomy(&cfg.anatomy, &placement)?,
        };
        if let Some(c) = &case {
            let vein = placement.anatomy.deep_vein_at(placement.pose.s);
            let st = c.thrombi.state(vein, placement.pose.s);
            println!(
                "case {}: {} at s = {:.1} mm: thrombus fills {:.0} % of the lumen (smallest lumen {:.0} % of rest)",
                c.name(),
                vein.as_str(),
                placement.pose.s * 1e3,
                st.fill * 100.0,
                st.min_lumen_ratio() * 100.0
            );
        }
        println!(
            "patient {patient}, s = {:.1} mm, angle {:.1}°: {} {:.1} mm deep, {:.1} mm wide",
            placement.pose.s * 1e3,
            placement.pose.theta.to_degrees(),
            placement.anatomy.deep_vein_at(placement.pose.s).as_str(),
            cfg.anatomy.vein_depth * 1e3,
            cfg.anatomy.vein_diameter * 1e3
        );
        on_leg = Some(placement);
    }
    anyhow::ensure!(
        args.doppler.is_none() || (on_leg.is_some() && !args.sweep && args.phantom.is_none()),
        "--doppler needs the leg (--case, or --patient with --at or --site) and one frame (no --sweep or --phantom)"
    );
    let face_area = cfg.probe_area();
    anyhow::ensure!(
        args.lateral.is_finite(),
        "--lateral must be a finite distance in m, got {}",
        args.lateral
    );
    if let Some(kind) = args.phantom {
        anyhow::ensure!(!args.sweep, "--phantom renders one frame: drop --sweep");
        let frame = render_phantom(&cfg, kind)?;
        write(&args.out, &cfg, &frame)?;
        println!("{}: {kind:?} phantom", args.out.display());
        return Ok(());
    }
    let bone = Anatomy::new(&cfg.anatomy, VeinState::Healthy)?.femur_top();
    if !args.sweep {
        let press = presses(&scenario, &[args.force], bone)?.remove(0);
        let mut r = Renderer::new(&cfg, args.vein)?;
        let (frame, vein, artery) = render_at(&mut r, &press, face_area, args.time, args.lateral)?;
        match (args.doppler, &on_leg) {
            (Some(mode), Some(placement)) => {
                let thrombi = match &case {
                    Some(c) => c.thrombi.clone(),
                    None => echothigh_anatomy::Thrombi::new(&placement.anatomy, &[])?,
                };
                let section = placement.anatomy.section(&placement.pose)?;
                let inputs = super::doppler_color::ColorInputs {
                    anatomy: &placement.anatomy,
                    section: &section,
                    thrombi: &thrombi,
                    proximal_obstruction: case
                        .as_ref()
                        .is_some_and(|c| c.file.doppler.proximal_obstruction),
                    imaging_anatomy: &cfg.anatomy,
                };
                let input = FrameInput {
                    deformation: &press.deformation,
                    probe_pressure: press.force / face_area,
                    time: args.time,
                    lateral_offset: args.lateral,
                };
                let n = super::doppler_color::write_color(
                    &args.out,
                    mode,
                    args.color_gain,
                    &inputs,
                    &r,
                    &input,
                    &frame,
                )?;
                println!(
                    "{}: {mode:?} Doppler, {n} coloured pixels",
                    args.out.display()
                );
            }
            _ => write(&args.out, &cfg, &frame)?,
        }
        println!(
            "{}: {} vein at {:.1} N (indentation {:.1} mm): vein lumen {:.0} % of rest, artery {:.0} %",
            args.out.display(),
            if case.is_some() { "case" } else { args.vein.name() },
            press.force,
            press.indentation * 1e3,
            vein * 100.0,
            artery * 100.0
        );
        return Ok(());
    }
    anyhow::ensure!(!args.forces.is_empty(), "--forces is empty");
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let pressed = presses(&scenario, &args.forces, bone)?;
    let mut frames = Vec::new();
    println!("state,force_N,indentation_mm,vein_lumen_ratio,artery_lumen_ratio,file");
    for state in VeinState::ALL {
        let mut r = Renderer::new(&cfg, state)?;
        for (press, &force) in pressed.iter().zip(&args.forces) {
            let (frame, vein, artery) =
                render_at(&mut r, press, face_area, args.time, args.lateral)?;
            let path = args
                .out
                .join(format!("{}_{:04.1}N.png", state.name(), force));
            write(&path, &cfg, &frame)?;
            println!(
                "{},{:.2},{:.2},{vein:.3},{artery:.3},{}",
                state.name(),
                press.force,
                press.indentation * 1e3,
                path.display()
            );
            frames.push(frame);
        }
    }
    let refs: Vec<&[u8]> = frames.iter().map(|f| f.as_slice()).collect();
    let rows: Vec<&str> = VeinState::ALL.iter().map(|s| s.name()).collect();
    let cols: Vec<String> = args.forces.iter().map(|f| format!("{f} N")).collect();
    let cols: Vec<&str> = cols.iter().map(|s| s.as_str()).collect();
    let sheet =
        echothigh_experiments::sheet::contact_sheet(&refs, cfg.columns, cfg.rows, &rows, &cols)?;
    let path = args.out.join("contact_sheet.png");
    write_gray_png(&path, sheet.width, sheet.height, &sheet.pixels)?;
    println!("contact sheet: {}", path.display());
    Ok(())
}
