//! The scorer on hand-built exams of the shipped cases.

use super::*;
use echothigh_cases::builtin;

fn press(vein: &str, s: f64, coapted: bool, artery: bool, peak: f64) -> CompressionEvent {
    CompressionEvent {
        t_start: 0.0,
        t_end: 2.0,
        vein: Some(vein.into()),
        s,
        peak_force: peak,
        min_lumen_ratio: if coapted { 0.0 } else { 0.7 },
        artery_deformed: artery,
        coapted,
        slide: 0.0,
        // A triangle to `peak` and back over 2 s: mean force peak / 2.
        force_trace: vec![[0.0, 0.0], [1.0, peak], [2.0, 0.0]],
    }
}

fn call(site: &ProtocolSite, finding: Finding, truth: Finding, t: f64) -> Call {
    Call {
        site: site.name.clone(),
        vein: site.vein.clone(),
        s: site.s,
        finding,
        truth,
        t,
    }
}

struct Exam {
    events: Vec<CompressionEvent>,
    calls: Vec<Call>,
}

fn score(case: &str, protocol: Protocol, exam: &Exam) -> CaseScore {
    let c = builtin(case).unwrap();
    let sites = protocol.sites(&c.anatomy);
    let truth = c.ground_truth();
    let mut cov = Coverage::new(&c.anatomy);
    for e in &exam.events {
        cov.apply(e);
    }
    score_case(&ScoreInput {
        case,
        protocol,
        sites: &sites,
        truth: &truth,
        events: &exam.events,
        calls: &exam.calls,
        coverage: &cov,
    })
}

/// A flawless two-point exam of the isolated FV thrombus (FV 170–230 mm,
/// case file): both sites close and are called normal — every call right,
/// full coverage of the protocol — and the score says where the disease
/// was missed: the FV from 170 to 230 mm, acute DVT. Three-point with an
/// adequate non-closing press at mid-thigh (200 mm) and an acute call
/// misses nothing.
#[test]
fn two_point_misses_the_isolated_fv_thrombus_and_says_where() {
    let c = builtin("isolated-fv-mid-acute").unwrap();
    let two = Protocol::TwoPoint.sites(&c.anatomy);
    let exam = Exam {
        events: two
            .iter()
            .map(|x| press(&x.vein, x.s, true, false, 8.0))
            .collect(),
        calls: two
            .iter()
            .enumerate()
            .map(|(i, x)| call(x, Finding::Normal, Finding::Normal, 10.0 + i as f64))
            .collect(),
    };
    let s = score("isolated-fv-mid-acute", Protocol::TwoPoint, &exam);
    assert_eq!((s.calls_correct, s.calls_total), (2, 2));
    assert_eq!(s.coverage, 1.0);
    assert_eq!(s.pressure_adequate, 1.0);
    assert_eq!(s.duration, 11.0);
    assert_eq!(s.peak_force, 8.0);
    assert!((s.mean_force - 4.0).abs() < 1e-12, "{}", s.mean_force);
    assert_eq!(s.missed.len(), 1, "{:?}", s.missed);
    let m = &s.missed[0];
    assert_eq!((m.vein.as_str(), m.truth), ("fv", Finding::AcuteDvt));
    assert!((m.s_start - 0.17).abs() < 1e-12 && (m.s_end - 0.23).abs() < 1e-12);

    let three = Protocol::ThreePoint.sites(&c.anatomy);
    let mid = &three[1];
    assert!((mid.s - 0.20).abs() < 1e-12, "fv-mid at {}", mid.s);
    let mut exam3 = exam;
    exam3.events.push(press("fv", mid.s, false, true, 14.0));
    exam3
        .calls
        .push(call(mid, Finding::AcuteDvt, Finding::AcuteDvt, 12.0));
    let s = score("isolated-fv-mid-acute", Protocol::ThreePoint, &exam3);
    assert_eq!((s.calls_correct, s.calls_total), (3, 3));
    assert!(s.missed.is_empty(), "{:?}", s.missed);
    assert_eq!(s.sites[1].truth, Finding::AcuteDvt);
    assert!(s.sites[1].pressure_adequate && !s.sites[1].called_without_adequate_pressure);
}

/// Light pressure: neither coapted nor the artery deformed. An acute call
/// there is marked as made without adequate pressure, the site is not
/// covered, and a site with no call counts as wrong.
#[test]
fn acute_call_without_adequate_pressure_is_marked() {
    let c = builtin("normal-average").unwrap();
    let two = Protocol::TwoPoint.sites(&c.anatomy);
    let exam = Exam {
        events: vec![press(&two[0].vein, two[0].s, false, false, 2.0)],
        calls: vec![call(&two[0], Finding::AcuteDvt, Finding::Normal, 3.0)],
    };
    let s = score("normal-average", Protocol::TwoPoint, &exam);
    assert!(s.sites[0].called_without_adequate_pressure);
    assert!(!s.sites[0].pressure_adequate);
    assert_eq!(s.sites[1].call, None);
    assert_eq!((s.calls_correct, s.calls_total), (0, 2));
    assert_eq!(s.coverage, 0.0);
    assert_eq!(s.pressure_adequate, 0.0);
    assert!(s.missed.is_empty());
}

/// A press over the free-floating thrombus beyond the 3 N limit counts as
/// excessive; one at 2.5 N, or one at 10 N on a normal stretch, does not.
#[test]
fn excessive_force_over_a_free_floating_thrombus_is_counted() {
    let c = builtin("cfv-free-floating").unwrap();
    let truth = c.ground_truth();
    let (vein, p) = truth
        .iter()
        .find_map(|v| {
            v.pieces
                .iter()
                .find(|p| p.kind == "free_floating")
                .map(|p| (v.vein, *p))
        })
        .expect("the case has a free-floating segment");
    let mid = 0.5 * (p.s_start + p.s_end);
    let exam = Exam {
        events: vec![
            press(vein, mid, false, true, 10.0),
            press(vein, mid, false, false, 2.5),
            press("pv", 0.36, true, false, 10.0),
        ],
        calls: vec![],
    };
    let s = score("cfv-free-floating", Protocol::TwoPoint, &exam);
    assert_eq!(s.excessive_force_on_tail, 1);
    assert_eq!(truth_at(&truth, vein, mid), Some(Finding::AcuteDvt));
}

/// A site on a thrombus's end (the isolated FV thrombus ends at 170 and
/// 230 mm, where whole-leg sites sit): either call is scored right there;
/// 6 mm inside, beyond the 5 mm footprint, only the thrombus is.
#[test]
fn a_site_on_a_thrombus_end_accepts_either_call() {
    let c = builtin("isolated-fv-mid-acute").unwrap();
    let t = c.ground_truth();
    for s in [0.17, 0.23] {
        for f in [Finding::Normal, Finding::AcuteDvt] {
            assert_eq!(truth_for_call(&t, "fv", s, Some(f)), f, "{s}");
        }
        assert_eq!(
            truth_for_call(&t, "fv", s, Some(Finding::ChronicPostThrombotic)),
            truth_at(&t, "fv", s).unwrap()
        );
    }
    assert_eq!(
        truth_for_call(&t, "fv", 0.176, Some(Finding::Normal)),
        Finding::AcuteDvt
    );
    assert_eq!(truth_for_call(&t, "fv", 0.176, None), Finding::AcuteDvt);
}
