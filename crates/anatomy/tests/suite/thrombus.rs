//! Thrombus segments (issue 13): validation names the key, the blend at one
//! `s` follows the segment (1 cm inside vs 1 cm outside), and the ground
//! truth covers every vein once.

use echothigh_anatomy::lumen_state::{ACUTE_MIN_RATIO, CHANNEL_MIN_RATIO, CHRONIC_MIN_RATIO};
use echothigh_anatomy::{
    Anatomy, AnatomyError, LumenState, Patient, StructureId, Thrombi, ThrombusSpec,
};

fn anatomy() -> Anatomy {
    Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap()
}

fn spec(vein: &str, s0: f64, s1: f64, kind: &str) -> ThrombusSpec {
    ThrombusSpec {
        vein: vein.into(),
        s_start: s0,
        s_end: s1,
        kind: kind.into(),
        fill: None,
        recanalized: None,
        tail: None,
        echo_db: None,
        distension: None,
        transition: None,
    }
}

fn key_of(e: AnatomyError) -> String {
    match e {
        AnatomyError::Thrombus { key, .. } => key,
        other => panic!("expected a thrombus error, got {other}"),
    }
}

#[test]
fn one_cm_inside_is_occlusive_one_cm_outside_is_healthy() {
    let a = anatomy();
    // Mid-thigh FV (lean male: confluence 60 mm, hiatus 267 mm).
    let t = Thrombi::new(&a, &[spec("fv", 0.15, 0.21, "acute_occlusive")]).unwrap();
    let inside = t.state(StructureId::Fv, 0.16);
    let outside = t.state(StructureId::Fv, 0.14);
    // 1 cm from the end with a 4 mm transition centred on it: the weight is
    // exactly 1 inside (10 mm > 2 mm) and exactly 0 outside.
    assert_eq!(inside.fill, 1.0);
    assert_eq!(inside.min_lumen_ratio(), ACUTE_MIN_RATIO);
    assert!((inside.distension - 1.18).abs() < 1e-12);
    assert_eq!(outside, LumenState::HEALTHY);
    assert_eq!(outside.min_lumen_ratio(), 0.0);
    // Another vein at the same s is untouched.
    assert_eq!(t.state(StructureId::Gsv, 0.16), LumenState::HEALTHY);
    // Half weight at the end itself, and monotone through the transition.
    let end = t.state(StructureId::Fv, 0.15);
    assert!((end.fill - 0.5).abs() < 1e-12);
    let mut last = 0.0;
    for i in 0..=40 {
        let s = 0.147 + i as f64 * 1.5e-4;
        let f = t.state(StructureId::Fv, s).fill;
        assert!(f >= last - 1e-15, "fill decreases at s = {s}");
        last = f;
    }
    assert_eq!(last, 1.0);
}

#[test]
fn non_occlusive_and_chronic_compress_partly() {
    let a = anatomy();
    let mut non = spec("fv", 0.10, 0.16, "acute_non_occlusive");
    non.fill = Some(0.4);
    let mut chr = spec("pv", 0.30, 0.36, "chronic");
    chr.recanalized = Some(0.6);
    let t = Thrombi::new(&a, &[non, chr]).unwrap();
    let n = t.state(StructureId::Fv, 0.13);
    // fill · 0.8 + (1 − fill) · 0 = 0.32: between healthy (0) and occlusive (0.8).
    assert!((n.min_lumen_ratio() - 0.4 * ACUTE_MIN_RATIO).abs() < 1e-12);
    let c = t.state(StructureId::Pv, 0.33);
    let expect = 0.4 * CHRONIC_MIN_RATIO + 0.6 * CHANNEL_MIN_RATIO;
    assert!((c.min_lumen_ratio() - expect).abs() < 1e-12);
    assert!(c.min_lumen_ratio() > 0.1 && c.min_lumen_ratio() < 0.95);
    assert!(c.wall_thickness > 1.4e-3 && c.distension < 1.0);
    assert_eq!(c.chronic, 1.0);
}

#[test]
fn free_floating_tail_is_central_then_attached() {
    let a = anatomy();
    let mut ff = spec("cfv", 0.005, 0.055, "free_floating");
    ff.tail = Some(0.02);
    let t = Thrombi::new(&a, &[ff]).unwrap();
    let tail = t.state(StructureId::Cfv, 0.015);
    assert_eq!(tail.layout, echothigh_anatomy::Layout::Central);
    assert_eq!(tail.free_floating, 1.0);
    assert!((tail.fill - 0.35).abs() < 1e-12);
    let attached = t.state(StructureId::Cfv, 0.045);
    assert_eq!(attached.fill, 1.0);
    assert_eq!(attached.free_floating, 0.0);
}

/// The tail's sway: the cantilever shape `ξ² (6 − 4ξ + ξ²)/3` of the
/// distance from the attachment (s_start + tail = 25 mm) to the free tip
/// (s_start = 5 mm): 0 at and beyond the attachment, rising monotonically
/// towards the tip, and the analytic value inside the tail where the
/// segment's weight is 1 (e.g. ξ = 0.5 at 15 mm: 0.25 · 4.25 / 3).
#[test]
fn free_tail_sways_most_at_its_tip() {
    let a = anatomy();
    let mut ff = spec("cfv", 0.005, 0.055, "free_floating");
    ff.tail = Some(0.02);
    let t = Thrombi::new(&a, &[ff]).unwrap();
    let sway = |s: f64| t.state(StructureId::Cfv, s).sway;
    assert_eq!(sway(0.03), 0.0);
    assert_eq!(sway(0.045), 0.0);
    assert!((sway(0.015) - 0.25 * 4.25 / 3.0).abs() < 1e-12);
    let mut last = 0.0;
    for k in 0..=18 {
        // From the attachment to 7 mm (2 mm from the tip: the segment's
        // weight is 1 from s_start + transition/2 on).
        let s = 0.025 - k as f64 * 1e-3;
        let w = sway(s);
        assert!(w >= last, "sway falls towards the tip at {s}");
        last = w;
    }
    // ξ = 0.9 at 7 mm: 0.81 · 3.21 / 3.
    assert!(
        (last - 0.81 * 3.21 / 3.0).abs() < 1e-12,
        "sway near the tip {last}"
    );
    assert_eq!(echothigh_anatomy::tail_sway(1.0), 1.0);
    assert_eq!(echothigh_anatomy::tail_sway(0.0), 0.0);
}

#[test]
fn abutting_segments_blend_without_a_gap() {
    let a = anatomy();
    let t = Thrombi::new(
        &a,
        &[
            spec("fv", 0.10, 0.15, "chronic"),
            spec("fv", 0.15, 0.20, "acute_occlusive"),
        ],
    )
    .unwrap();
    // Equal transitions: the two weights sum to 1 through the shared one,
    // so the acute + chronic weights are 1 everywhere in it.
    for i in 0..=20 {
        let s = 0.148 + i as f64 * 2e-4;
        let st = t.state(StructureId::Fv, s);
        assert!(
            (st.acute + st.chronic - 1.0).abs() < 1e-12,
            "gap at s = {s}"
        );
    }
}

#[test]
fn bad_segments_name_the_key() {
    let a = anatomy();
    let cases: Vec<(Vec<ThrombusSpec>, &str)> = vec![
        (
            vec![
                spec("fv", 0.10, 0.15, "acute_occlusive"),
                spec("fv", 0.14, 0.20, "chronic"),
            ],
            "thrombus[1].s_start",
        ),
        (
            vec![spec("fv", 0.01, 0.05, "acute_occlusive")],
            "thrombus[0].s_start",
        ),
        (
            vec![spec("cfv", 0.01, 0.09, "acute_occlusive")],
            "thrombus[0].s_end",
        ),
        (
            vec![spec("sfv", 0.10, 0.15, "acute_occlusive")],
            "thrombus[0].vein",
        ),
        (
            vec![spec("fv2", 0.15, 0.20, "acute_occlusive")],
            "thrombus[0].vein",
        ),
        (vec![spec("fv", 0.10, 0.15, "subacute")], "thrombus[0].kind"),
        (
            vec![spec("fv", f64::NAN, 0.15, "acute_occlusive")],
            "thrombus[0].s_start",
        ),
        (
            vec![spec("fv", 0.10, 0.103, "acute_occlusive")],
            "thrombus[0].s_end",
        ),
    ];
    for (specs, key) in cases {
        let e = Thrombi::new(&a, &specs).unwrap_err();
        let msg = e.to_string();
        assert_eq!(key_of(e), key, "{msg}");
    }
    let mut wrong = spec("fv", 0.10, 0.15, "acute_occlusive");
    wrong.recanalized = Some(0.5);
    assert_eq!(
        key_of(Thrombi::new(&a, &[wrong]).unwrap_err()),
        "thrombus[0].recanalized"
    );
    let mut nan = spec("fv", 0.10, 0.15, "acute_non_occlusive");
    nan.fill = Some(f64::NAN);
    assert_eq!(
        key_of(Thrombi::new(&a, &[nan]).unwrap_err()),
        "thrombus[0].fill"
    );
}

#[test]
fn ground_truth_covers_each_vein_once() {
    let mut p = Patient::preset("average-female").unwrap();
    p.duplicated_fv = true;
    let a = Anatomy::new(p).unwrap();
    let fv2 = a.tube(StructureId::Fv2).unwrap().s_range();
    let mid = 0.5 * (fv2.0 + fv2.1);
    let t = Thrombi::new(
        &a,
        &[
            spec("fv2", mid - 0.02, mid + 0.02, "acute_occlusive"),
            spec("cfv", 0.0, 0.03, "chronic"),
        ],
    )
    .unwrap();
    let truth = t.ground_truth(&a);
    let veins: Vec<&str> = truth.iter().map(|v| v.vein).collect();
    for v in ["cfv", "fv", "pv", "gsv", "dfv", "fv2"] {
        assert_eq!(
            veins.iter().filter(|&&x| x == v).count(),
            1,
            "{v} in {veins:?}"
        );
    }
    for v in &truth {
        let id = a
            .tubes()
            .iter()
            .find(|t| t.id().as_str() == v.vein)
            .unwrap();
        let (lo, hi) = id.s_range();
        assert_eq!(v.pieces.first().unwrap().s_start, lo);
        assert_eq!(v.pieces.last().unwrap().s_end, hi);
        for w in v.pieces.windows(2) {
            assert_eq!(w[0].s_end, w[1].s_start, "{}: gap or overlap", v.vein);
        }
    }
    let fv2t = truth.iter().find(|v| v.vein == "fv2").unwrap();
    assert_eq!(fv2t.pieces.len(), 3);
    assert_eq!(fv2t.pieces[1].kind, "acute_occlusive");
}
