//! The detector on synthetic sample streams: exact events.

use super::*;

const DT: f64 = 1e-3;

fn sample(t: f64, force: f64) -> ExamSample {
    ExamSample {
        t,
        force,
        skin: [0.19, 0.0],
        vein: Some("fv"),
        s: 0.19,
        // A healthy-looking vein: closes linearly by 8 N; the artery loses
        // 2 % of its area per newton.
        vein_ratio: (1.0 - force / 8.0).max(0.0),
        artery_ratio: 1.0 - 0.02 * force,
    }
}

/// Runs `force(t)` at 1 kHz over `[0, duration]`, collecting the events.
fn run(
    det: &mut EventDetector,
    duration: f64,
    f: impl Fn(f64) -> f64,
    edit: impl Fn(&mut ExamSample),
) -> Vec<CompressionEvent> {
    let n = (duration / DT).round() as usize;
    let mut out = Vec::new();
    for i in 0..=n {
        let t = i as f64 * DT;
        let mut x = sample(t, f(t));
        edit(&mut x);
        if let Some(e) = det.push(&x).unwrap() {
            out.push(e);
        }
    }
    out.extend(det.finish(n as f64 * DT));
    out
}

/// Trapezoid: up at 12 N/s to 12 N (1 s), hold 1 s, down at 24 N/s.
fn trapezoid(t: f64) -> f64 {
    if t < 1.0 {
        12.0 * t
    } else if t < 2.0 {
        12.0
    } else {
        (12.0 - 24.0 * (t - 2.0)).max(0.0)
    }
}

/// One press, its numbers exact: it starts at the first sample above 1 N
/// (12 t > 1 → t = 0.084 s, the 1 ms grid), ends at the first below 0.5 N
/// (12 − 24 (t − 2) < 0.5 → t = 2.480 s), peaks at 12 N, the vein closes
/// (ratio 0 < 0.1), the artery deforms (1 − 0.24 = 0.76 < 0.9), no slide;
/// the trace never samples faster than 50 Hz and spans the press.
#[test]
fn one_trapezoid_press_is_one_exact_event() {
    let mut det = EventDetector::new(10.0);
    let ev = run(&mut det, 3.0, trapezoid, |_| {});
    assert_eq!(ev.len(), 1, "{ev:?}");
    let e = &ev[0];
    assert!((e.t_start - 0.084).abs() < 1e-9, "{}", e.t_start);
    assert!((e.t_end - 2.480).abs() < 1e-9, "{}", e.t_end);
    assert_eq!(e.peak_force, 12.0);
    assert_eq!(e.vein.as_deref(), Some("fv"));
    assert_eq!(e.s, 0.19);
    assert_eq!(e.min_lumen_ratio, 0.0);
    assert!(e.coapted && e.artery_deformed);
    assert_eq!(e.slide, 0.0);
    let tr = &e.force_trace;
    assert_eq!(tr[0], [e.t_start, trapezoid(e.t_start)]);
    assert_eq!(tr.last().unwrap()[0], e.t_end);
    for w in tr.windows(2) {
        assert!(w[1][0] - w[0][0] >= 0.02 - 1e-9, "{w:?}");
    }
    // 2.396 s at 50 Hz: 120 points after the first, the end replacing the
    // last one when it falls within 20 ms of it.
    assert!((119..=121).contains(&tr.len()), "{}", tr.len());
}

/// Hysteresis: a dip to 0.7 N (above the 0.5 N release) keeps one press; a
/// dip to 0.3 N makes two.
#[test]
fn hysteresis_splits_only_below_the_release_threshold() {
    let twin = |low: f64| {
        move |t: f64| {
            if t < 1.0 {
                5.0
            } else if t < 1.2 {
                low
            } else if t < 2.0 {
                5.0
            } else {
                0.0
            }
        }
    };
    let mut det = EventDetector::new(10.0);
    assert_eq!(run(&mut det, 2.5, twin(0.7), |_| {}).len(), 1);
    let mut det = EventDetector::new(10.0);
    let ev = run(&mut det, 2.5, twin(0.3), |_| {});
    assert_eq!(ev.len(), 2);
    assert!((ev[0].t_end - 1.0).abs() < 1e-9 && (ev[1].t_start - 1.2).abs() < 1e-9);
    // 5 N: the vein at 1 − 5/8 = 0.375, the artery at 0.9 (not below it).
    assert!(!ev[0].coapted && !ev[0].artery_deformed);
    assert_eq!(ev[0].min_lumen_ratio, 0.375);
}

/// Sliding while pressed: the probe moves 15 mm along the leg and 4 mm
/// around it during the hold; the slide is the farthest distance from where
/// the press began, √(15² + 4²) mm, and the vein and `s` are those at the
/// peak force.
#[test]
fn a_slide_while_pressed_is_measured() {
    let mut det = EventDetector::new(10.0);
    let ev = run(&mut det, 3.0, trapezoid, |x| {
        let u = ((x.t - 1.0) / 1.0).clamp(0.0, 1.0);
        x.skin = [0.19 + 0.015 * u, 0.004 * u];
        x.s = x.skin[0];
        if x.t > 0.5 {
            x.vein = Some("pv");
        }
    });
    let e = &ev[0];
    assert!(
        (e.slide - 0.015f64.hypot(0.004)).abs() < 1e-12,
        "{}",
        e.slide
    );
    // The peak (12 N) is first reached at t = 1.0 s, where s = 0.19.
    assert_eq!(e.vein.as_deref(), Some("pv"));
    assert!((e.s - 0.19).abs() < 1e-12);
}

/// A press longer than the trace's room is decimated in place: the trace
/// stays within its capacity (1 s at 50 Hz = 50 points), still spans the
/// press, and its spacing doubled.
#[test]
fn a_long_press_keeps_a_bounded_trace() {
    let mut det = EventDetector::new(1.0);
    let ev = run(&mut det, 6.0, |t| if t < 5.0 { 10.0 } else { 0.0 }, |_| {});
    let tr = &ev[0].force_trace;
    assert!(tr.len() <= 50, "{}", tr.len());
    assert_eq!(tr[0][0], 0.0);
    assert!((tr.last().unwrap()[0] - 5.0).abs() < 1e-9);
    for w in tr.windows(2).take(tr.len() - 2) {
        assert!(w[1][0] - w[0][0] >= 0.08 - 1e-9, "{w:?}");
    }
}

/// Bad samples are refused naming the field; time may not go back.
#[test]
fn bad_samples_name_the_field() {
    let mut det = EventDetector::new(1.0);
    let mut x = sample(0.0, 2.0);
    x.vein_ratio = f64::NAN;
    let e = det.push(&x).unwrap_err().to_string();
    assert!(e.contains("vein_ratio"), "{e}");
    x = sample(1.0, -1.0);
    assert!(det.push(&x).unwrap_err().to_string().contains("force"));
    det.push(&sample(1.0, 2.0)).unwrap();
    let e = det.push(&sample(0.5, 2.0)).unwrap_err();
    assert!(matches!(e, DetectorError::Backwards { .. }), "{e}");
}
