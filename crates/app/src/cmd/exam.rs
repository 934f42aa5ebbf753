//! `echothigh exam --script FILE --case NAME|FILE [--json]` (issue 14): the
//! scripted trainee headless on the virtual clock, and its score.
//!
//! The exam's records go to an [`ExamLog`] as they happen: here a
//! [`MemoryLog`] (printed at the end); `--db URL` (records14's store) plugs
//! in through [`run_with_log`].

use anyhow::{Context, Result};
use clap::Parser;
use echothigh_exam::{CaseScore, ExamLog, MemoryLog};
use echothigh_runtime::exam_run::{run_exam, ExamOutcome};
use echothigh_runtime::exam_script::TraineeScript;
use echothigh_runtime::scenario::read_bounded;
use serde::Serialize;
use std::path::PathBuf;

/// `echothigh exam` arguments (the scripted trainee).
#[derive(Parser, Debug)]
pub struct Args {
    /// The trainee's script (TOML: protocol, press policy, skipped sites,
    /// calls), e.g. `scenarios/exam-thorough.toml`.
    #[arg(long)]
    pub script: PathBuf,
    /// A shipped case's name (`echothigh cases list`) or a case TOML file.
    #[arg(long)]
    pub case: String,
    /// Print the score as JSON (coverage, calls_correct, calls_total,
    /// pressure_adequate, and per call the site, the call and the truth).
    #[arg(long)]
    pub json: bool,
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
    let mut log = MemoryLog::default();
    let out = run_with_log(&args, &mut log)?;
    if args.json {
        print_json(&log, &out)
    } else {
        print_text(&log, &out);
        Ok(())
    }
}

/// Loads the script and the case and runs the exam into `log` (the seam
/// for a database-backed [`ExamLog`]).
pub fn run_with_log(args: &Args, log: &mut dyn ExamLog) -> Result<ExamOutcome> {
    let origin = args.script.display().to_string();
    let text = read_bounded(&args.script).with_context(|| format!("--script {origin}"))?;
    let script = TraineeScript::from_toml_str(&text, &origin)?;
    let case = super::cases::load_case(&args.case)?;
    run_exam(&script, &case, log)
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
