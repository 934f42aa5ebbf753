//! A restart of the server keeps the exam session (issue 19): a trainee's
//! session recorded in a real (SQLite) database, its server stopped mid-case,
//! goes on under a new server with the same case open, its presses and calls
//! kept, and its later records joining the same rows.

use super::server::{connect, next_state, send, Client};
use crate::exam::{ExamPlan, ExamSession};
use crate::fake::{z_of, FakeLive};
use crate::{serve_on, DbSink, ServerConfig};
use echothigh_exam::{Finding, Protocol};
use echothigh_records::BlockingStore;
use std::sync::Arc;

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

/// Serves `session` over `fake` until the returned sender fires; the handle
/// ends once the server has stopped (and suspended its exam).
async fn serve(
    fake: Arc<FakeLive>,
    session: ExamSession,
) -> (
    std::net::SocketAddr,
    tokio::sync::oneshot::Sender<()>,
    tokio::task::JoinHandle<()>,
) {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let config = ServerConfig {
        state_rate: 100.0,
        ..ServerConfig::default()
    };
    let handle = tokio::spawn(async move {
        serve_on(listener, fake, config, session, async {
            let _ = rx.await;
        })
        .await
        .unwrap();
    });
    (addr, tx, handle)
}

/// One press at `s` (m) `depth` (m) deep, released, until the exam counts
/// `presses`: 15 mm gives the double's 12 N (a healthy vein closes), 20 mm
/// its 20 N (its artery deforms: adequate over a thrombus).
async fn press(ws: &mut Client, fake: &FakeLive, s: f64, depth: f64, presses: u32) {
    let z = z_of(fake, s);
    send(
        ws,
        &format!(r#"{{"type":"probe","theta":0,"z":{z},"depth":{depth},"tilt":0}}"#),
    )
    .await;
    next_state(ws, |s| s.status.rendered_force[1] > 10.0).await;
    tokio::time::sleep(std::time::Duration::from_millis(200)).await;
    send(ws, r#"{"type":"lift"}"#).await;
    next_state(ws, |s| {
        s.exam.as_ref().is_some_and(|e| e.presses == presses)
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_restarted_server_resumes_the_case_under_way() {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite://{}", dir.path().join("records.sqlite3").display());
    let store = BlockingStore::open(Some(&url)).unwrap();

    // The first server: case 1 opened, the CFV pressed and called, then
    // the server stops.
    let fake = Arc::new(FakeLive::new());
    let sink = DbSink::new(store.clone(), "ada").unwrap();
    let first = ExamSession::new(
        plan(&["popliteal-acute", "normal-average"]),
        Box::new(sink),
        false,
    );
    let (addr, stop, handle) = serve(fake.clone(), first).await;
    let mut ws = connect(addr).await;
    send(&mut ws, r#"{"type":"exam_start"}"#).await;
    let s = next_state(&mut ws, |s| s.exam.as_ref().is_some_and(|e| e.open)).await;
    let sites = s.exam.unwrap().sites;
    press(&mut ws, &fake, sites[0].s, 0.015, 1).await;
    send(
        &mut ws,
        r#"{"type":"exam_call","site":"cfv","finding":"normal"}"#,
    )
    .await;
    next_state(&mut ws, |s| {
        s.exam.as_ref().is_some_and(|e| e.sites[0].call.is_some())
    })
    .await;
    drop(ws);
    stop.send(()).unwrap();
    handle.await.unwrap();

    // The records: the session is still open, its one attempt under way
    // with the press and the call.
    let open = store
        .open_session("ada", "two-point")
        .unwrap()
        .expect("an open session");
    assert_eq!(open.cases.len(), 1);
    let c = &open.cases[0];
    assert_eq!(
        (c.key.name.as_str(), c.finished_ms),
        ("popliteal-acute", None)
    );
    assert_eq!((c.detail.events.len(), c.detail.calls.len()), (1, 1));
    assert!(store.open_session("ada", "three-point").unwrap().is_none());

    // The second server, its plan in another order: the same case is open
    // with its press and call, and its leg loaded.
    let fake = Arc::new(FakeLive::new());
    let (sink, point) = DbSink::resume(store.clone(), "ada", &open).unwrap();
    let resumed = ExamSession::resume(
        plan(&["normal-average", "popliteal-acute"]),
        Box::new(sink),
        point,
    )
    .unwrap();
    let (addr, stop, handle) = serve(fake.clone(), resumed).await;
    let mut ws = connect(addr).await;
    let s = next_state(&mut ws, |s| s.exam.as_ref().is_some_and(|e| e.open)).await;
    assert_eq!(fake.case_name().as_deref(), Some("popliteal-acute"));
    let e = s.exam.unwrap();
    assert_eq!(
        (e.case_number, e.cases_total, e.cases_done, e.presses),
        (1, 2, 0, 1)
    );
    assert_eq!(e.sites[0].call, Some(Finding::Normal));
    assert!(e.sites[0].done && !e.sites[1].done);
    // The popliteal pressed and called; the case finished and scored over
    // both halves.
    press(&mut ws, &fake, e.sites[1].s, 0.02, 2).await;
    send(
        &mut ws,
        r#"{"type":"exam_call","site":"popliteal","finding":"acute_dvt"}"#,
    )
    .await;
    send(&mut ws, r#"{"type":"exam_finish"}"#).await;
    let s = next_state(&mut ws, |s| {
        s.exam.as_ref().is_some_and(|e| e.last.is_some())
    })
    .await;
    let e = s.exam.unwrap();
    let score = e.last.unwrap().score;
    assert_eq!(
        (score.calls_correct, score.calls_total, score.coverage),
        (2, 2, 1.0)
    );
    assert_eq!((e.cases_done, e.calls_correct), (1, 2));
    // The next case is the plan's other one.
    send(&mut ws, r#"{"type":"exam_start"}"#).await;
    next_state(&mut ws, |s| {
        s.exam
            .as_ref()
            .is_some_and(|e| e.open && e.case_number == 2)
    })
    .await;
    assert_eq!(fake.case_name().as_deref(), Some("normal-average"));
    drop(ws);
    stop.send(()).unwrap();
    handle.await.unwrap();

    // One session, its first attempt finished in the same rows (both
    // presses, both calls), the second under way.
    let h = store.history("ada").unwrap();
    assert_eq!(h.sessions.len(), 1);
    let cases = &h.sessions[0].cases;
    assert_eq!(cases.len(), 2);
    let d = store.case_detail(cases[0].id).unwrap();
    assert_eq!((d.events.len(), d.calls.len()), (2, 2));
    assert_eq!(d.score.map(|s| s.calls_correct), Some(2));
    assert!(cases[1].finished_ms.is_none());
}

/// A session whose cases are not among the new plan's is refused, naming
/// the case; a session not resumed by its protocol is not found.
#[test]
fn a_session_of_other_cases_is_not_resumed() {
    use crate::exam::ResumePoint;
    let point = ResumePoint {
        attempted: vec![("popliteal-acute".into(), None)],
        open: None,
    };
    let sink = crate::MemorySink::default();
    let Err(e) = ExamSession::resume(plan(&["normal-average"]), Box::new(sink), point) else {
        panic!("resumed a session with a case not in the plan");
    };
    assert!(e.contains("`popliteal-acute`"), "{e}");
}
