//! The scripted trainee (issue 14) on the virtual clock: the shipped
//! scripts on the shipped cases, through the same haptic tick as `run`.

use echothigh_cases::builtin;
use echothigh_exam::{Finding, MemoryLog, Protocol};
use echothigh_runtime::exam_run::{run_exam, ExamOutcome};
use echothigh_runtime::exam_script::TraineeScript;

fn script(name: &str) -> TraineeScript {
    let path = format!("{}/../../scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    TraineeScript::from_toml_str(&text, &path).unwrap()
}

fn walk(script: &TraineeScript, case: &str) -> (ExamOutcome, MemoryLog) {
    let case = builtin(case).unwrap();
    let mut log = MemoryLog::default();
    let wall = std::time::Instant::now();
    let out = run_exam(script, &case, &mut log).unwrap();
    eprintln!(
        "{} on {}: {:.1} s virtual, {} ticks, {} looks, {:.1} s wall",
        script.protocol,
        case.name(),
        out.virtual_time,
        out.ticks,
        out.looks,
        wall.elapsed().as_secs_f64()
    );
    for (site, s_phys) in &out.pressed {
        eprintln!(
            "  site {} at {:.1} mm pressed at {:.1} mm",
            site.name,
            site.s * 1e3,
            s_phys * 1e3
        );
    }
    for e in &log.events {
        eprintln!(
            "  {:?} [{:.3}, {:.3}] s {:6.1} mm: peak {:5.2} N, min vein {:.3}, artery cue {}, coapted {}, slide {:.1} mm",
            e.vein,
            e.t_start,
            e.t_end,
            e.s * 1e3,
            e.peak_force,
            e.min_lumen_ratio,
            e.artery_deformed,
            e.coapted,
            e.slide * 1e3
        );
    }
    for (x, why) in &out.unexaminable {
        eprintln!("  NOT IMAGEABLE {}: {why}", x.name);
    }
    for c in &log.calls {
        eprintln!("  call {}: {:?} (truth {:?})", c.site, c.finding, c.truth);
    }
    (out, log)
}

/// Two-point with a 10 N target on the isolated FV thrombus: one event per
/// pressed site, over the site's vein, its `s` within half the 2 cm site
/// spacing of the site, its peak at the target (at least the target, the
/// press stopping when the felt force reaches it; at most 10 % over it:
/// see the overshoot derivation below), released between presses (less
/// than the record's 1 cm of sliding). The honest calls
/// are right where the probe went (CFV and popliteal normal), the
/// thrombus is reported missed on the FV (170–230 mm).
#[test]
fn two_point_presses_are_detected_and_miss_the_isolated_fv_thrombus() {
    let (out, log) = walk(&script("exam-two-point"), "isolated-fv-mid-acute");
    let s = &out.score;
    assert_eq!(log.events.len(), out.pressed.len(), "{:?}", log.events);
    let target = 10.0;
    for (e, (site, _)) in log.events.iter().zip(&out.pressed) {
        assert_eq!(e.vein.as_deref(), Some(site.vein.as_str()));
        assert!(
            (e.s - site.s).abs() <= 0.01,
            "{} at {} vs {}",
            site.name,
            e.s,
            site.s
        );
        // Overshoot: the hand stops its setpoint on the tick the felt force
        // reaches the target; the felt force comes from the buffer model,
        // one physics period (10 ms) plus the compute delay (10 ms) behind
        // the probe, and the force rises at ≤ 25 N/s during the press
        // (measured in these runs): ≤ 0.5 N, 5 % of 10 N; doubled for the
        // probe's settling into the hand's spring.
        assert!(
            e.peak_force >= target && e.peak_force <= 1.1 * target,
            "{}: peak {}",
            site.name,
            e.peak_force
        );
        // Compress–release–step, not a slide: below the record's 1 cm
        // slide criterion (`CompressionEvent::slide`).
        assert!(e.slide < 0.01, "{}: slide {}", site.name, e.slide);
    }
    assert_eq!(s.protocol, Protocol::TwoPoint.name());
    assert_eq!(s.missed.len(), 1, "{:?}", s.missed);
    let m = &s.missed[0];
    assert_eq!((m.vein.as_str(), m.truth), ("fv", Finding::AcuteDvt));
    assert!((m.s_start - 0.17).abs() < 1e-9 && (m.s_end - 0.23).abs() < 1e-9);
}

/// Light pressure (2 N) never deforms the artery: every site is called
/// indeterminate (inadequate study), none acute DVT, and the score counts
/// no adequate press and no coverage.
#[test]
fn light_pressure_is_inadequate_not_non_compressible() {
    let (out, log) = walk(&script("exam-light-pressure"), "normal-average");
    let s = &out.score;
    assert!(!log.calls.is_empty());
    for c in &log.calls {
        assert_eq!(c.finding, Finding::Indeterminate, "{}", c.site);
    }
    assert!(s.sites.iter().all(|x| !x.called_without_adequate_pressure));
    assert_eq!(s.pressure_adequate, 0.0);
    assert_eq!(s.coverage, 0.0);
}

/// The thorough trainee (whole-leg, a press every 2 cm until the artery
/// deforms or the walls meet, up to 20 N, honest calls) on the average
/// normal leg: every bin closes and every call it makes is right, nothing
/// is missed. (Until issue 13's follow-up the renderer refused the average
/// female's CFV in the first 2 cm below the ligament, whose top crosses
/// the fascia into the fat; every section now draws,
/// `sections_everywhere.rs`.)
#[test]
fn thorough_trainee_on_a_normal_leg_closes_every_imageable_bin() {
    let (out, log) = walk(&script("exam-thorough"), "normal-average");
    let s = &out.score;
    let lost: Vec<&str> = out
        .unexaminable
        .iter()
        .map(|(x, _)| x.name.as_str())
        .collect();
    assert!(lost.is_empty(), "not examinable: {lost:?}");
    let bins = &log.coverage;
    for b in bins {
        assert_eq!(b.state, echothigh_exam::BinState::Closed, "{b:?}");
    }
    assert_eq!(s.coverage, 1.0, "{}", s.coverage);
    let n = bins.len() as u32;
    assert_eq!(log.calls.len(), bins.len());
    assert!(log.calls.iter().all(|c| c.is_correct()));
    assert_eq!((s.calls_correct, s.calls_total), (n, n));
    assert!(s.missed.is_empty());
}

/// The thorough trainee on the isolated FV thrombus (FV 170–230 mm): every
/// bin covered, every call right — acute DVT at the sites inside the
/// thrombus, normal elsewhere — and nothing missed.
#[test]
fn thorough_trainee_finds_the_isolated_fv_thrombus() {
    let (out, log) = walk(&script("exam-thorough"), "isolated-fv-mid-acute");
    let s = &out.score;
    assert_eq!(s.coverage, 1.0, "{:?}", log.coverage);
    assert_eq!(s.calls_correct, s.calls_total);
    assert!(s.missed.is_empty(), "{:?}", s.missed);
    assert!(log
        .calls
        .iter()
        .any(|c| c.finding == Finding::AcuteDvt && c.vein == "fv"));
}

/// The thorough trainee on the obese leg (issue 12: the force scale and
/// the device's limits must let a trainee close a healthy vein there): an
/// adequate press, capped at the patient's exam force (50 N) instead of
/// the former fixed 20 N, closes every imageable bin and every call is
/// right. (Measured: the hardest bin, FV at 210 mm, coapted at 20.0 N, at
/// the former cap; `coaptation_along_leg.rs` presses straight in and finds
/// 12–22 N.)
#[test]
fn thorough_trainee_closes_every_bin_of_the_obese_leg() {
    let (out, log) = walk(&script("exam-thorough"), "normal-obese");
    let lost: Vec<&str> = out
        .unexaminable
        .iter()
        .map(|(x, _)| x.name.as_str())
        .collect();
    assert!(lost.is_empty(), "not examinable: {lost:?}");
    for b in &log.coverage {
        assert_eq!(b.state, echothigh_exam::BinState::Closed, "{b:?}");
    }
    assert!(log.calls.iter().all(|c| c.is_correct()));
    let peak = log.events.iter().map(|e| e.peak_force).fold(0.0, f64::max);
    eprintln!("obese: peak press {peak:.1} N");
}
