//! `echothigh image --doppler color|power`: the colour flow overlay
//! (`echothigh_doppler::ColorFlow`) over the B-mode frame of a section of
//! the leg, the flow of each vessel from its case's segment state
//! (`echothigh_doppler::SectionFlows`), written as an RGB PNG.

use anyhow::{Context, Result};
use echothigh_anatomy::{Section, Thrombi};
use echothigh_doppler::{
    ColorConfig, ColorFlow, ColorMode, FlowConfig, FlowScene, Maneuvers, SectionFlows,
};
use echothigh_imaging::{AnatomyConfig, FrameInput, Renderer};
use std::path::Path;

/// `--doppler`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DopplerMode {
    /// Colour flow: mean velocity, towards red, away blue.
    Color,
    /// Power Doppler: flow amplitude, no direction.
    Power,
}

/// What the colour overlay needs from the section under the probe.
pub struct ColorInputs<'a> {
    /// The leg's anatomy (a case's or a patient's).
    pub anatomy: &'a echothigh_anatomy::Anatomy,
    /// The section under the probe.
    pub section: &'a Section,
    /// The case's segments (none for a patient).
    pub thrombi: &'a Thrombi,
    /// The case's iliac obstruction flag.
    pub proximal_obstruction: bool,
    /// The renderer's anatomy (the section's, `section_anatomy_with`).
    pub imaging_anatomy: &'a AnatomyConfig,
}

/// Renders the colour overlay of `frame` (rendered by `renderer` for
/// `input`) and writes it to `path`; returns the coloured pixel count.
pub fn write_color(
    path: &Path,
    mode: DopplerMode,
    gain_db: f64,
    inputs: &ColorInputs,
    renderer: &Renderer,
    input: &FrameInput,
    frame: &[u8],
) -> Result<usize> {
    let fc = FlowConfig::default();
    let flows = SectionFlows::new(
        &fc,
        inputs.anatomy,
        inputs.thrombi,
        inputs.proximal_obstruction,
        inputs.section,
        inputs.imaging_anatomy,
    )?;
    let cfg = ColorConfig {
        gain_db,
        ..Default::default()
    };
    let mut scene = FlowScene::new();
    flows.fill(
        &fc,
        &Maneuvers::new(),
        renderer,
        input,
        cfg.steer_deg.to_radians(),
        0.0,
        &mut scene,
    )?;
    let (w, h) = renderer.frame_size();
    let cols: Vec<f64> = (0..w).map(|j| renderer.column_lateral(j)).collect();
    let m = match mode {
        DopplerMode::Color => ColorMode::Velocity,
        DopplerMode::Power => ColorMode::Power,
    };
    let mut cf = ColorFlow::new(&cfg, m, &cols, h, renderer.config().pixel_depth())?;
    let mut rgb = vec![0u8; 3 * w * h];
    cf.frame(frame, &scene, &mut rgb)?;
    write_rgb_png(path, w, h, &rgb)?;
    Ok(cf.colored())
}

/// Writes an 8-bit RGB PNG.
pub fn write_rgb_png(path: &Path, w: usize, h: usize, rgb: &[u8]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc
        .write_header()
        .with_context(|| format!("writing {}", path.display()))?;
    wr.write_image_data(rgb)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
