//! `echothigh doppler --case C (--at S | --site NAME) [--maneuver
//! none|augment|valsalva] --out DIR`: a pulsed-wave spectral Doppler
//! recording of the deep vein (or `--vessel artery`, its companion artery)
//! at a level of a case's leg: the gate centred in the lumen at
//! `--doppler-angle`, the flow from `echothigh_doppler::SegmentFlow`
//! (breathing, the manoeuvre at a third of the recording, the case's
//! thrombi and its `[doppler] proximal_obstruction`), writing
//! `spectrogram.png` (time across, velocity up, baseline and scale of
//! `--baseline` and `--prf`), `doppler.wav` (the sound: forward flow
//! left, reverse right, at the PRF as sample rate) and `velocities.json`.

use super::image_site;
use anyhow::{Context, Result};
use echothigh_anatomy::StructureId;
use echothigh_doppler::{
    AudioSynth, FlowConfig, FlowKind, Maneuver, Maneuvers, Profile, PwConfig, PwDoppler,
    SegmentFlow, SpectralDisplay,
};
use std::path::PathBuf;

/// Arguments of `echothigh doppler`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A case (shipped name or case TOML file).
    #[arg(long)]
    pub case: String,
    /// Level: mm below the inguinal ligament.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<f64>,
    /// Or a named exam site (cfv, sfj, fv-proximal, fv-mid, fv-distal, popliteal).
    #[arg(long)]
    pub site: Option<String>,
    /// What the examiner does a third into the recording.
    #[arg(long, value_enum, default_value = "none")]
    pub maneuver: ManeuverArg,
    /// Which vessel the gate is in.
    #[arg(long, value_enum, default_value = "vein")]
    pub vessel: VesselArg,
    /// Treat the case as having an iliac (proximal) obstruction even if
    /// its `[doppler] proximal_obstruction` is not set.
    #[arg(long)]
    pub proximal_obstruction: bool,
    /// Doppler angle between flow and beam (degrees, 0–80 for angle correction).
    #[arg(long, default_value_t = 60.0)]
    pub doppler_angle: f64,
    /// Pulse repetition frequency (Hz): the velocity scale.
    #[arg(long, default_value_t = 6000.0)]
    pub prf: f64,
    /// Baseline shift of the display, in (−1, 1).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub baseline: f64,
    /// Recording length (s).
    #[arg(long, default_value_t = 12.0)]
    pub seconds: f64,
    /// Seed of the scatterers, noise and sound phases.
    #[arg(long, default_value_t = 17)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--maneuver`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ManeuverArg {
    /// Quiet breathing.
    None,
    /// Calf squeeze.
    Augment,
    /// Valsalva strain (a third of the recording).
    Valsalva,
}

/// `--vessel`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum VesselArg {
    /// The deep vein of the level.
    Vein,
    /// Its companion artery.
    Artery,
}

#[derive(serde::Serialize)]
struct Line {
    t_s: f64,
    model_centreline_m_s: f64,
    flow_detected: bool,
    mean_m_s: Option<f64>,
    envelope_m_s: Option<f64>,
    mean_shift_hz: f64,
}

/// Runs `echothigh doppler`.
pub fn run(args: Args) -> Result<()> {
    anyhow::ensure!(
        args.seconds.is_finite() && (0.5..=120.0).contains(&args.seconds),
        "--seconds must be 0.5 to 120 s, got {}",
        args.seconds
    );
    anyhow::ensure!(
        args.baseline.is_finite() && args.baseline.abs() < 1.0,
        "--baseline must be in (-1, 1), got {}",
        args.baseline
    );
    let case = super::cases::load_case(&args.case)?;
    let placement =
        image_site::place_on(case.anatomy.clone(), args.at, None, args.site.as_deref())?;
    let s = placement.pose.s;
    let vein = case.anatomy.deep_vein_at(s);
    let id = match (args.vessel, vein) {
        (VesselArg::Vein, v) => v,
        (VesselArg::Artery, StructureId::Cfv) => StructureId::Cfa,
        (VesselArg::Artery, StructureId::Fv) => StructureId::Fa,
        (VesselArg::Artery, _) => StructureId::Pa,
    };
    let tube = case
        .anatomy
        .tube(id)
        .with_context(|| format!("the case's leg has no {}", id.as_str()))?;
    let radius = tube.radius(s);
    let obstruction = args.proximal_obstruction || case.file.doppler.proximal_obstruction;
    let fc = FlowConfig::default();
    let flow = SegmentFlow::of(&fc, &case.anatomy, &case.thrombi, id, s, obstruction);
    let t0 = args.seconds / 3.0;
    let m = Maneuvers::scripted(
        match args.maneuver {
            ManeuverArg::None => Maneuver::None,
            ManeuverArg::Augment => Maneuver::Augment,
            ManeuverArg::Valsalva => Maneuver::Valsalva,
        },
        t0,
        args.seconds / 3.0,
    );
    let pw_cfg = PwConfig {
        angle_deg: args.doppler_angle,
        prf: args.prf,
        seed: args.seed,
        ..Default::default()
    };
    let profile = if flow.kind == FlowKind::Artery {
        Profile::Plug
    } else {
        Profile::Parabolic
    };
    let v = |t: f64| flow.velocity(&fc, &m, t, 1.0);
    let mut pw =
        PwDoppler::new(&pw_cfg, radius, profile, 0.0, v(0.0)).context("--prf / --doppler-angle")?;
    let mut synth = AudioSynth::new(pw_cfg.fft_size, pw_cfg.hop(), args.seed);
    let mut chunk = vec![[0.0f32; 2]; pw_cfg.hop()];
    let n_lines = (args.seconds / pw_cfg.line_interval).round() as usize;
    let mut powers: Vec<Vec<f32>> = Vec::with_capacity(n_lines);
    let mut audio: Vec<[f32; 2]> = Vec::with_capacity(n_lines * pw_cfg.hop());
    let mut lines = Vec::with_capacity(n_lines);
    for _ in 0..n_lines {
        let sp = pw.line(v);
        synth.push(sp, &mut chunk);
        audio.extend_from_slice(&chunk);
        powers.push(sp.power.clone());
        let (mean, env) = (sp.mean_frequency(), sp.max_frequency(0.95));
        let t = pw.time();
        // A line of noise alone shows no flow (the scanner's display
        // threshold): no velocities for it.
        let flow_seen = pw.has_signal();
        lines.push(Line {
            t_s: t,
            model_centreline_m_s: v(t),
            flow_detected: flow_seen,
            mean_m_s: pw_cfg.velocity(mean).filter(|_| flow_seen),
            envelope_m_s: pw_cfg.velocity(env).filter(|_| flow_seen),
            mean_shift_hz: mean,
        });
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    // Spectrogram: one column per line, 256 rows over the PRF.
    let rows = 256;
    let display = SpectralDisplay {
        baseline: args.baseline,
        ..Default::default()
    };
    let reference = powers.iter().flatten().fold(0.0f32, |a, &b| a.max(b)) as f64;
    let mut img = vec![0u8; rows * n_lines];
    let mut col = vec![0u8; rows];
    let mut sp = echothigh_doppler::Spectrum::new(pw_cfg.fft_size, pw_cfg.prf);
    for (x, p) in powers.iter().enumerate() {
        sp.power.copy_from_slice(p);
        display.column(&sp, pw_cfg.prf, reference, &mut col);
        for (r, &g) in col.iter().enumerate() {
            img[r * n_lines + x] = g;
        }
    }
    let zero = display.row_of(0.0, pw_cfg.prf, rows);
    for x in (0..n_lines).step_by(2) {
        img[zero * n_lines + x] = 255;
    }
    let png = args.out.join("spectrogram.png");
    echothigh_imaging::write_gray_png(&png, n_lines, rows, &img)?;
    let wav = args.out.join("doppler.wav");
    write_wav(&wav, pw_cfg.prf.round() as u32, &audio)?;
    let valsalva_rise = (0..n_lines)
        .map(|i| flow.diameter_factor(&fc, &m, i as f64 * pw_cfg.line_interval) - 1.0)
        .fold(0.0, f64::max);
    let report = serde_json::json!({
        "case": case.name(),
        "vessel": id.as_str(),
        "s_mm": s * 1e3,
        "lumen_radius_mm": radius * 1e3,
        "maneuver": format!("{:?}", args.maneuver).to_lowercase(),
        "flow": flow,
        "proximal_obstruction": obstruction,
        "doppler_angle_deg": pw_cfg.angle_deg,
        "prf_hz": pw_cfg.prf,
        "center_frequency_hz": pw_cfg.center_frequency,
        "nyquist_velocity_m_s": pw_cfg.nyquist_velocity(),
        "valsalva_diameter_rise": valsalva_rise,
        "line_interval_s": pw_cfg.line_interval,
        "lines": lines,
    });
    let json = args.out.join("velocities.json");
    std::fs::write(&json, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", json.display()))?;
    // The 98th percentile of the envelope: its peak without single-line outliers.
    let mut env: Vec<f64> = lines
        .iter()
        .filter_map(|l| l.envelope_m_s.map(f64::abs))
        .collect();
    env.sort_by(f64::total_cmp);
    let peak = env
        .get((env.len() as f64 * 0.98) as usize)
        .copied()
        .unwrap_or(0.0);
    let seen = lines.iter().filter(|l| l.flow_detected).count() as f64 / lines.len().max(1) as f64;
    println!(
        "{} {} at s = {:.1} mm: phasic {}, augmentable {}, occluded {}; flow in {:.0} % of lines, envelope peak (98th percentile) {:.1} cm/s; {}, {}, {}",
        case.name(),
        id.as_str(),
        s * 1e3,
        flow.phasic,
        flow.augmentable,
        flow.occluded,
        seen * 100.0,
        peak * 100.0,
        png.display(),
        wav.display(),
        json.display()
    );
    Ok(())
}

/// Writes stereo 16-bit PCM at `rate` Hz, normalized to 0.9 of full scale.
fn write_wav(path: &std::path::Path, rate: u32, samples: &[[f32; 2]]) -> Result<()> {
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: rate,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let peak = samples
        .iter()
        .flatten()
        .fold(0.0f32, |a, &b| a.max(b.abs()))
        .max(1e-12);
    let g = 0.9 * i16::MAX as f32 / peak;
    let mut w = hound::WavWriter::create(path, spec)
        .with_context(|| format!("creating {}", path.display()))?;
    for s in samples {
        w.write_sample((s[0] * g) as i16)?;
        w.write_sample((s[1] * g) as i16)?;
    }
    w.finalize()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
