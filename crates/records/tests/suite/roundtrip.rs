//! Every recorded type goes in and comes back bit-identical, on SQLite and
//! on PostgreSQL; trainees are validated; the blocking store works from
//! inside a tokio multi-thread runtime.

use crate::common;

use echothigh_exam::{
    BinState, Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall, DopplerFinding,
    DopplerScore, DopplerSiteScore, ExamLog, Finding, FlowPattern, SiteScore,
};
use echothigh_records::{BlockingStore, RecordsError, TruthSegment};

fn event(k: usize, vein: Option<&str>) -> CompressionEvent {
    let t = k as f64 * 1.7;
    CompressionEvent {
        t_start: t,
        t_end: t + 0.913,
        vein: vein.map(str::to_string),
        // Values with full mantissas (not short decimals) so that a lossy
        // float path (f32, decimal text) would show.
        s: 0.1 + k as f64 * std::f64::consts::PI * 1e-3,
        peak_force: 14.0 / 3.0,
        min_lumen_ratio: 1.0 / 7.0,
        artery_deformed: k.is_multiple_of(2),
        coapted: k.is_multiple_of(3),
        slide: 2.0f64.sqrt() * 1e-3,
        force_trace: (0..17)
            .map(|i| [t + i as f64 * 0.02, (i as f64).sin().abs() * 9.81])
            .collect(),
    }
}

fn score(case: &str) -> CaseScore {
    CaseScore {
        case: case.into(),
        protocol: "three-point".into(),
        coverage: 2.0 / 3.0,
        calls_correct: 2,
        calls_total: 3,
        pressure_adequate: 0.6,
        excessive_force_on_tail: 1,
        duration: 123.456,
        peak_force: 21.25,
        mean_force: 11.0 / 9.0,
        sites: vec![
            SiteScore {
                site: "cfv".into(),
                call: Some(Finding::Normal),
                truth: Finding::Normal,
                pressure_adequate: true,
                called_without_adequate_pressure: false,
            },
            SiteScore {
                site: "fv-mid".into(),
                call: Some(Finding::AcuteDvt),
                truth: Finding::AcuteDvt,
                pressure_adequate: false,
                called_without_adequate_pressure: true,
            },
            SiteScore {
                site: "popliteal".into(),
                call: None,
                truth: Finding::ChronicPostThrombotic,
                pressure_adequate: false,
                called_without_adequate_pressure: false,
            },
        ],
        missed: vec![echothigh_exam::MissedSegment {
            vein: "fv".into(),
            s_start: 0.17,
            s_end: 0.2300000000000001,
            truth: Finding::AcuteDvt,
        }],
        // A called site and an uncalled one (NULL columns).
        doppler: DopplerScore {
            correct: 1,
            total: 2,
            sites: vec![
                DopplerSiteScore {
                    site: "cfv".into(),
                    call: Some(DopplerFinding {
                        flow: FlowPattern::Continuous,
                        augments: true,
                    }),
                    truth: DopplerFinding {
                        flow: FlowPattern::Continuous,
                        augments: true,
                    },
                },
                DopplerSiteScore {
                    site: "popliteal".into(),
                    call: None,
                    truth: DopplerFinding {
                        flow: FlowPattern::Absent,
                        augments: false,
                    },
                },
            ],
        },
    }
}

#[test]
fn every_type_round_trips_on_every_backend() {
    for db in common::all() {
        let store =
            BlockingStore::open(Some(&db.url)).unwrap_or_else(|e| panic!("{}: {e}", db.kind));
        let ana = store.trainee("Ana Ferreira").unwrap();
        // Get-or-create: the same name is the same trainee.
        assert_eq!(store.trainee("Ana Ferreira").unwrap(), ana, "{}", db.kind);
        let session = store.begin_session(&ana, "three-point").unwrap();
        let truth = vec![
            TruthSegment {
                vein: "fv".into(),
                s_start: 0.0,
                s_end: 0.155,
                kind: "normal".into(),
            },
            TruthSegment {
                vein: "fv".into(),
                s_start: 0.155,
                s_end: 0.31,
                kind: "free_floating".into(),
            },
        ];
        let mut rec = store.begin_case(session, "isolated-fv", &truth).unwrap();
        let events: Vec<_> = (0..4)
            .map(|k| event(k, if k == 3 { None } else { Some("fv") }))
            .collect();
        for e in &events {
            rec.event(e).unwrap();
        }
        let calls: Vec<_> = Finding::ALL
            .iter()
            .enumerate()
            .map(|(i, &f)| Call {
                site: format!("fv@{}", 100 + i),
                vein: "fv".into(),
                s: 0.1 + i as f64 / 3.0,
                finding: f,
                truth: Finding::ALL[(i + 1) % 4],
                t: 10.0 + i as f64 / 7.0,
            })
            .collect();
        for c in &calls {
            rec.call(c).unwrap();
        }
        // Every pattern with and without augmentation, truth shifted by one.
        let doppler: Vec<_> = FlowPattern::ALL
            .iter()
            .flat_map(|&flow| [false, true].map(|augments| DopplerFinding { flow, augments }))
            .enumerate()
            .map(|(i, finding)| DopplerCall {
                site: if i % 2 == 0 { "cfv" } else { "popliteal" }.into(),
                vein: "cfv".into(),
                s: 0.03 + i as f64 / 9.0,
                finding,
                truth: DopplerFinding {
                    flow: FlowPattern::ALL[(i + 1) % 3],
                    augments: i % 3 == 0,
                },
                t: 20.0 + i as f64 / 11.0,
            })
            .collect();
        for c in &doppler {
            rec.doppler(c).unwrap();
        }
        let states = [
            BinState::NotExamined,
            BinState::InadequatePressure,
            BinState::NotClosed,
            BinState::Closed,
        ];
        let coverage: Vec<_> = states
            .iter()
            .enumerate()
            .map(|(i, &state)| CoverageBin {
                vein: "fv".into(),
                s_start: i as f64 * 0.02,
                s_end: (i + 1) as f64 * 0.02,
                state,
            })
            .collect();
        let sc = score("isolated-fv");
        rec.finish(&coverage, &sc).unwrap();
        store.end_session(session).unwrap();

        let d = store.case_detail(rec.case_id().0).unwrap();
        assert_eq!(d.case, "isolated-fv");
        assert_eq!(d.truth, truth, "{}", db.kind);
        assert_eq!(d.events, events, "{}", db.kind);
        assert_eq!(d.calls, calls, "{}", db.kind);
        assert_eq!(d.doppler_calls, doppler, "{}", db.kind);
        assert_eq!(d.coverage, coverage, "{}", db.kind);
        assert_eq!(d.score.as_ref(), Some(&sc), "{}", db.kind);

        let h = store.history("Ana Ferreira").unwrap();
        assert_eq!(h.sessions.len(), 1);
        assert_eq!(h.sessions[0].protocol, "three-point");
        assert!(h.sessions[0]
            .ended_ms
            .is_some_and(|e| e >= h.sessions[0].started_ms));
        assert_eq!(
            h.sessions[0].cases[0].score.as_ref().unwrap().mean_force,
            11.0 / 9.0
        );
    }
}

#[test]
fn names_are_validated_and_unknown_trainees_named() {
    let db = common::sqlite();
    let store = BlockingStore::open(Some(&db.url)).unwrap();
    for bad in ["", "   ", " Ana", "Ana\n", &"x".repeat(65)] {
        let e = store.trainee(bad).unwrap_err();
        assert!(matches!(e, RecordsError::BadName { .. }), "{bad:?}: {e}");
    }
    // 64 characters (multi-byte ones) are accepted.
    store.trainee(&"é".repeat(64)).unwrap();
    let e = store.history("Nobody").unwrap_err();
    assert!(matches!(e, RecordsError::UnknownTrainee { .. }), "{e}");
    assert!(
        e.to_string().contains("Nobody") && e.to_string().contains("records.sqlite3"),
        "{e}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn blocking_store_works_inside_a_multi_thread_runtime() {
    // An axum handler's situation: a tokio worker thread. Entering a second
    // runtime here would panic; the records thread never does.
    let db = common::sqlite();
    let store = BlockingStore::open(Some(&db.url)).unwrap();
    let t = store.trainee("Bo").unwrap();
    let s = store.begin_session(&t, "two-point").unwrap();
    let mut rec = store.begin_case(s, "normal", &[]).unwrap();
    rec.event(&event(0, Some("cfv"))).unwrap();
    // And the async store opened on this runtime reads the same rows.
    let a = echothigh_records::Store::open(Some(&db.url)).await.unwrap();
    let d = a.case_detail(rec.case_id().0).await.unwrap();
    assert_eq!(d.events, vec![event(0, Some("cfv"))]);
}
