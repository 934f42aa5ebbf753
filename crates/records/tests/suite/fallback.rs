//! A database that fails mid-exam loses no record (issue 14, "nothing
//! lost under faults"): a two-case session recorded through
//! [`SessionRecorder`] on a database that breaks during the first case's
//! third press. The faults are real, not mocked:
//! - SQLite: a directory is put where SQLite creates its rollback journal
//!   (`<file>-journal`), so every write transaction fails to open it, as
//!   on a directory turned read-only. The tests run as root, where `chmod`
//!   does not stop writes; a directory in the journal's place stops root
//!   too (`open(2)` of a directory for writing is `EISDIR`).
//! - PostgreSQL (when `ECHOTHIGH_TEST_POSTGRES` names a server): the
//!   exam's database is closed to connections (`ALLOW_CONNECTIONS false`)
//!   and its open connections are killed (`pg_terminate_backend`), as when
//!   the server stops or the network drops; new connections are refused.
//!
//! Each asserts: every event and call is in memory (the `CaseExam`s) and,
//! from the fault on, in the journal; the fault's message names the
//! database and the journal; importing the journal into a fresh database
//! gives exactly the rows of the same exam recorded on a database that
//! never failed (every column but row ids, times and unique ids); a second
//! import adds nothing; once the database is healed, importing into it adds
//! only the missing rows (the same rows again).

use crate::common;

use common::TestDb;
use echothigh_exam::{
    CaseExam, DopplerFinding, ExamLog, ExamSample, Finding, FlowPattern, Protocol,
};
use echothigh_records::journal::{self, Record};
use echothigh_records::{BlockingStore, SessionRecorder, TruthSegment};
use sqlx::{Connection, Row};

/// Cases of the session.
const CASES: [&str; 2] = ["normal-average", "popliteal-acute"];
/// The fault strikes after this many presses of the first case.
const FAULT_AFTER: usize = 2;

/// One exam of both cases, every record through `rec`; `fault` runs after
/// the first case's `FAULT_AFTER`-th press. Returns the cases as examined.
fn exam(rec: &SessionRecorder, fault: &mut dyn FnMut()) -> Vec<CaseExam> {
    let mut done = Vec::new();
    for (c, name) in CASES.iter().enumerate() {
        let case = echothigh_cases::builtin(name).unwrap();
        let mut log = rec.begin_case("two-point", name, &TruthSegment::of_case(&case));
        let mut x = CaseExam::new(&case, Protocol::TwoPoint);
        let sites = x.sites().to_vec();
        let mut t = 0.0;
        for k in 0..4 {
            let site = &sites[k % 2];
            let vein = if site.vein == "cfv" { "cfv" } else { "pv" };
            for j in 0..=100 {
                let u = f64::from(j) / 100.0;
                let f = 12.0 * (1.0 - (2.0 * u - 1.0).abs());
                let s = ExamSample {
                    t: t + 2.0 * u,
                    force: f,
                    skin: [site.s, 0.0],
                    vein: Some(vein),
                    s: site.s,
                    vein_ratio: 1.0 - f / 12.5,
                    artery_ratio: 1.0 - f / 60.0,
                };
                // A failed write is the log's error; the record is kept.
                let _ = x.observe(&s, &mut log);
            }
            t += 3.0;
            if c == 0 && k + 1 == FAULT_AFTER {
                fault();
            }
            if k < 2 {
                let _ = x.call(&site.name, Finding::Normal, t, &mut log);
            }
        }
        let d = DopplerFinding {
            flow: FlowPattern::Phasic,
            augments: true,
        };
        let _ = x.call_doppler("cfv", d, t, &mut log);
        let _ = x.finish(t + 1.0, &mut log);
        assert!(
            x.score().is_some(),
            "the score is kept whatever the log said"
        );
        if c == 0 {
            assert_eq!(log.fault(), rec.fault());
        }
        done.push(x);
    }
    let _ = rec.end();
    done
}

/// Every row of every records table, without row ids, times or unique
/// ids (the columns `id`, `*_id`, `*_ms`, `uid`), in insertion order.
fn content(url: &str) -> Vec<(String, Vec<String>)> {
    const TABLES: [&str; 10] = [
        "trainees",
        "sessions",
        "case_attempts",
        "truth_pieces",
        "events",
        "calls",
        "doppler_calls",
        "coverage_bins",
        "site_scores",
        "doppler_site_scores",
    ];
    common::block_on(async {
        sqlx::any::install_default_drivers();
        let mut c = sqlx::AnyConnection::connect(url).await.unwrap();
        let mut out = Vec::new();
        for t in TABLES {
            let rows = sqlx::query(&format!("SELECT * FROM {t} ORDER BY id"))
                .fetch_all(&mut c)
                .await
                .unwrap();
            for r in rows {
                let mut vals = Vec::new();
                for (i, col) in sqlx::Row::columns(&r).iter().enumerate() {
                    let n = sqlx::Column::name(col);
                    if n == "id" || n == "uid" || n.ends_with("_id") || n.ends_with("_ms") {
                        // Times are compared apart: only whether set.
                        if n.ends_with("_ms") {
                            let v: Option<i64> = r.try_get(i).unwrap();
                            vals.push(format!("{n} set: {}", v.is_some()));
                        }
                        continue;
                    }
                    // Exact: floats by their bits.
                    let v = if let Ok(v) = r.try_get::<Option<f64>, _>(i) {
                        format!("{n}={:?}", v.map(f64::to_bits))
                    } else if let Ok(v) = r.try_get::<Option<i64>, _>(i) {
                        format!("{n}={v:?}")
                    } else {
                        format!("{n}={:?}", r.try_get::<Option<String>, _>(i).unwrap())
                    };
                    vals.push(v);
                }
                out.push((t.to_string(), vals));
            }
        }
        c.close().await.ok();
        out
    })
}

/// Row counts per table.
fn counts(rows: &[(String, Vec<String>)]) -> Vec<(String, usize)> {
    let mut v: Vec<(String, usize)> = Vec::new();
    for (t, _) in rows {
        match v.last_mut() {
            Some((l, n)) if l == t => *n += 1,
            _ => v.push((t.clone(), 1)),
        }
    }
    v
}

/// Runs the whole check on `db` with `break_it`/`heal` as the fault.
fn check(db: &TestDb, fresh: TestDb, reference: TestDb, break_it: &dyn Fn(), heal: &dyn Fn()) {
    // The same exam on a database that never fails.
    let good = {
        let store = BlockingStore::open(Some(&reference.url)).unwrap();
        let rec = SessionRecorder::new(store, "Noor").unwrap();
        let x = exam(&rec, &mut || {});
        assert_eq!(rec.fault(), None);
        assert_eq!(rec.journal_path(), None);
        x
    };
    let want = content(&reference.url);

    let store = BlockingStore::open(Some(&db.url)).unwrap();
    let rec = SessionRecorder::new(store.clone(), "Noor").unwrap();
    let got = exam(&rec, &mut || break_it());
    drop(store);

    // In memory: everything, exactly as in the healthy exam.
    for (g, x) in good.iter().zip(&got) {
        assert_eq!(g.events(), x.events());
        assert_eq!(g.calls(), x.calls());
        assert_eq!(g.doppler_calls(), x.doppler_calls());
        assert_eq!(g.score(), x.score());
        assert_eq!(x.events().len(), 4);
    }
    // The page's message names the failure, the database and the journal.
    let path = rec.journal_path().expect("a journal");
    let fault = rec.fault().expect("a fault");
    assert!(fault.contains("the records database failed"), "{fault}");
    assert!(fault.contains(&path.display().to_string()), "{fault}");
    assert!(fault.contains("echothigh records import"), "{fault}");
    if let Some(dir) = &db.dir {
        assert_eq!(path.parent(), Some(dir.path()), "next to the database");
    }
    // The journal: the whole session (2 × (case + 4 events + 2 calls + 1
    // Doppler + finish) + its end = 19 lines), each event and call of
    // memory in its place, the ones after the fault included.
    let j = journal::read(&path).unwrap();
    assert!(!j.torn_tail);
    assert_eq!(j.lines.len(), 19);
    let mut events = Vec::new();
    let mut calls = Vec::new();
    for (_, l) in &j.lines {
        match &l.record {
            Record::Event { event, .. } => events.push(event.clone()),
            Record::Call { call, .. } => calls.push(call.clone()),
            _ => {}
        }
    }
    let mem_events: Vec<_> = got.iter().flat_map(|x| x.events().to_vec()).collect();
    let mem_calls: Vec<_> = got.iter().flat_map(|x| x.calls().to_vec()).collect();
    assert_eq!(events, mem_events);
    assert_eq!(calls, mem_calls);

    // A fresh database: exactly the healthy exam's rows; twice: no more.
    let fresh_store = BlockingStore::open(Some(&fresh.url)).unwrap();
    let first = fresh_store.import_journal(&path).unwrap();
    assert_eq!((first.records, first.added, first.present), (19, 19, 0));
    assert_eq!(content(&fresh.url), want);
    let again = fresh_store.import_journal(&path).unwrap();
    assert_eq!((again.added, again.present), (0, 19));
    assert_eq!(counts(&content(&fresh.url)), counts(&want));
    assert_eq!(content(&fresh.url), want);
    drop(fresh_store);

    // The healed database: the rows written before the fault stay, the
    // missing ones come, none twice.
    heal();
    let healed = BlockingStore::open(Some(&db.url)).unwrap();
    let r = healed.import_journal(&path).unwrap();
    // Before the fault: the session, the first case's line, 2 events and
    // 1 call were in the database.
    assert_eq!((r.added, r.present), (15, 4));
    assert_eq!(content(&db.url), want);
}

#[test]
fn sqlite_failing_mid_case_loses_no_record() {
    let db = common::sqlite();
    let file = db
        .dir
        .as_ref()
        .unwrap()
        .path()
        .join("records.sqlite3-journal");
    let (f1, f2) = (file.clone(), file.clone());
    check(
        &db,
        common::sqlite(),
        common::sqlite(),
        &move || std::fs::create_dir(&f1).unwrap(),
        &move || std::fs::remove_dir(&f2).unwrap(),
    );
}

#[test]
fn postgres_dropping_the_exam_mid_case_loses_no_record() {
    let (Some(db), Some(fresh), Some(reference)) =
        (common::postgres(), common::postgres(), common::postgres())
    else {
        return;
    };
    let base = common::postgres_base().unwrap();
    let name = db.url.rsplit('/').next().unwrap().to_string();
    let n2 = name.clone();
    let b2 = base.clone();
    check(
        &db,
        fresh,
        reference,
        &move || {
            common::execute(
                &base,
                &format!("ALTER DATABASE {name} ALLOW_CONNECTIONS false"),
            );
            common::execute(
                &base,
                &format!(
                    "SELECT pg_terminate_backend(pid)::text FROM pg_stat_activity WHERE datname = '{name}'"
                ),
            );
        },
        &move || common::execute(&b2, &format!("ALTER DATABASE {n2} ALLOW_CONNECTIONS true")),
    );
}
