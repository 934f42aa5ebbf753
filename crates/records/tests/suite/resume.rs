//! A session that never ended is read back whole (issue 19: a restart of
//! the server keeps the exam session), on SQLite and PostgreSQL: its
//! attempts in order with every record, the unfinished one writing on into
//! the same rows; ended sessions, other protocols and unknown trainees are
//! not resumed; and the resumed recorder's journal lines import into a
//! fresh database as the same session.

use crate::common;

use echothigh_exam::{CaseExam, ExamSample, Finding, Protocol};
use echothigh_records::{BlockingStore, SessionRecorder, TruthSegment};

/// One press at the first site of `x` (a healthy vein closing under 12 N),
/// from `t` (s), recorded to `log`; returns its end.
fn press(x: &mut CaseExam, log: &mut dyn echothigh_exam::ExamLog, t: f64) -> f64 {
    let site = x.sites()[0].clone();
    for j in 0..=100 {
        let u = f64::from(j) / 100.0;
        let f = 12.0 * (1.0 - (2.0 * u - 1.0).abs());
        let s = ExamSample {
            t: t + 2.0 * u,
            force: f,
            skin: [site.s, 0.0],
            vein: Some("cfv"),
            s: site.s,
            vein_ratio: 1.0 - f / 12.5,
            artery_ratio: 1.0,
        };
        x.observe(&s, log).unwrap();
    }
    t + 2.0
}

#[test]
fn an_open_session_is_read_back_and_goes_on_in_the_same_rows() {
    for db in common::all() {
        let store = BlockingStore::open(Some(&db.url)).unwrap();
        let k = db.kind;
        assert!(
            store.open_session("ada", "two-point").unwrap().is_none(),
            "{k}: unknown trainee"
        );
        // Case 1 finished, case 2 under way with one press and one call,
        // then the "server" goes (nothing ends the session).
        let rec = SessionRecorder::new(store.clone(), "ada").unwrap();
        let mut scores = Vec::new();
        for (i, name) in ["normal-average", "popliteal-acute"].iter().enumerate() {
            let case = echothigh_cases::builtin(name).unwrap();
            let mut log = rec.begin_case("two-point", name, &TruthSegment::of_case(&case));
            let mut x = CaseExam::new(&case, Protocol::TwoPoint);
            let t = press(&mut x, &mut log, 0.0);
            x.call("cfv", Finding::Normal, t, &mut log).unwrap();
            if i == 0 {
                scores.push(x.finish(t + 1.0, &mut log).unwrap());
            }
        }
        drop(rec);
        assert!(
            store.open_session("ada", "three-point").unwrap().is_none(),
            "{k}: protocol"
        );
        let open = store
            .open_session("ada", "two-point")
            .unwrap()
            .expect("open session");
        assert_eq!(
            (open.key.trainee.as_str(), open.key.protocol.as_str()),
            ("ada", "two-point")
        );
        let names: Vec<_> = open.cases.iter().map(|c| c.key.name.as_str()).collect();
        assert_eq!(names, ["normal-average", "popliteal-acute"], "{k}");
        let (a, b) = (&open.cases[0], &open.cases[1]);
        assert!(a.finished_ms.is_some() && b.finished_ms.is_none(), "{k}");
        assert_eq!(a.detail.score.as_ref(), Some(&scores[0]), "{k}");
        assert_eq!((b.detail.events.len(), b.detail.calls.len()), (1, 1), "{k}");
        // Journal lines: per attempt its case line, event, call, and the
        // first's finish.
        assert_eq!(open.journal_lines().len(), 4 + 3, "{k}");

        // The next "server": the unfinished attempt goes on and finishes.
        let rec = SessionRecorder::resume(store.clone(), "ada", &open).unwrap();
        let case = echothigh_cases::builtin("popliteal-acute").unwrap();
        let mut log = rec.continue_case(b);
        let mut x = CaseExam::resume(
            &case,
            Protocol::TwoPoint,
            b.detail.events.clone(),
            b.detail.calls.clone(),
            b.detail.doppler_calls.clone(),
        );
        let t0 = x.last_time() + 1.0;
        let t = press(&mut x, &mut log, t0);
        x.call("popliteal", Finding::AcuteDvt, t, &mut log).unwrap();
        x.finish(t + 1.0, &mut log).unwrap();
        rec.end().unwrap();
        assert!(
            store.open_session("ada", "two-point").unwrap().is_none(),
            "{k}: ended"
        );
        let h = store.history("ada").unwrap();
        assert_eq!(h.sessions.len(), 1, "{k}: one session");
        let cases = &h.sessions[0].cases;
        assert_eq!(cases.len(), 2, "{k}: no new attempt");
        let d = store.case_detail(cases[1].id).unwrap();
        assert_eq!((d.events.len(), d.calls.len()), (2, 2), "{k}");
        assert!(d.score.is_some(), "{k}: finished");
    }
}
