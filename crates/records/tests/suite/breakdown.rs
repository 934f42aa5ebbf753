//! The instructor's per-site breakdown read back from the database equals
//! hand-computed values on a fixed set of cases, on SQLite and on
//! PostgreSQL.
//!
//! The fixed set (trainee "Ines"), Doppler sites as (site: truth / call),
//! a reading written flow+augments (P phasic, C continuous, A absent):
//!   case A  cfv: P+ / P+ → right        popliteal: P+ / P+ → right
//!           missed: none
//!   case B  cfv: C+ / P+ → pattern wrong, augmentation right
//!           popliteal: A- / A+ → pattern right, augmentation wrong
//!           missed: fv 170–230 mm acute DVT
//!   case C  cfv: P- / none → not called popliteal: A- / A- → right
//!           missed: pv 300–400 mm acute DVT, fv 60–220 mm chronic
//!   case D  unfinished (no score): counted nowhere.
//! Per site: cfv 1 right of 3 sites (1/3), 2 called, pattern right 1,
//!   augmentation right 2; popliteal 2 right of 3 (2/3), 3 called,
//!   pattern right 3, augmentation right 2.
//! Missed: 3 segments, in case order B, C, C.

use crate::common;

use echothigh_exam::{
    CaseScore, DopplerFinding, DopplerScore, DopplerSiteScore, ExamLog, Finding, FlowPattern,
    MissedSegment,
};
use echothigh_records::{BlockingStore, SessionId};
use FlowPattern::*;

fn d(flow: FlowPattern, augments: bool) -> DopplerFinding {
    DopplerFinding { flow, augments }
}

type Site = (&'static str, DopplerFinding, Option<DopplerFinding>);

fn case(
    store: &BlockingStore,
    session: SessionId,
    name: &str,
    doppler: &[Site],
    missed: &[(&str, f64, f64, Finding)],
) {
    let mut rec = store.begin_case(session, name, &[]).unwrap();
    let sites: Vec<DopplerSiteScore> = doppler
        .iter()
        .map(|&(site, truth, call)| DopplerSiteScore {
            site: site.into(),
            call,
            truth,
        })
        .collect();
    let score = CaseScore {
        case: name.into(),
        protocol: "two-point".into(),
        coverage: 1.0,
        calls_correct: 0,
        calls_total: 0,
        pressure_adequate: 0.0,
        excessive_force_on_tail: 0,
        duration: 1.0,
        peak_force: 0.0,
        mean_force: 0.0,
        sites: Vec::new(),
        missed: missed
            .iter()
            .map(|&(vein, a, b, truth)| MissedSegment {
                vein: vein.into(),
                s_start: a,
                s_end: b,
                truth,
            })
            .collect(),
        doppler: DopplerScore {
            correct: sites.iter().filter(|x| x.call == Some(x.truth)).count() as u32,
            total: sites.len() as u32,
            sites,
        },
    };
    rec.finish(&[], &score).unwrap();
}

#[test]
fn per_site_doppler_accuracy_and_missed_segments_equal_the_hand_computed_values() {
    for db in common::all() {
        let store = BlockingStore::open(Some(&db.url)).unwrap();
        let ines = store.trainee("Ines").unwrap();
        let s = store.begin_session(&ines, "two-point").unwrap();
        case(
            &store,
            s,
            "A",
            &[
                ("cfv", d(Phasic, true), Some(d(Phasic, true))),
                ("popliteal", d(Phasic, true), Some(d(Phasic, true))),
            ],
            &[],
        );
        case(
            &store,
            s,
            "B",
            &[
                ("cfv", d(Continuous, true), Some(d(Phasic, true))),
                ("popliteal", d(Absent, false), Some(d(Absent, true))),
            ],
            &[("fv", 0.17, 0.23, Finding::AcuteDvt)],
        );
        case(
            &store,
            s,
            "C",
            &[
                ("cfv", d(Phasic, false), None),
                ("popliteal", d(Absent, false), Some(d(Absent, false))),
            ],
            &[
                ("pv", 0.3, 0.4, Finding::AcuteDvt),
                ("fv", 0.06, 0.22, Finding::ChronicPostThrombotic),
            ],
        );
        store.begin_case(s, "D", &[]).unwrap();
        // Another trainee's rows must not leak into Ines's numbers.
        let other = store.trainee("Jo").unwrap();
        let s2 = store.begin_session(&other, "two-point").unwrap();
        case(
            &store,
            s2,
            "A",
            &[("cfv", d(Phasic, true), Some(d(Absent, false)))],
            &[("cfv", 0.0, 0.06, Finding::AcuteDvt)],
        );

        let h = store.history("Ines").unwrap();
        let k = db.kind;
        assert_eq!(h.doppler.len(), 2, "{k}");
        let (cfv, pop) = (&h.doppler[0], &h.doppler[1]);
        assert_eq!(
            (cfv.site.as_str(), cfv.correct, cfv.total, cfv.called),
            ("cfv", 1, 3, 2),
            "{k}"
        );
        assert_eq!((cfv.flow_correct, cfv.augments_correct), (1, 2), "{k}");
        assert_eq!(
            (pop.site.as_str(), pop.correct, pop.total, pop.called),
            ("popliteal", 2, 3, 3),
            "{k}"
        );
        assert_eq!((pop.flow_correct, pop.augments_correct), (3, 2), "{k}");
        // One IEEE division each: exact.
        assert_eq!(cfv.accuracy(), Some(1.0 / 3.0), "{k}");
        assert_eq!(pop.accuracy(), Some(2.0 / 3.0), "{k}");
        let missed: Vec<(&str, &str, f64, f64, Finding)> = h
            .missed
            .iter()
            .map(|m| {
                let s = &m.segment;
                (
                    m.case.as_str(),
                    s.vein.as_str(),
                    s.s_start,
                    s.s_end,
                    s.truth,
                )
            })
            .collect();
        assert_eq!(
            missed,
            [
                ("B", "fv", 0.17, 0.23, Finding::AcuteDvt),
                ("C", "pv", 0.3, 0.4, Finding::AcuteDvt),
                ("C", "fv", 0.06, 0.22, Finding::ChronicPostThrombotic),
            ],
            "{k}"
        );
    }
}
