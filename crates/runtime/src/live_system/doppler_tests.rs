//! The live flow on a case's leg (issue 17), through the imaging thread's
//! own processing ([`FlowImaging`]) on the drawn section: colour inside a
//! patent vein and none inside an occluded one at the same settings; the
//! spectral envelope at a normal CFV oscillating at the breathing rate; a
//! calf squeeze raising the peak velocity by the model's factor.

use super::doppler::{mode_code, DopplerShared, FlowContext, FlowImaging};
use crate::live_doppler::{DopplerCommand, DopplerMode, Gate, SpectralLines, SPECTRAL_ROWS};
use crate::scenario::Scenario;
use crate::section_follow::SectionImager;
use echothigh_anatomy::{Site, Thrombi};
use echothigh_imaging::{FrameInput, ImagingConfig, SectionDeformation, VeinState};
use echothigh_model::LegSurface;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// The live imager of `case` at `site`, its thrombi and image settings.
fn imager(case: &str, site: Site) -> (SectionImager, Thrombi, ImagingConfig) {
    let case = echothigh_cases::builtin(case).unwrap();
    let mut sc = Scenario::builtin().unwrap();
    sc.set_patient(case.anatomy.patient()).unwrap();
    let leg = LegSurface::new(&sc.thigh, "thigh").unwrap().unwrap();
    let cfg = sc.live_imaging_config();
    let pose = leg.anatomy().site_pose(site);
    let t = Arc::new(case.thrombi.clone());
    let im = SectionImager::with_thrombi(leg, &cfg, VeinState::Healthy, pose, Some(t)).unwrap();
    (im, case.thrombi, cfg)
}

/// Runs the flow processing of the rest frame at times `times` in `mode`
/// (the B-mode rendered once: the flow does not depend on it), calling
/// `each(t, shared, overlay, imager)` after each frame.
fn run(
    im: &mut SectionImager,
    thrombi: &Thrombi,
    shared: &DopplerShared,
    mode: DopplerMode,
    times: impl Iterator<Item = f64>,
    mut each: impl FnMut(f64, &DopplerShared, &[u8], &SectionImager),
) {
    shared.mode.store(mode_code(mode), Ordering::Release);
    let bone = im.renderer().anatomy().unwrap().femur_top();
    let rest = SectionDeformation::rest(bone);
    let (w, h) = im.renderer().frame_size();
    let mut pixels = vec![0u8; w * h];
    let input = |time| FrameInput {
        deformation: &rest,
        probe_pressure: 0.0,
        time,
        lateral_offset: 0.0,
    };
    im.renderer().render_into(&input(0.0), &mut pixels).unwrap();
    let mut flow = FlowImaging::default();
    let mut overlay = Vec::new();
    for t in times {
        let ctx = FlowContext {
            anatomy: im.leg().anatomy(),
            thrombi,
            pose: im.built_pose(),
            key: im.rebuilds(),
        };
        flow.frame(
            shared,
            &ctx,
            im.renderer_ref(),
            &input(t),
            &pixels,
            Some(1.0),
            &mut overlay,
        )
        .unwrap();
        each(t, shared, &overlay, im);
    }
}

/// Coloured pixels inside, and the pixel count of, the studied vein's
/// lumen (vessel 0) of the rest frame.
fn coloured_in_vein(im: &SectionImager, overlay: &[u8]) -> (usize, usize) {
    let r = im.renderer_ref();
    let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    let l = r
        .vessel_lumen(
            0,
            &FrameInput {
                deformation: &rest,
                probe_pressure: 0.0,
                time: 0.0,
                lateral_offset: 0.0,
            },
        )
        .unwrap()
        .unwrap();
    let (w, h) = r.frame_size();
    let dz = r.config().pixel_depth();
    let (mut n, mut c) = (0, 0);
    for i in 0..h {
        for j in 0..w {
            let u = (r.column_lateral(j) - l.lateral) / l.half_width;
            let d = ((i as f64 + 0.5) * dz - l.depth) / l.half_height;
            if u * u + d * d < 1.0 {
                n += 1;
                c += usize::from(overlay[i * w + j] != 0);
            }
        }
    }
    (c, n)
}

/// Colour inside a patent CFV, none inside an occluded one, at the same
/// (default) settings. Patent: with the beam rocked 20° the CFV's 0.13–0.2
/// m/s centreline has an axial part of ~0.05–0.07 m/s against a colour
/// Nyquist of 0.115 m/s; the parabolic profile is above the 5 %-of-Nyquist
/// cut-off over ρ < 0.95 of the lumen (91 % of its area) and the blood is
/// 20 dB over the noise (6 dB threshold), so more than half the lumen's
/// pixels must be coloured (the rest: the wall band the grey priority
/// hides). Occluded: no blood, and the noise alone passes the 6 dB
/// threshold on an ensemble of 10 with a chance far below one in the
/// lumen's few hundred pixels: zero allowed.
#[test]
fn colour_fills_a_patent_vein_and_not_an_occluded_one() {
    for (case, patent) in [("normal-average", true), ("cfv-occlusive-acute", false)] {
        let (mut im, thrombi, _) = imager(case, Site::Cfv);
        let shared = DopplerShared::default();
        let mut counts = (0, 0);
        run(
            &mut im,
            &thrombi,
            &shared,
            DopplerMode::Color,
            [1.0].into_iter(),
            |_, _, o, im| counts = coloured_in_vein(im, o),
        );
        let (c, n) = counts;
        assert!(n > 50, "{case}: a lumen of {n} pixels");
        if patent {
            assert!(2 * c > n, "{case}: {c} of {n} lumen pixels coloured");
        } else {
            assert_eq!(c, 0, "{case}: {c} of {n} lumen pixels coloured");
        }
    }
}

/// Per line, the magnitude-weighted mean |frequency| (Hz) of the rows at
/// least half the display's range up (−20 dB of the reference), 0 without
/// any: the spectrum's centre, which scales with the velocity.
fn mean_shift(line: &[u8], prf: f64) -> f64 {
    let (mut s, mut wsum) = (0.0, 0.0);
    for (r, &m) in line.iter().enumerate() {
        let f = 0.5 * prf - (r as f64 + 0.5) / SPECTRAL_ROWS as f64 * prf;
        if m >= 128 {
            s += m as f64 * f.abs();
            wsum += m as f64;
        }
    }
    if wsum > 0.0 {
        s / wsum
    } else {
        0.0
    }
}

/// The mean shift of every spectral line over `seconds` at 20 frames/s,
/// the gate at the CFV's centre; `at(t, shared)` runs before each frame.
fn spectral_trace(seconds: f64, mut at: impl FnMut(f64, &DopplerShared)) -> (Vec<f64>, f64) {
    let (mut im, thrombi, _) = imager("normal-average", Site::Cfv);
    let shared = DopplerShared::default();
    let (l, w, h, dz) = {
        let r = im.renderer_ref();
        let rest = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
        let input = FrameInput {
            deformation: &rest,
            probe_pressure: 0.0,
            time: 0.0,
            lateral_offset: 0.0,
        };
        let (w, h) = r.frame_size();
        (
            r.vessel_lumen(0, &input).unwrap().unwrap(),
            w,
            h,
            r.config().pixel_depth(),
        )
    };
    let r = im.renderer_ref();
    let j = (0..w)
        .min_by(|&a, &b| {
            (r.column_lateral(a) - l.lateral)
                .abs()
                .total_cmp(&(r.column_lateral(b) - l.lateral).abs())
        })
        .unwrap();
    shared.controls.lock().unwrap().gate = Gate {
        x: j as f64 / (w - 1) as f64,
        y: l.depth / (h as f64 * dz),
        angle_deg: 60.0,
    };
    let frames = (seconds * 20.0) as usize;
    let mut next = 0;
    let mut out = Vec::new();
    let mut lines = SpectralLines::default();
    let mut prf = 0.0;
    run(
        &mut im,
        &thrombi,
        &shared,
        DopplerMode::Spectral,
        (1..=frames).map(|k| k as f64 / 20.0),
        |t, sh, _, _| {
            at(t, sh);
            let st = *sh.status.lock().unwrap();
            assert!(st.gate_in_flow, "the gate is in the CFV");
            prf = st.prf;
            sh.lines.lock().unwrap().copy(next, &mut lines);
            next = lines.first + lines.count as u64;
            out.extend(lines.data.chunks(SPECTRAL_ROWS).map(|c| mean_shift(c, prf)));
        },
    );
    (out, 1.0 / 0.005)
}

/// A normal CFV's spectrum follows breathing: over 16 s of lines (four
/// breaths at the default 0.25 Hz), the strongest non-zero frequency of
/// the mean shift's DFT is the breathing rate, within the DFT's resolution
/// (1/16 s = 0.0625 Hz), scanned from 0.1 to 2 Hz.
#[test]
fn the_spectral_envelope_follows_breathing() {
    let seconds = 16.0;
    let (trace, rate) = spectral_trace(seconds, |_, _| {});
    let n = trace.len() as f64;
    assert!(n > 0.9 * seconds * rate, "{n} lines");
    let mean = trace.iter().sum::<f64>() / n;
    assert!(mean > 50.0, "flow seen: mean shift {mean} Hz");
    let power = |f: f64| {
        let (mut re, mut im) = (0.0, 0.0);
        for (k, x) in trace.iter().enumerate() {
            let ph = std::f64::consts::TAU * f * k as f64 / rate;
            re += (x - mean) * ph.cos();
            im += (x - mean) * ph.sin();
        }
        re * re + im * im
    };
    let df = 1.0 / seconds;
    let best = (2..=32)
        .map(|k| k as f64 * df)
        .max_by(|a, b| power(*a).total_cmp(&power(*b)))
        .unwrap();
    let breathing = echothigh_doppler::FlowConfig::default().breathing_rate;
    assert!((best - breathing).abs() <= df + 1e-9, "peak at {best} Hz");
}

/// A calf squeeze raises the peak: the largest mean shift (smoothed over 5
/// lines, 25 ms, against a pulse peaking over ~0.3 s) in the 2 s after a
/// squeeze at 6 s, over the largest of the quiet 4 s before it (a full
/// breath), is the model's `augmentation_factor` (3: the pulse peaks at
/// exactly `F·peak`, the quiet maximum is `peak`). Tolerance 15 %: the
/// 8-bit, 64-row display (62.5 Hz rows; a row entering or leaving the
/// −20 dB band moves a mean of ~200 Hz by a few %) and the speckle of a
/// line's spectrum (a 128-point periodogram, ~5 % on a mean over a dozen
/// bins).
#[test]
fn a_squeeze_raises_the_peak_by_the_models_factor() {
    let mut squeezed = false;
    let (trace, rate) = spectral_trace(8.0, |t, sh| {
        if t >= 6.0 && !squeezed {
            squeezed = true;
            sh.command(DopplerCommand::Squeeze, 6.0).unwrap();
        }
    });
    let smooth: Vec<f64> = trace
        .windows(5)
        .map(|w| w.iter().sum::<f64>() / 5.0)
        .collect();
    let at = |t: f64| (t * rate) as usize;
    let max = |a: usize, b: usize| {
        smooth[a..b.min(smooth.len())]
            .iter()
            .fold(0.0f64, |m, &x| m.max(x))
    };
    let quiet = max(at(1.5), at(5.5));
    let peak = max(at(6.0), at(8.0));
    let f = echothigh_doppler::FlowConfig::default().augmentation_factor;
    let ratio = peak / quiet;
    assert!(
        (ratio / f - 1.0).abs() < 0.15,
        "peak {peak} / quiet {quiet} = {ratio}, model {f}"
    );
}

/// Valsalva in the B-mode: held from 1 s, at 4 s (the strain
/// `1 − e^{−3/0.3}`, within 5e-5 of full) the studied vein's drawn lumen
/// height is `1 + D` times its rest height — the model's healthy `D` = 1
/// (+100 %, inside the 50–200 % of a healthy CFV) for a normal CFV, its
/// obstructed `D` = 0.3 (under 50 %) for a CFV filled by an acute
/// thrombus there. The renderer's lumen height is the vertical warp of the
/// lumen law times the factor, so the ratio is the factor to rounding: 1 %.
#[test]
fn valsalva_distends_a_healthy_cfv_and_a_thrombosed_one_much_less() {
    let fc = echothigh_doppler::FlowConfig::default();
    for (case, d) in [
        ("normal-average", fc.valsalva_distension_healthy),
        ("cfv-occlusive-acute", fc.valsalva_distension_obstructed),
    ] {
        let (mut im, thrombi, _) = imager(case, Site::Cfv);
        let shared = DopplerShared::default();
        shared
            .command(DopplerCommand::Valsalva { hold: true }, 1.0)
            .unwrap();
        let bone = im.renderer().anatomy().unwrap().femur_top();
        let rest = SectionDeformation::rest(bone);
        let input = FrameInput {
            deformation: &rest,
            probe_pressure: 0.0,
            time: 4.0,
            lateral_offset: 0.0,
        };
        let height = |im: &SectionImager| {
            im.renderer_ref()
                .vessel_lumen(0, &input)
                .unwrap()
                .unwrap()
                .half_height
        };
        let h0 = height(&im);
        let (w, h) = im.renderer().frame_size();
        let pixels = vec![0u8; w * h];
        let mut flow = FlowImaging::default();
        let ctx = FlowContext {
            anatomy: im.leg().anatomy(),
            thrombi: &thrombi,
            pose: im.built_pose(),
            key: im.rebuilds(),
        };
        flow.frame(
            &shared,
            &ctx,
            im.renderer_ref(),
            &input,
            &pixels,
            None,
            &mut Vec::new(),
        )
        .unwrap();
        let factor = flow.vein_distension();
        im.renderer().set_vein_distension(factor);
        let ratio = height(&im) / h0;
        let want = 1.0 + d * (1.0 - (-3.0f64 / fc.valsalva_time_constant).exp());
        assert!(
            (factor / want - 1.0).abs() < 1e-9,
            "{case}: factor {factor}, model {want}"
        );
        assert!(
            (ratio / want - 1.0).abs() < 0.01,
            "{case}: drawn {ratio}, model {want}"
        );
        assert!(
            if d >= 0.5 { ratio > 1.5 } else { ratio < 1.5 },
            "{case}: distension {ratio}"
        );
    }
}
