//! `echothigh bench image`: frame rate of the B-mode renderer at the
//! default size (512 × 864, `echothigh image`) and at the live viewer's
//! size (256 × 384, `[imaging] live_columns/live_rows`), the latter also
//! with the section of the 3D leg at `fv-proximal`, on one core (the
//! renderer is serial and allocation-free: the viewer renders on its own
//! imaging thread), under a press that varies every frame. Frame times are
//! the thread's CPU time (`cpu-time`), which the other processes sharing
//! the machine do not inflate, and wall time beside it.

use super::clock::thread_cpu_us;
use anyhow::{Context, Result};
use echothigh_anatomy::{ProbePose, Site};
use echothigh_imaging::{
    FrameInput, ImagingConfig, Renderer, SectionDeformation, StageTimes, VeinState,
};
use echothigh_model::LegSurface;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::section_follow::SectionImager;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `echothigh bench image`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the report as JSON (otherwise a short text summary).
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON report to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Frames timed (after 10 warm-up frames).
    #[arg(long, default_value_t = 300)]
    pub frames: usize,
    /// Time the Doppler paths instead (issue 17): colour frames at 256 ×
    /// 384 with B-mode, and PW spectral lines (10 × --frames lines).
    #[arg(long)]
    pub doppler: bool,
    /// Time only the live viewer's frames (the default scenario's leg
    /// through the section imager, at the groin and mid-thigh).
    #[arg(long)]
    pub live: bool,
}

/// Percentiles of frame times (s).
#[derive(Debug, serde::Serialize)]
struct Timing {
    threads: usize,
    frames: usize,
    median_s: f64,
    p90_s: f64,
    p99_s: f64,
    max_s: f64,
    fps_median: f64,
    fps_mean: f64,
}

fn timing(mut t: Vec<f64>, threads: usize) -> Timing {
    let total: f64 = t.iter().sum();
    t.sort_by(f64::total_cmp);
    let q = |p: f64| t[((t.len() - 1) as f64 * p).round() as usize];
    Timing {
        threads,
        frames: t.len(),
        median_s: q(0.5),
        p90_s: q(0.9),
        p99_s: q(0.99),
        max_s: q(1.0),
        fps_median: 1.0 / q(0.5),
        fps_mean: t.len() as f64 / total,
    }
}

/// The calling thread's CPU time (s): the renderer's stage clock here.
fn thread_cpu_s() -> f64 {
    thread_cpu_us() * 1e-6
}

/// Median thread-CPU time (s) of each stage over the timed frames.
fn stage_medians(stages: &[StageTimes]) -> serde_json::Value {
    let median = |f: fn(&StageTimes) -> f64| {
        let mut v: Vec<f64> = stages.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[(v.len() - 1) / 2]
    };
    serde_json::json!({
        "prepare": median(|s| s.prepare),
        "splat": median(|s| s.splat),
        "convolve": median(|s| s.convolve),
        "loss": median(|s| s.loss),
        "echoes": median(|s| s.echoes),
        "compress": median(|s| s.compress),
        "transpose": median(|s| s.transpose),
    })
}

/// Renders `frames` frames (after 10 warm-up ones); returns the thread-CPU
/// and wall times of each (s), and the median thread-CPU time of each
/// stage (s, [`Renderer::stage_times`]).
fn run_frames(
    r: &mut Renderer,
    presses: &[SectionDeformation],
    frames: usize,
) -> Result<(Vec<f64>, Vec<f64>, serde_json::Value)> {
    r.set_stage_clock(thread_cpu_s);
    let mut stages = Vec::with_capacity(frames);
    let (w, h) = r.frame_size();
    let mut out = vec![0u8; w * h];
    let mut cpu = Vec::with_capacity(frames);
    let mut wall = Vec::with_capacity(frames);
    for k in 0..frames + 10 {
        let d = &presses[k % presses.len()];
        let force = 10.0 * d.face_depth(0.02) / 0.012;
        let input = FrameInput {
            deformation: d,
            probe_pressure: force / r.config().probe_area(),
            time: k as f64 / 60.0,
            lateral_offset: 0.0,
        };
        let (t0, c0) = (Instant::now(), thread_cpu_us());
        r.render_into(&input, &mut out)?;
        let (c1, dt) = (thread_cpu_us(), t0.elapsed().as_secs_f64());
        if k >= 10 {
            cpu.push((c1 - c0) * 1e-6);
            wall.push(dt);
            stages.push(r.stage_times());
        }
    }
    Ok((cpu, wall, stage_medians(&stages)))
}

/// Times one frame size; returns its JSON report.
fn bench_size(
    columns: usize,
    rows: usize,
    frames: usize,
    leg_site: Option<&str>,
) -> Result<serde_json::Value> {
    let mut cfg = ImagingConfig {
        columns,
        rows,
        ..Default::default()
    };
    if let Some(site) = leg_site {
        let p = crate::cmd::image_site::place("lean-male", None, None, Some(site))?;
        cfg.anatomy = crate::cmd::image_site::section_anatomy(&cfg.anatomy, &p)?;
    }
    let mut r = Renderer::new(&cfg, VeinState::Healthy)?;
    let bone = r.anatomy().context("anatomy")?.femur_top();
    // A press going from 2 to 14 mm and back over 60 frames.
    let presses: Vec<SectionDeformation> = (0..60)
        .map(|k| {
            let phase = k as f64 / 60.0 * std::f64::consts::TAU;
            let depth = 8e-3 - 6e-3 * phase.cos();
            SectionDeformation::flat_press(depth, cfg.probe_width, 1.5e-3, bone)
        })
        .collect::<Result<_, _>>()?;
    let (cpu, wall, stages) = run_frames(&mut r, &presses, frames)?;
    Ok(serde_json::json!({
        "columns": cfg.columns,
        "rows": cfg.rows,
        "width_m": cfg.width,
        "depth_m": cfg.depth,
        "anatomy": leg_site.map_or("mid-thigh pair (default)".to_string(), |s| {
            format!("3D leg, lean-male, site {s}")
        }),
        "vessels": r.anatomy().map_or(0, |a| a.vessels().len()),
        "scatterers": r.scatterer_count(),
        "axial_taps": r.axial_taps(),
        "one_core_thread_cpu": timing(cpu, 1),
        "one_core_wall": timing(wall, 1),
        "stage_thread_cpu_median_s": stages,
    }))
}

/// Times the live viewer's frame (issue 19): the default scenario's leg,
/// its live image settings (256 × 384, the depth a sonographer sets at the
/// level), the section drawn in material coordinates by the imaging
/// thread's [`SectionImager`] at `site`, under the same press.
fn bench_live(site: Option<Site>, frames: usize) -> Result<serde_json::Value> {
    let sc = Scenario::builtin()?;
    let leg = LegSurface::new(&sc.thigh, "thigh")?.context("the default scenario has no leg")?;
    let cfg = sc.live_imaging_config();
    // `None`: where a trainee first puts the probe on the page, anterior
    // mid-thigh (θ = 0.1 rad, 0.19 m below the ligament), off the vein, so
    // that the image reaches the femur (80 mm).
    let pose = site.map_or(ProbePose::transverse(0.19, 0.1), |s| {
        leg.anatomy().site_pose(s)
    });
    let mut im = SectionImager::new(leg, &cfg, VeinState::Healthy, pose)?;
    let r = im.renderer();
    let bone = r.anatomy().context("anatomy")?.femur_top();
    let (depth_m, width_m) = (r.config().depth, r.config().probe_width);
    let presses: Vec<SectionDeformation> = (0..60)
        .map(|k| {
            let phase = k as f64 / 60.0 * std::f64::consts::TAU;
            let depth = 8e-3 - 6e-3 * phase.cos();
            SectionDeformation::flat_press(depth, width_m, 1.5e-3, bone)
        })
        .collect::<Result<_, _>>()?;
    let (cpu, wall, stages) = run_frames(r, &presses, frames)?;
    let (columns, rows) = r.frame_size();
    Ok(serde_json::json!({
        "columns": columns,
        "rows": rows,
        "depth_m": depth_m,
        "anatomy": format!(
            "live: default scenario's leg, section imager at {}",
            site.map_or("anterior mid-thigh", Site::name)
        ),
        "vessels": r.anatomy().map_or(0, |a| a.vessels().len()),
        "scatterers": r.scatterer_count(),
        "axial_taps": r.axial_taps(),
        "one_core_thread_cpu": timing(cpu, 1),
        "one_core_wall": timing(wall, 1),
        "stage_thread_cpu_median_s": stages,
    }))
}

/// Runs the benchmark.
pub fn run(args: Args) -> Result<()> {
    anyhow::ensure!(args.frames > 0, "--frames must be > 0");
    if args.doppler {
        let report = super::doppler::report(args.frames)?;
        let text = serde_json::to_string_pretty(&report)?;
        if args.json {
            println!("{text}");
        } else {
            let f = |a: &str, b: &str| report[a][b].as_f64().unwrap_or(0.0);
            println!(
                "colour 256x384: {:.0} fps colour only, {:.0} fps with B-mode (median thread CPU); spectral: {:.0} lines/s",
                f("color", "color_only_fps"),
                f("color", "bmode_plus_color_fps"),
                f("spectral", "lines_per_s")
            );
        }
        if let Some(path) = &args.out {
            std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
        }
        return Ok(());
    }
    let d = ImagingConfig::default();
    // The default size, the live size, and the live size with the section
    // of the 3D leg below the profunda's branch point (four vessels, the
    // sartorius outline).
    let sizes = [
        (d.columns, d.rows, None),
        (256, 384, None),
        (256, 384, Some("fv-proximal")),
    ];
    let sizes = if args.live { &sizes[..0] } else { &sizes[..] };
    let mut reports = sizes
        .iter()
        .map(|&(c, r, site)| bench_size(c, r, args.frames, site))
        .collect::<Result<Vec<_>>>()?;
    // The live viewer's frame at the groin and mid-thigh.
    for site in [Some(Site::Cfv), Some(Site::FvMid), None] {
        reports.push(bench_live(site, args.frames)?);
    }
    let report = serde_json::json!({
        "benchmark": "image",
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "sizes": reports,
        "goal_fps_one_core_live_size": 60.0,
    });
    let text = serde_json::to_string_pretty(&report)?;
    if args.json {
        println!("{text}");
    } else {
        for r in &reports {
            println!(
                "image {}x{} ({}): one core {:.0} fps (median thread CPU), {:.0} fps (median wall)",
                r["columns"],
                r["rows"],
                r["anatomy"],
                r["one_core_thread_cpu"]["fps_median"]
                    .as_f64()
                    .unwrap_or(0.0),
                r["one_core_wall"]["fps_median"].as_f64().unwrap_or(0.0),
            );
        }
    }
    if let Some(path) = &args.out {
        std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
