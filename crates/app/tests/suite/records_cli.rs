//! `echothigh records import`: a fallback journal (one case begun, one
//! event, one call, the session's end) replayed into a fresh SQLite file
//! adds its four records; a second run adds none and leaves the rows as
//! they were; a damaged line is refused naming the file and the line.

use echothigh_exam::{Call, CompressionEvent, Finding};
use echothigh_records::journal::{Journal, JournalLine, Record, FORMAT};
use echothigh_records::{BlockingStore, CaseKey, SessionKey};
use std::path::Path;
use std::process::Command;

fn line(session: &SessionKey, case: Option<&CaseKey>, record: Record) -> JournalLine {
    JournalLine {
        format: FORMAT,
        session: session.clone(),
        case: case.cloned(),
        record,
    }
}

fn import(file: &Path, db: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(["records", "import", "--json", "--db", db])
        .arg(file)
        .output()
        .unwrap()
}

#[test]
fn a_journal_is_imported_once_whatever_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let session = SessionKey::new("Ravi", "two-point");
    let case = CaseKey::new("normal-average");
    let mut j = Journal::create(dir.path(), "Ravi").unwrap();
    let event = CompressionEvent {
        t_start: 1.0,
        t_end: 2.0,
        vein: Some("cfv".into()),
        s: 0.02,
        peak_force: 12.5,
        min_lumen_ratio: 0.04,
        artery_deformed: true,
        coapted: true,
        slide: 0.0,
        force_trace: vec![[1.0, 0.0], [1.5, 12.5], [2.0, 0.0]],
    };
    let call = Call {
        site: "cfv".into(),
        vein: "cfv".into(),
        s: 0.02,
        finding: Finding::Normal,
        truth: Finding::Normal,
        t: 3.0,
    };
    for l in [
        line(&session, Some(&case), Record::Case { truth: vec![] }),
        line(
            &session,
            Some(&case),
            Record::Event {
                seq: 0,
                event: event.clone(),
            },
        ),
        line(
            &session,
            Some(&case),
            Record::Call {
                seq: 0,
                call: call.clone(),
            },
        ),
        line(
            &session,
            None,
            Record::SessionEnd {
                ended_ms: session.started_ms + 5000,
            },
        ),
    ] {
        j.append(&l).unwrap();
    }
    let db = format!("sqlite://{}", dir.path().join("fresh.sqlite3").display());
    let counts = |out: &std::process::Output| -> (u64, u64, u64) {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let n = |k: &str| v[k].as_u64().unwrap();
        (n("records"), n("added"), n("present"))
    };
    assert_eq!(counts(&import(j.path(), &db)), (4, 4, 0));
    assert_eq!(counts(&import(j.path(), &db)), (4, 0, 4));

    let store = BlockingStore::open(Some(&db)).unwrap();
    let h = store.history("Ravi").unwrap();
    assert_eq!(h.sessions.len(), 1);
    let s = &h.sessions[0];
    assert_eq!(
        (s.started_ms, s.ended_ms),
        (session.started_ms, Some(session.started_ms + 5000))
    );
    assert_eq!(s.cases.len(), 1);
    let d = store.case_detail(s.cases[0].id).unwrap();
    assert_eq!(d.events, vec![event]);
    assert_eq!(d.calls, vec![call]);
    drop(store);

    // A damaged second line: refused, naming the file and the line.
    let bad = dir.path().join("bad.jsonl");
    let text = std::fs::read_to_string(j.path()).unwrap();
    let mut rows: Vec<&str> = text.lines().collect();
    rows[1] = "{\"format\":1,\"session\":";
    std::fs::write(&bad, rows.join("\n") + "\n").unwrap();
    let out = import(&bad, &db);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("fallback journal {}, line 2", bad.display())),
        "{err}"
    );
}
