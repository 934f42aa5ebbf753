//! `echothigh bench image --doppler`: colour flow frames per second at the
//! live size (256 × 384) on one core — the B-mode frame, the flow scene
//! and the colour overlay each timed (`color` is scene plus overlay), and
//! together — on the section of a normal lean leg at `fv-proximal` (four
//! vessels) with the probe tilted 20°, and PW spectral lines per second (default `[doppler.pw]`: 512
//! scatterers, 4 kHz PRF, 128-point FFT, 20 pulses per line) with the
//! sound synthesized from each line. Medians of the thread's CPU time.

use super::clock::thread_cpu_us;
use anyhow::{Context, Result};
use echothigh_doppler::{
    AudioSynth, ColorConfig, ColorFlow, ColorMode, FlowConfig, FlowKind, FlowScene, Maneuvers,
    Profile, PwConfig, PwDoppler, SectionFlows, SegmentFlow,
};
use echothigh_imaging::{FrameInput, ImagingConfig, Renderer, SectionDeformation, VeinState};

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Times `frames` colour frames; returns the JSON report.
fn color(frames: usize) -> Result<serde_json::Value> {
    let case = echothigh_cases::builtin("normal-lean")?;
    let mut p =
        crate::cmd::image_site::place_on(case.anatomy.clone(), None, None, Some("fv-proximal"))?;
    p.pose.tilt = 20f64.to_radians();
    let mut cfg = ImagingConfig {
        columns: 256,
        rows: 384,
        ..Default::default()
    };
    cfg.anatomy = crate::cmd::image_site::case_section_anatomy(&cfg.anatomy, &p, &case.thrombi)?;
    let mut r = Renderer::new(&cfg, VeinState::Healthy)?;
    let bone = r.anatomy().context("anatomy")?.femur_top();
    let press = SectionDeformation::flat_press(3e-3, cfg.probe_width, 1.5e-3, bone)?;
    let section = p.anatomy.section(&p.pose)?;
    let fc = FlowConfig::default();
    let flows = SectionFlows::new(
        &fc,
        &p.anatomy,
        &case.thrombi,
        false,
        &section,
        &cfg.anatomy,
    )?;
    let cc = ColorConfig::default();
    let cols: Vec<f64> = (0..cfg.columns).map(|j| r.column_lateral(j)).collect();
    let mut cf = ColorFlow::new(&cc, ColorMode::Velocity, &cols, cfg.rows, cfg.pixel_depth())?;
    let mut gray = vec![0u8; cfg.columns * cfg.rows];
    let mut rgb = vec![0u8; 3 * gray.len()];
    let mut scene = FlowScene::new();
    let m = Maneuvers::new();
    let (mut tb, mut ts, mut to) = (Vec::new(), Vec::new(), Vec::new());
    let (mut tc, mut tt) = (Vec::new(), Vec::new());
    for k in 0..frames + 5 {
        let input = FrameInput {
            deformation: &press,
            probe_pressure: 2.0 / cfg.probe_area(),
            time: k as f64 / 30.0,
            lateral_offset: 0.0,
        };
        let c0 = thread_cpu_us();
        r.render_into(&input, &mut gray)?;
        let c1 = thread_cpu_us();
        flows.fill(&fc, &m, &r, &input, 0.0, 0.0, &mut scene)?;
        let c2 = thread_cpu_us();
        cf.frame(&gray, &scene, &mut rgb)?;
        let c3 = thread_cpu_us();
        if k >= 5 {
            tb.push((c1 - c0) * 1e-6);
            ts.push((c2 - c1) * 1e-6);
            to.push((c3 - c2) * 1e-6);
            tc.push((c3 - c1) * 1e-6);
            tt.push((c3 - c0) * 1e-6);
        }
    }
    let (b, c, t) = (median(tb), median(tc), median(tt));
    let (sc, ov) = (median(ts), median(to));
    Ok(serde_json::json!({
        "columns": cfg.columns,
        "rows": cfg.rows,
        "anatomy": "normal-lean, fv-proximal, tilt 20 deg",
        "frames": frames,
        "colored_pixels_last_frame": cf.colored(),
        "bmode_median_s": b,
        "scene_median_s": sc,
        "overlay_median_s": ov,
        "color_median_s": c,
        "bmode_plus_color_median_s": t,
        "color_only_fps": 1.0 / c,
        "bmode_plus_color_fps": 1.0 / t,
        "goal_fps_with_bmode": 30.0,
    }))
}

/// Times `lines` spectral lines (with the sound of each); returns the report.
fn spectral(lines: usize) -> Result<serde_json::Value> {
    let c = PwConfig::default();
    let fc = FlowConfig::default();
    let flow = SegmentFlow::healthy(FlowKind::Vein, fc.cfv_peak_velocity);
    let m = Maneuvers::new();
    let v = |t: f64| flow.velocity(&fc, &m, t, 1.0);
    let mut pw = PwDoppler::new(&c, 5e-3, Profile::Parabolic, 0.0, v(0.0))?;
    let mut synth = AudioSynth::new(c.fft_size, c.hop(), 1);
    let mut out = vec![[0.0f32; 2]; c.hop()];
    let mut t = Vec::with_capacity(lines);
    for k in 0..lines + 20 {
        let c0 = thread_cpu_us();
        let s = pw.line(v);
        synth.push(s, &mut out);
        let c1 = thread_cpu_us();
        if k >= 20 {
            t.push((c1 - c0) * 1e-6);
        }
    }
    let med = median(t);
    Ok(serde_json::json!({
        "lines": lines,
        "scatterers": c.scatterers,
        "prf_hz": c.prf,
        "fft_size": c.fft_size,
        "pulses_per_line": c.hop(),
        "line_median_s": med,
        "lines_per_s": 1.0 / med,
        "goal_lines_per_s": 200.0,
    }))
}

/// The Doppler benchmark's JSON report.
pub fn report(frames: usize) -> Result<serde_json::Value> {
    Ok(serde_json::json!({
        "benchmark": "image --doppler",
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "timer": "thread CPU time (cpu-time), medians, one core",
        "color": color(frames)?,
        "spectral": spectral(frames.max(1) * 10)?,
    }))
}
