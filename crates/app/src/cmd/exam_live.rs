//! `echothigh exam --trainee NAME [--protocol P] [--cases DIR | --generate N]
//! [--db URL]` (issue 14): the viewer in exam mode for a trainee, every
//! event, call and score written to the records database as the exam goes.

use super::exam::Args;
use anyhow::{bail, Context, Result};
use echothigh_cases::Case;
use echothigh_exam::Protocol;
use echothigh_records::BlockingStore;
use std::path::Path;

/// The cases of the session: `--cases DIR`, `--generate N`, or the library.
fn cases(args: &Args) -> Result<Vec<Case>> {
    let seed = args.seed.unwrap_or_else(rand::random);
    if let Some(dir) = &args.cases {
        return cases_in(dir);
    }
    if let Some(n) = args.generate {
        if n == 0 {
            bail!("--generate 0: a session needs at least one case");
        }
        let mut g = echothigh_cases::Generator::new(args.prevalence, seed)?;
        return (0..n)
            .map(|_| {
                let d = g.draw();
                let name = d.file.name.clone();
                d.file
                    .load()
                    .with_context(|| format!("generated case {name}"))
            })
            .collect();
    }
    Ok(echothigh_viewer::ExamPlan::practice(seed)?.cases)
}

/// Every `*.toml` case of `dir`, in file-name order.
fn cases_in(dir: &Path) -> Result<Vec<Case>> {
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| format!("--cases {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        bail!("--cases {}: no *.toml case file there", dir.display());
    }
    paths
        .iter()
        .map(|p| {
            let text =
                std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
            echothigh_cases::from_toml_str(&text)
                .with_context(|| format!("case file {}", p.display()))
        })
        .collect()
}

/// The session's plan: `--protocol` and the cases.
fn plan_of(args: &Args, trainee: &str) -> Result<echothigh_viewer::ExamPlan> {
    let protocol = Protocol::from_name(&args.protocol).with_context(|| {
        format!(
            "--protocol `{}`: expected two-point, three-point or whole-leg",
            args.protocol
        )
    })?;
    Ok(echothigh_viewer::ExamPlan {
        trainee: Some(trainee.to_string()),
        protocol,
        cases: cases(args)?,
    })
}

/// The exam session: the trainee's session under this protocol that never
/// ended, resumed (issue 19: a restart of the server keeps it), unless
/// `--new-session`; else a new one. A session whose cases are not among
/// this run's (other `--cases`, another seed of `--generate`) cannot go on:
/// it is ended now, saying so, and a new one begins.
fn session(
    args: &Args,
    store: BlockingStore,
    trainee: &str,
    plan: echothigh_viewer::ExamPlan,
) -> Result<echothigh_viewer::ExamSession> {
    let protocol = plan.protocol.name();
    let (n, describe) = (plan.cases.len(), echothigh_viewer::RecordSink::describe);
    let open = match args.new_session {
        true => None,
        false => store.open_session(trainee, protocol)?,
    };
    if let Some(open) = open {
        let (sink, point) = echothigh_viewer::DbSink::resume(store.clone(), trainee, &open)?;
        let (done, under_way) = (
            point.attempted.iter().filter(|(_, s)| s.is_some()).count(),
            point.open.as_ref().map(|o| o.case.clone()),
        );
        let what = describe(&sink);
        match echothigh_viewer::ExamSession::resume(plan, Box::new(sink), point) {
            Ok(session) => {
                eprintln!(
                    "exam: {trainee}, {protocol} protocol: resuming the session begun at {} (Unix ms), \
                     {done} of {n} cases done{}; {what} (--new-session starts another)",
                    open.key.started_ms,
                    under_way.map_or(String::new(), |c| format!(", case {c} under way"))
                );
                return Ok(session);
            }
            Err(why) => {
                store.end_session_at(open.id, echothigh_records::now_ms())?;
                eprintln!(
                    "exam: {trainee}'s unfinished session (begun at {} Unix ms) cannot go on: {why}; \
                     it is ended now and a new session begins",
                    open.key.started_ms
                );
                // The plan went with the refused resume: build it again.
                return session(args, store, trainee, plan_of(args, trainee)?);
            }
        }
    }
    let sink = echothigh_viewer::DbSink::new(store, trainee)?;
    eprintln!(
        "exam: {trainee}, {protocol} protocol, {n} cases, {}",
        describe(&sink)
    );
    Ok(echothigh_viewer::ExamSession::new(
        plan,
        Box::new(sink),
        false,
    ))
}

/// Runs the viewer in exam mode for `--trainee`.
pub fn run(args: &Args) -> Result<()> {
    let Some(trainee) = args.trainee.as_deref() else {
        bail!("`echothigh exam` needs --trainee NAME (the viewer's exam) or --script FILE --case NAME (headless)");
    };
    if args.case.is_some() || args.json {
        bail!("--case and --json go with --script (a scripted, headless exam)");
    }
    let plan = plan_of(args, trainee)?;
    // The device before the database: a missing driver is said first.
    let kind = echothigh_runtime::scenario::Scenario::default().device.kind;
    let device = super::live_device::open(&args.device, kind)?;
    let store = BlockingStore::open(args.db.as_deref())?;
    let session = session(args, store, trainee, plan)?;
    let view = echothigh_viewer::Args {
        scenario: None,
        port: args.port,
        bind: args.bind,
        allow_remote: args.allow_remote,
        rate: 40.0,
        idle_timeout: 60.0,
        case: None,
    };
    echothigh_viewer::run_with_device(view, None, session, device)
}
