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

/// Runs the viewer in exam mode for `--trainee`.
pub fn run(args: &Args) -> Result<()> {
    let Some(trainee) = args.trainee.as_deref() else {
        bail!("`echothigh exam` needs --trainee NAME (the viewer's exam) or --script FILE --case NAME (headless)");
    };
    if args.case.is_some() || args.json {
        bail!("--case and --json go with --script (a scripted, headless exam)");
    }
    let protocol = Protocol::from_name(&args.protocol).with_context(|| {
        format!(
            "--protocol `{}`: expected two-point, three-point or whole-leg",
            args.protocol
        )
    })?;
    let plan = echothigh_viewer::ExamPlan {
        trainee: Some(trainee.to_string()),
        protocol,
        cases: cases(args)?,
    };
    // The device before the database: a missing driver is said first.
    let kind = echothigh_runtime::scenario::Scenario::default().device.kind;
    let device = super::live_device::open(&args.device, kind)?;
    let store = BlockingStore::open(args.db.as_deref())?;
    let sink = echothigh_viewer::DbSink::new(store, trainee)?;
    eprintln!(
        "exam: {trainee}, {} protocol, {} cases, {}",
        protocol.name(),
        plan.cases.len(),
        echothigh_viewer::RecordSink::describe(&sink)
    );
    let session = echothigh_viewer::ExamSession::new(plan, Box::new(sink), false);
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
