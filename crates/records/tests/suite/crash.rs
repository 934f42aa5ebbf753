//! Killing the process mid-exam (SIGKILL: no destructor, no flush) leaves
//! every acknowledged event and call in the database. The child is this
//! test binary re-run on the ignored `crash_child` test: it records until
//! killed, printing each id as its write returns.

use crate::common;

use echothigh_exam::{Call, CompressionEvent, Finding};
use echothigh_records::BlockingStore;
use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

const CHILD_ENV: &str = "ECHOTHIGH_RECORDS_CRASH_CHILD";

fn event(k: u32) -> CompressionEvent {
    CompressionEvent {
        t_start: f64::from(k),
        t_end: f64::from(k) + 0.5,
        vein: Some("fv".into()),
        s: 0.02 * f64::from(k % 20),
        peak_force: 10.0,
        min_lumen_ratio: 0.05,
        artery_deformed: true,
        coapted: true,
        slide: 0.0,
        force_trace: vec![[f64::from(k), 0.0], [f64::from(k) + 0.25, 10.0]],
    }
}

fn call(k: u32) -> Call {
    Call {
        site: format!("fv@{k}"),
        vein: "fv".into(),
        s: 0.02 * f64::from(k % 20),
        finding: Finding::Normal,
        truth: Finding::Normal,
        t: f64::from(k),
    }
}

#[test]
#[ignore = "the child process of every_acknowledged_row_survives_sigkill"]
fn crash_child() {
    let url = std::env::var(CHILD_ENV).expect("run by the crash test");
    let store = BlockingStore::open(Some(&url)).unwrap();
    let t = store.trainee("Ivo").unwrap();
    let s = store.begin_session(&t, "whole-leg").unwrap();
    let mut rec = store.begin_case(s, "normal", &[]).unwrap();
    let mut out = std::io::stdout().lock();
    // A line of its own: the harness has printed `test crash_child ... `.
    writeln!(out, "\ncase {}", rec.case_id().0).unwrap();
    // Bounded: the parent kills it long before; if not, it ends by itself.
    for k in 0..100_000 {
        rec.record_event(&event(k)).unwrap();
        writeln!(out, "event {k}").unwrap();
        rec.record_call(&call(k)).unwrap();
        writeln!(out, "call {k}").unwrap();
        out.flush().unwrap();
    }
}

/// The harness's name of [`crash_child`]: its path below the test binary's
/// crate root (`crash::crash_child` in the crate's suite; with `--exact` a
/// bare `crash_child` matched nothing there, and the child exited at once).
fn child_test_name() -> String {
    match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::crash_child"),
        None => "crash_child".to_owned(),
    }
}

#[test]
fn every_acknowledged_row_survives_sigkill() {
    for db in common::all() {
        let mut child = Command::new(std::env::current_exe().unwrap())
            .args([
                "--ignored",
                "--exact",
                &child_test_name(),
                "--nocapture",
                "--test-threads=1",
            ])
            .env(CHILD_ENV, &db.url)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let (mut case, mut events, mut calls) = (None, Vec::new(), Vec::new());
        // Kill it after 30 acknowledged events, in the middle of its work.
        for line in lines.by_ref() {
            let line = line.unwrap();
            let mut w = line.split_whitespace();
            match (w.next(), w.next().and_then(|n| n.parse::<i64>().ok())) {
                (Some("case"), Some(id)) => case = Some(id),
                (Some("event"), Some(k)) => events.push(k),
                (Some("call"), Some(k)) => calls.push(k),
                _ => continue, // the test harness's own lines
            }
            if events.len() == 30 {
                child.kill().unwrap(); // SIGKILL on Unix
                break;
            }
        }
        // Lines already written before the kill are acknowledged too.
        for line in lines.map_while(Result::ok) {
            let mut w = line.split_whitespace();
            match (w.next(), w.next().and_then(|n| n.parse::<i64>().ok())) {
                (Some("event"), Some(k)) => events.push(k),
                (Some("call"), Some(k)) => calls.push(k),
                _ => {}
            }
        }
        let status = child.wait().unwrap();
        assert!(!status.success(), "{}: the child was not killed", db.kind);
        let case = case.expect("the child printed its case id");

        let store = BlockingStore::open(Some(&db.url)).unwrap();
        let d = store.case_detail(case).unwrap();
        let stored_events: Vec<i64> = d.events.iter().map(|e| e.t_start as i64).collect();
        let stored_calls: Vec<i64> = d.calls.iter().map(|c| c.t as i64).collect();
        for k in &events {
            assert!(
                stored_events.contains(k),
                "{}: acknowledged event {k} lost",
                db.kind
            );
            assert_eq!(d.events[*k as usize], event(*k as u32), "{}", db.kind);
        }
        for k in &calls {
            assert!(
                stored_calls.contains(k),
                "{}: acknowledged call {k} lost",
                db.kind
            );
        }
        // At most the one write in flight at the kill is beyond the acks.
        assert!(stored_events.len() <= events.len() + 1, "{}", db.kind);
        assert!(
            d.score.is_none(),
            "{}: an interrupted case has no score",
            db.kind
        );
    }
}
