//! Sensitivity, specificity, coverage, calls correct and pressure adequacy
//! read back from the database equal hand-computed values on a fixed set of
//! sessions, on SQLite and on PostgreSQL.
//!
//! The fixed set (trainee "Gil"), sites as (site: truth / call):
//! Session 1 (two-point)
//!   case A  cfv: acute / acute → TP      popliteal: normal / normal → TN
//!           coverage 1.0, calls 2/2, presses 2 (both adequate)
//!   case B  cfv: normal / acute → FP     popliteal: acute / indeterminate → FN
//!           coverage 0.5, calls 0/2, presses 2 (1 adequate: coapted only)
//! Session 2 (three-point)
//!   case C  cfv: acute / none → FN       fv-mid: acute / acute → TP
//!           popliteal: chronic / chronic → TN
//!           coverage 0.75, calls 2/3, presses 1 (adequate: artery only)
//!   case D  cfv: normal / indeterminate → unresolved (out of specificity)
//!           popliteal: normal / normal → TN
//!           coverage 0.25, calls 1/2, presses 3 (none adequate)
//!   case E  interrupted (no score): one adequate press, counted nowhere.
//!
//! Session 1: TP 1, FN 1, TN 1, FP 1 → sensitivity 1/2, specificity 1/2;
//!   coverage (1 + 0.5)/2 = 0.75; calls 2/4 = 0.5; pressure 3/4 = 0.75.
//! Session 2: TP 1, FN 1, TN 2, FP 0 → sensitivity 1/2, specificity 2/2 = 1;
//!   coverage (0.75 + 0.25)/2 = 0.5; calls 3/5 = 0.6; pressure 1/4 = 0.25.
//! Overall: TP 2, FN 2, TN 3, FP 1 → sensitivity 2/4 = 0.5, specificity
//!   3/4 = 0.75; coverage 2.5/4 = 0.625; calls 5/9; pressure 4/8 = 0.5.
//! Per site: cfv TP, FP, FN, unresolved → sens 1/2, spec 0/1 = 0;
//!   popliteal TN, FN, TN, TN → sens 0/1 = 0, spec 3/3 = 1;
//!   fv-mid TP → sens 1, spec none.
//! Each value is one IEEE division of small integers (or a sum of dyadic
//! fractions), so the comparisons are exact.

use crate::common;

use echothigh_exam::{CaseScore, CompressionEvent, ExamLog, Finding, SiteScore};
use echothigh_records::{BlockingStore, SessionId};
use Finding::*;

fn press(adequate_artery: bool, coapted: bool) -> CompressionEvent {
    CompressionEvent {
        t_start: 0.0,
        t_end: 1.0,
        vein: Some("cfv".into()),
        s: 0.02,
        peak_force: 12.0,
        min_lumen_ratio: if coapted { 0.0 } else { 0.5 },
        artery_deformed: adequate_artery,
        coapted,
        slide: 0.0,
        force_trace: vec![[0.0, 0.0], [0.5, 12.0]],
    }
}

type Site<'a> = (&'a str, Finding, Option<Finding>);

fn case(
    store: &BlockingStore,
    session: SessionId,
    name: &str,
    sites: &[Site],
    coverage: f64,
    presses: &[(bool, bool)],
) {
    let mut rec = store.begin_case(session, name, &[]).unwrap();
    for &(a, c) in presses {
        rec.event(&press(a, c)).unwrap();
    }
    let correct = sites.iter().filter(|(_, t, c)| *c == Some(*t)).count() as u32;
    let score = CaseScore {
        case: name.into(),
        protocol: "p".into(),
        coverage,
        calls_correct: correct,
        calls_total: sites.len() as u32,
        pressure_adequate: 0.0,
        excessive_force_on_tail: 0,
        duration: 1.0,
        peak_force: 12.0,
        mean_force: 6.0,
        sites: sites
            .iter()
            .map(|&(site, truth, call)| SiteScore {
                site: site.into(),
                call,
                truth,
                pressure_adequate: true,
                called_without_adequate_pressure: false,
            })
            .collect(),
        missed: Vec::new(),
        doppler: Default::default(),
    };
    rec.finish(&[], &score).unwrap();
}

#[test]
fn sensitivity_and_specificity_equal_the_hand_computed_values() {
    for db in common::all() {
        let store = BlockingStore::open(Some(&db.url)).unwrap();
        let gil = store.trainee("Gil").unwrap();
        let s1 = store.begin_session(&gil, "two-point").unwrap();
        let a = [
            ("cfv", AcuteDvt, Some(AcuteDvt)),
            ("popliteal", Normal, Some(Normal)),
        ];
        case(&store, s1, "A", &a, 1.0, &[(true, true), (true, false)]);
        let b = [
            ("cfv", Normal, Some(AcuteDvt)),
            ("popliteal", AcuteDvt, Some(Indeterminate)),
        ];
        case(&store, s1, "B", &b, 0.5, &[(false, true), (false, false)]);
        store.end_session(s1).unwrap();
        let s2 = store.begin_session(&gil, "three-point").unwrap();
        let c = [
            ("cfv", AcuteDvt, None),
            ("fv-mid", AcuteDvt, Some(AcuteDvt)),
            (
                "popliteal",
                ChronicPostThrombotic,
                Some(ChronicPostThrombotic),
            ),
        ];
        case(&store, s2, "C", &c, 0.75, &[(true, false)]);
        let d = [
            ("cfv", Normal, Some(Indeterminate)),
            ("popliteal", Normal, Some(Normal)),
        ];
        case(&store, s2, "D", &d, 0.25, &[(false, false); 3]);
        let mut e = store.begin_case(s2, "E", &[]).unwrap();
        e.event(&press(true, true)).unwrap();
        // Another trainee's rows must not leak into Gil's numbers.
        let other = store.trainee("Hal").unwrap();
        let s3 = store.begin_session(&other, "two-point").unwrap();
        case(
            &store,
            s3,
            "A",
            &[("cfv", AcuteDvt, Some(Normal))],
            0.0,
            &[],
        );

        let h = store.history("Gil").unwrap();
        let k = db.kind;
        assert_eq!(h.sessions.len(), 2, "{k}");
        let (r1, r2) = (&h.sessions[0].rates, &h.sessions[1].rates);
        assert_eq!(
            (r1.sensitivity, r1.specificity),
            (Some(0.5), Some(0.5)),
            "{k}"
        );
        assert_eq!(
            (r1.mean_coverage, r1.calls_correct, r1.pressure_adequacy),
            (Some(0.75), Some(0.5), Some(0.75)),
            "{k}"
        );
        assert_eq!(
            (r2.sensitivity, r2.specificity),
            (Some(0.5), Some(1.0)),
            "{k}"
        );
        assert_eq!(
            (r2.mean_coverage, r2.calls_correct, r2.pressure_adequacy),
            (Some(0.5), Some(0.6), Some(0.25)),
            "{k}"
        );
        assert_eq!(r2.confusion.unresolved_negative, 1, "{k}");
        assert_eq!(r2.cases, 2, "{k}: the interrupted case E is not scored");
        let r = &h.rates;
        assert_eq!(
            (r.sensitivity, r.specificity),
            (Some(0.5), Some(0.75)),
            "{k}"
        );
        assert_eq!(
            (r.mean_coverage, r.calls_correct, r.pressure_adequacy),
            (Some(0.625), Some(5.0 / 9.0), Some(0.5)),
            "{k}"
        );
        let site = |n: &str| h.sites.iter().find(|s| s.site == n).unwrap();
        assert_eq!(
            (site("cfv").sensitivity, site("cfv").specificity),
            (Some(0.5), Some(0.0)),
            "{k}"
        );
        assert_eq!(
            (site("popliteal").sensitivity, site("popliteal").specificity),
            (Some(0.0), Some(1.0)),
            "{k}"
        );
        assert_eq!(
            (site("fv-mid").sensitivity, site("fv-mid").specificity),
            (Some(1.0), None),
            "{k}"
        );

        // The instructor's summary: Gil started 5 cases in 2 sessions.
        let all = store.trainees().unwrap();
        let g = all.iter().find(|t| t.name == "Gil").unwrap();
        assert_eq!((g.sessions, g.cases), (2, 5), "{k}");
        assert_eq!(
            (g.rates.sensitivity, g.rates.specificity),
            (Some(0.5), Some(0.75)),
            "{k}"
        );
        assert!(g.last_seen_ms.is_some(), "{k}");
        let hal = all.iter().find(|t| t.name == "Hal").unwrap();
        assert_eq!(
            (hal.rates.sensitivity, hal.rates.specificity),
            (Some(0.0), None),
            "{k}"
        );
        // All trainees' sites: cfv gains Hal's miss → TP 1, FN 2.
        let cfv = store
            .site_stats()
            .unwrap()
            .into_iter()
            .find(|s| s.site == "cfv")
            .unwrap();
        assert_eq!(cfv.sensitivity, Some(1.0 / 3.0), "{k}");
    }
}
