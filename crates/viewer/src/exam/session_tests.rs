use super::*;
use crate::exam::sink::MemorySink;
use echothigh_exam::{BinState, Protocol};

fn plan(names: &[&str]) -> ExamPlan {
    ExamPlan {
        trainee: Some("ada".into()),
        protocol: Protocol::TwoPoint,
        cases: names
            .iter()
            .map(|n| echothigh_cases::builtin(n).unwrap())
            .collect(),
    }
}

/// A sample over `site` with force `f` (N) and the vein's ratio `r`.
fn sample(t: f64, f: f64, vein: &'static str, s: f64, r: f64) -> ExamSample {
    ExamSample {
        t,
        force: f,
        skin: [s, 0.0],
        vein: Some(vein),
        s,
        vein_ratio: r,
        artery_ratio: 1.0,
    }
}

#[test]
fn a_case_is_examined_scored_and_revealed_only_when_finished() {
    let sink = MemorySink::default();
    let mut x = ExamSession::new(
        plan(&["normal-average", "popliteal-acute"]),
        Box::new(sink.clone()),
        false,
    );
    assert!(!x.status().active);
    let name = x.start().unwrap().file.name.clone();
    assert_eq!(name, "normal-average");
    let st = x.status().clone();
    assert!(
        st.active && st.open && st.last.is_none(),
        "the truth stays hidden while open"
    );
    assert_eq!((st.case_number, st.cases_total, st.sites.len()), (1, 2, 2));
    assert!(matches!(x.start(), Err(ExamError::CaseOpen(1))));

    // Before the trainee moves the probe, samples do not count (the case's
    // own reset may press the tissue).
    let cfv = st.sites[0].clone();
    assert_eq!(x.case_time(Instant::now()), None);
    x.observe(&sample(0.0, 30.0, "cfv", cfv.s, 0.0)).unwrap();
    x.observe(&sample(0.1, 0.0, "cfv", cfv.s, 1.0)).unwrap();
    assert_eq!(x.status().presses, 0);

    x.trainee_pressed();
    assert!(x.case_time(Instant::now()).is_some());
    let rev = x.status().rev;
    for (k, f) in [0.0, 4.0, 9.0, 4.0, 0.2].into_iter().enumerate() {
        x.observe(&sample(
            1.0 + 0.1 * k as f64,
            f,
            "cfv",
            cfv.s,
            1.0 - f / 10.0,
        ))
        .unwrap();
    }
    let st = x.status().clone();
    assert_eq!(st.presses, 1);
    assert!(st.rev > rev, "the page hears of the press");
    assert!(
        st.sites[0].done,
        "the CFV closed (0.1 at 9 N): its item is done"
    );
    assert_eq!(
        st.coverage
            .iter()
            .filter(|b| b.state == BinState::Closed)
            .count(),
        1
    );

    x.call("cfv", Finding::Normal).unwrap();
    x.call("popliteal", Finding::AcuteDvt).unwrap();
    assert_eq!(x.status().sites[1].call, Some(Finding::AcuteDvt));
    assert!(
        x.call("fv-mid", Finding::Normal).is_err(),
        "not a two-point site"
    );
    x.finish().unwrap();
    let st = x.status().clone();
    assert!(!st.open && st.sites.is_empty());
    let last = st.last.expect("revealed");
    assert_eq!(
        (last.case.as_str(), last.diagnosis.as_str()),
        ("normal-average", "normal")
    );
    assert_eq!((last.score.calls_correct, last.score.calls_total), (1, 2));
    assert!(last.truth.iter().all(|t| t.kind == "normal"));
    assert_eq!((st.cases_done, st.calls_correct, st.calls_total), (1, 1, 2));

    // The sink saw the case's records as they happened.
    let cases = sink.cases.lock().unwrap();
    assert_eq!(cases.len(), 1);
    let log = cases[0].1.lock().unwrap();
    assert_eq!((log.events.len(), log.calls.len()), (1, 2));
    assert_eq!(log.score.as_ref(), Some(&last.score));
}

#[test]
fn the_plan_ends_or_cycles() {
    let mut x = ExamSession::new(
        plan(&["normal-average"]),
        Box::new(MemorySink::default()),
        false,
    );
    x.start().unwrap();
    x.finish().unwrap();
    assert!(matches!(x.start(), Err(ExamError::NoMoreCases(1))));
    let mut y = ExamSession::new(
        plan(&["normal-average"]),
        Box::new(MemorySink::default()),
        true,
    );
    for k in 1..=3 {
        y.start().unwrap();
        y.finish().unwrap();
        assert_eq!(y.status().case_number, k);
    }
}

#[test]
fn leaving_drops_the_open_case_unscored() {
    let mut x = ExamSession::new(
        plan(&["normal-average", "popliteal-acute"]),
        Box::new(MemorySink::default()),
        false,
    );
    x.start().unwrap();
    x.stop();
    let st = x.status();
    assert!(!st.active && !st.open && st.last.is_none() && st.cases_done == 0);
    assert!(matches!(x.finish(), Err(ExamError::NoCase)));
    assert!(matches!(
        x.call("cfv", Finding::Normal),
        Err(ExamError::NoCase)
    ));
}

/// One press at the checklist site `k` of the open case (the vein closes
/// at 9 N, as in the first test).
fn press_at(x: &mut ExamSession, k: usize, t0: f64) {
    let site = x.status().sites[k].clone();
    let vein = if site.vein == "cfv" { "cfv" } else { "pv" };
    for (j, f) in [0.0, 4.0, 9.0, 4.0, 0.2].into_iter().enumerate() {
        x.observe(&sample(
            t0 + 0.1 * j as f64,
            f,
            vein,
            site.s,
            1.0 - f / 10.0,
        ))
        .unwrap();
    }
}

/// The database under a live exam fails mid-case. The fault is real: a
/// directory is put where SQLite creates its rollback journal
/// (`records.sqlite3-journal`), so every write fails to open it, as on a
/// directory turned read-only (the tests run as root, where `chmod` does
/// not stop writes; a directory in the way stops root too). The exam goes
/// on without an error to the trainee's commands; the press and call after
/// the fault are counted; the page's `recording` and `error` say the
/// database failed and name the journal; the journal next to the database
/// holds the whole case (case, both presses, the call, the score).
#[test]
fn a_database_failing_mid_case_is_named_on_the_page_and_nothing_is_lost() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("records.sqlite3");
    let store =
        echothigh_records::BlockingStore::open(Some(&format!("sqlite://{}", file.display())))
            .unwrap();
    let sink = crate::exam::sink::DbSink::new(store, "ada").unwrap();
    let mut x = ExamSession::new(plan(&["normal-average"]), Box::new(sink), false);
    x.start().unwrap();
    x.trainee_pressed();
    press_at(&mut x, 0, 1.0);
    assert_eq!(x.status().presses, 1);
    assert!(
        x.status().recording.starts_with("recorded in "),
        "{}",
        x.status().recording
    );
    assert_eq!(x.status().error, None);

    std::fs::create_dir(dir.path().join("records.sqlite3-journal")).unwrap();
    press_at(&mut x, 1, 3.0);
    x.call("cfv", Finding::Normal).unwrap();
    let st = x.status().clone();
    assert_eq!((st.presses, st.sites[0].call), (2, Some(Finding::Normal)));
    let journals: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("records-fallback-ada-")
        })
        .collect();
    assert_eq!(journals.len(), 1, "one journal next to the database");
    let path = journals[0].display().to_string();
    assert!(
        st.recording.contains("the records database failed"),
        "{}",
        st.recording
    );
    assert!(st.recording.contains(&path), "{}", st.recording);
    assert_eq!(st.error.as_deref(), Some(st.recording.as_str()));

    x.finish().unwrap();
    assert_eq!(
        x.status().last.as_ref().map(|l| l.score.calls_total),
        Some(2)
    );
    let j = echothigh_records::journal::read(&journals[0]).unwrap();
    let kinds: Vec<&str> = j.lines.iter().map(|(_, l)| l.record.kind()).collect();
    assert_eq!(kinds, ["case", "event", "event", "call", "finish"]);
}
