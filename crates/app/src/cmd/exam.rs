//! `echothigh exam --script FILE --case NAME|FILE [--json]` (issue 14): the
//! scripted trainee headless on the virtual clock, and its score.
//!
//! The exam's records go to an [`ExamLog`] as they happen: here a
//! [`MemoryLog`] (printed at the end); `--db URL` (records14's store) plugs
//! in through [`run_with_log`].

use anyhow::{bail, Context, Result};
use clap::Parser;
use echothigh_exam::{CaseScore, ExamLog, MemoryLog};
use echothigh_runtime::exam_run::{run_exam, ExamOutcome};
use echothigh_runtime::exam_script::TraineeScript;
use echothigh_runtime::scenario::read_bounded;
use serde::Serialize;
use std::path::PathBuf;

/// `echothigh exam` arguments: the scripted trainee headless (`--script`
/// with `--case`), or the viewer in exam mode for a trainee (`--trainee`
/// without `--script`, see [`super::exam_live`]).
#[derive(Parser, Debug)]
pub struct Args {
    /// The trainee's script (TOML: protocol, press policy, skipped sites,
    /// calls), e.g. `scenarios/exam-thorough.toml`: runs headless.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// With `--script`: a shipped case's name (`echothigh cases list`) or a
    /// case TOML file.
    #[arg(long)]
    pub case: Option<String>,
    /// With `--script`: print the score as JSON (coverage, calls_correct,
    /// calls_total, pressure_adequate, and per call the site, the call and
    /// the truth).
    #[arg(long)]
    pub json: bool,
    /// The trainee's name: the viewer's exam session is theirs (without
    /// `--script`), or the scripted run is recorded under it (with `--db`).
    #[arg(long)]
    pub trainee: Option<String>,
    /// The records database: `sqlite://PATH` or `postgres://…`; default a
    /// SQLite file under the user's data directory. The viewer's exam always
    /// records; a scripted run records only when `--db` or `--trainee` is given.
    #[arg(long)]
    pub db: Option<String>,
    /// Viewer: the protocol (`two-point`, `three-point`, `whole-leg`).
    #[arg(long, default_value = "three-point")]
    pub protocol: String,
    /// Viewer: the cases to examine, every `*.toml` of DIR in name order
    /// (default: the shipped library in an order drawn from `--seed`).
    #[arg(long, conflicts_with = "generate")]
    pub cases: Option<PathBuf>,
    /// Viewer: examine N cases drawn by the generator (`--prevalence`, `--seed`).
    #[arg(long)]
    pub generate: Option<usize>,
    /// Viewer: the generator's share of acute-DVT cases (practice ~0.5,
    /// realistic 0.10–0.15).
    #[arg(long, default_value_t = echothigh_cases::PRACTICE)]
    pub prevalence: f64,
    /// Viewer: the seed of the case order or of the generator (default: random).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Viewer: start a new session even when the trainee has one that never
    /// ended under this protocol (by default it is resumed: a restart of the
    /// server keeps the exam session).
    #[arg(long)]
    pub new_session: bool,
    /// Viewer: TCP port; 0 picks a free one (the URL printed says which).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Viewer: address to bind; only loopback unless `--allow-remote`.
    #[arg(long, default_value_t = std::net::IpAddr::V4(std::net::Ipv4Addr::LOCALHOST))]
    pub bind: std::net::IpAddr,
    /// Viewer: allow binding a non-loopback address (a classroom station).
    #[arg(long)]
    pub allow_remote: bool,
    /// Viewer: the haptic device that drives the probe (issue 15; default
    /// the page's mouse).
    #[command(flatten)]
    pub device: super::device_arg::DeviceArgs,
}

/// One call in the JSON.
#[derive(Serialize)]
struct JsonCall<'a> {
    site: &'a str,
    vein: &'a str,
    s_mm: f64,
    call: &'static str,
    truth: &'static str,
    correct: bool,
}

/// The JSON report.
#[derive(Serialize)]
struct JsonReport<'a> {
    case: &'a str,
    protocol: &'a str,
    coverage: f64,
    calls_correct: u32,
    calls_total: u32,
    pressure_adequate: f64,
    calls: Vec<JsonCall<'a>>,
    score: &'a CaseScore,
    coverage_strip: &'a [echothigh_exam::CoverageBin],
    events: usize,
    virtual_time_s: f64,
    /// Sites that could not be imaged, and why.
    unexaminable: Vec<[&'a str; 2]>,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    if args.script.is_none() {
        #[cfg(feature = "viewer")]
        return super::exam_live::run(&args);
        #[cfg(not(feature = "viewer"))]
        bail!("this echothigh was built without the viewer: only `exam --script FILE --case NAME` runs");
    }
    if args.device.device.is_some() || args.device.hardware.is_some() {
        bail!("--device and --hardware go with the viewer's exam (--trainee NAME without --script): a scripted exam has no hand on a device");
    }
    let (script, case) = load(&args)?;
    let mut log = MemoryLog::default();
    let out = if args.db.is_some() || args.trainee.is_some() {
        let mut rec = recorder(&args, &case, script.protocol())?;
        let mut tee = Tee(&mut log, &mut rec);
        run_loaded(&args, &script, &case, &mut tee)?
    } else {
        run_loaded(&args, &script, &case, &mut log)?
    };
    if args.json {
        print_json(&log, &out)
    } else {
        print_text(&log, &out);
        Ok(())
    }
}

/// Sends every record to two logs: the printed one and the database's.
struct Tee<'a>(&'a mut MemoryLog, &'a mut dyn ExamLog);

impl ExamLog for Tee<'_> {
    fn event(
        &mut self,
        e: &echothigh_exam::CompressionEvent,
    ) -> Result<(), echothigh_exam::LogError> {
        self.1.event(e)?;
        self.0.event(e)
    }
    fn call(&mut self, c: &echothigh_exam::Call) -> Result<(), echothigh_exam::LogError> {
        self.1.call(c)?;
        self.0.call(c)
    }
    fn doppler(&mut self, c: &echothigh_exam::DopplerCall) -> Result<(), echothigh_exam::LogError> {
        self.1.doppler(c)?;
        self.0.doppler(c)
    }
    fn finish(
        &mut self,
        coverage: &[echothigh_exam::CoverageBin],
        score: &CaseScore,
    ) -> Result<(), echothigh_exam::LogError> {
        self.1.finish(coverage, score)?;
        self.0.finish(coverage, score)
    }
}

/// The trainee a record belongs to: `--trainee`, or `scripted` for a
/// scripted run recorded without one.
fn trainee_name(args: &Args) -> &str {
    args.trainee.as_deref().unwrap_or("scripted")
}

/// Opens the database and a session and case attempt for a scripted run.
pub fn recorder(
    args: &Args,
    case: &echothigh_cases::Case,
    protocol: echothigh_exam::Protocol,
) -> Result<echothigh_records::CaseRecorder> {
    let store = echothigh_records::BlockingStore::open(args.db.as_deref())?;
    let trainee = store.trainee(trainee_name(args))?;
    let session = store.begin_session(&trainee, protocol.name())?;
    Ok(store.begin_case(
        session,
        case.name(),
        &echothigh_records::TruthSegment::of_case(case),
    )?)
}

/// Loads `--script` and `--case`.
fn load(args: &Args) -> Result<(TraineeScript, echothigh_cases::Case)> {
    let (Some(script_path), Some(case_arg)) = (args.script.as_ref(), args.case.as_deref()) else {
        bail!("a scripted exam needs both --script FILE and --case NAME|FILE");
    };
    let origin = script_path.display().to_string();
    let text = read_bounded(script_path).with_context(|| format!("--script {origin}"))?;
    let script = TraineeScript::from_toml_str(&text, &origin)?;
    let case = super::cases::load_case(case_arg)?;
    Ok((script, case))
}

/// Runs the loaded exam into `log` (a [`MemoryLog`], or it and the
/// database's recorder).
fn run_loaded(
    args: &Args,
    script: &TraineeScript,
    case: &echothigh_cases::Case,
    log: &mut dyn ExamLog,
) -> Result<ExamOutcome> {
    let origin = args
        .script
        .as_ref()
        .map_or(String::new(), |p| p.display().to_string());
    run_exam(script, case, log)
        .with_context(|| format!("exam script {origin} on case {}", case.name()))
}

fn print_json(log: &MemoryLog, out: &ExamOutcome) -> Result<()> {
    let s = &out.score;
    let report = JsonReport {
        case: &s.case,
        protocol: &s.protocol,
        coverage: s.coverage,
        calls_correct: s.calls_correct,
        calls_total: s.calls_total,
        pressure_adequate: s.pressure_adequate,
        calls: log
            .calls
            .iter()
            .map(|c| JsonCall {
                site: &c.site,
                vein: &c.vein,
                s_mm: c.s * 1e3,
                call: c.finding.name(),
                truth: c.truth.name(),
                correct: c.is_correct(),
            })
            .collect(),
        score: s,
        coverage_strip: &log.coverage,
        events: log.events.len(),
        virtual_time_s: out.virtual_time,
        unexaminable: out
            .unexaminable
            .iter()
            .map(|(x, why)| [x.name.as_str(), why.as_str()])
            .collect(),
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

fn print_text(log: &MemoryLog, out: &ExamOutcome) {
    let s = &out.score;
    println!("case {} — protocol {}", s.case, s.protocol);
    println!(
        "coverage {:.0} %, calls {}/{} right, adequate pressure in {:.0} % of {} presses",
        100.0 * s.coverage,
        s.calls_correct,
        s.calls_total,
        100.0 * s.pressure_adequate,
        log.events.len()
    );
    println!(
        "time {:.1} s, peak force {:.1} N, mean force {:.1} N, excessive force over a free-floating thrombus: {}",
        s.duration, s.peak_force, s.mean_force, s.excessive_force_on_tail
    );
    for x in &s.sites {
        let call = x.call.map_or("(no call)", |f| f.name());
        let mark = if x.call == Some(x.truth) {
            "ok"
        } else {
            "WRONG"
        };
        let pressure = if x.called_without_adequate_pressure {
            " — called without adequate pressure"
        } else {
            ""
        };
        println!(
            "  {:<12} {:<24} truth {:<24} {mark}{pressure}",
            x.site,
            call,
            x.truth.name()
        );
    }
    for (x, why) in &out.unexaminable {
        println!("  NOT IMAGEABLE: {} ({why})", x.name);
    }
    for m in &s.missed {
        println!(
            "  MISSED: {} from {:.0} to {:.0} mm ({}) was never examined",
            m.vein,
            m.s_start * 1e3,
            m.s_end * 1e3,
            m.truth.name()
        );
    }
}
