//! `echothigh cases list|show|generate` (issue 13): the shipped case library
//! (`echothigh-cases`, embedded in the binary), one case's vignette and
//! ground truth, and new cases drawn from documented distributions.
//!
//! `show --json`: `{"name", "title", "patient", "vignette", "diagnosis",
//! "truth": [{"vein", "segments": [{"s_start_mm", "s_end_mm", "kind"}]}]}`;
//! each vein of the leg appears once and its segments cover it end to end.

use anyhow::{bail, Context, Result};
use echothigh_cases::{Case, CaseFile, Generator};
use serde::Serialize;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// `echothigh cases …`.
#[derive(clap::Subcommand, Debug)]
pub enum CasesCommand {
    /// List the shipped cases.
    List {
        /// Print JSON (else a table).
        #[arg(long)]
        json: bool,
    },
    /// One case: vignette and ground truth per vein (s in mm).
    Show {
        /// A shipped case's name or a case TOML file.
        name: String,
        /// Print JSON (else text).
        #[arg(long)]
        json: bool,
    },
    /// Draw new cases (distributions in crates/cases/src/generate.rs) into DIR.
    Generate {
        /// Number of cases.
        #[arg(long)]
        count: usize,
        /// Fraction of acute-DVT cases: practice ~0.5, realistic 0.10–0.15.
        #[arg(long, default_value_t = echothigh_cases::PRACTICE)]
        prevalence: f64,
        /// Generator seed (the same seed gives the same cases).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output directory (created); one `<name>.toml` per case.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Loads `--case`: a shipped case's name, else a case TOML file.
pub fn load_case(arg: &str) -> Result<Case> {
    if echothigh_cases::names().any(|n| n == arg) {
        return Ok(echothigh_cases::builtin(arg)?);
    }
    let path = Path::new(arg);
    if !path.exists() {
        bail!("--case `{arg}` is neither a shipped case (see `echothigh cases list`) nor an existing file");
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {arg}"))?;
    echothigh_cases::from_toml_str(&text).with_context(|| format!("case file {arg}"))
}

#[derive(Serialize)]
struct JsonSegment {
    s_start_mm: f64,
    s_end_mm: f64,
    kind: &'static str,
}

#[derive(Serialize)]
struct JsonVein {
    vein: &'static str,
    segments: Vec<JsonSegment>,
}

#[derive(Serialize)]
struct JsonCase<'a> {
    name: &'a str,
    title: &'a str,
    patient: &'a str,
    variants: Vec<&'static str>,
    vignette: &'a echothigh_cases::Vignette,
    diagnosis: &'static str,
    truth: Vec<JsonVein>,
}

fn json_case(c: &Case) -> JsonCase<'_> {
    let p = c.anatomy.patient();
    let variants = [
        (p.duplicated_fv, "duplicated_fv"),
        (p.lymph_node, "lymph_node"),
        (p.tense_muscle, "tense_muscle"),
    ]
    .into_iter()
    .filter_map(|(on, n)| on.then_some(n))
    .collect();
    JsonCase {
        name: &c.file.name,
        title: &c.file.title,
        patient: &p.name,
        variants,
        vignette: &c.file.vignette,
        diagnosis: c.file.truth.diagnosis.name(),
        truth: c
            .ground_truth()
            .into_iter()
            .map(|v| JsonVein {
                vein: v.vein,
                segments: v
                    .pieces
                    .iter()
                    .map(|p| JsonSegment {
                        s_start_mm: p.s_start * 1e3,
                        s_end_mm: p.s_end * 1e3,
                        kind: p.kind,
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// Runs `print` on the locked stdout. The output goes through checked
/// writes (`println!` panics when the reader has gone, e.g. `cases list |
/// head`): a closed pipe (`BrokenPipe`, which Rust's runtime turns SIGPIPE
/// into; SIGPIPE is not reset here, the viewer's sockets need it ignored)
/// ends the output quietly, as the reader wanted no more; any other write
/// error is reported.
pub fn to_stdout(print: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    let mut out = io::stdout().lock();
    match print(&mut out).and_then(|()| out.flush()) {
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("writing to stdout"),
    }
}

/// Runs `echothigh cases …`.
pub fn run(cmd: CasesCommand) -> Result<()> {
    match cmd {
        CasesCommand::List { json } => {
            let cases = echothigh_cases::names()
                .map(|n| echothigh_cases::builtin(n).with_context(|| format!("shipped case {n}")))
                .collect::<Result<Vec<_>>>()?;
            if json {
                let list: Vec<_> = cases.iter().map(json_case).collect();
                let text = serde_json::to_string(&list)?;
                to_stdout(|out| writeln!(out, "{text}"))?;
            } else {
                to_stdout(|out| {
                    for c in &cases {
                        let j = json_case(c);
                        writeln!(
                            out,
                            "{:<28} {:<15} {:<28} {}",
                            j.name, j.patient, j.diagnosis, j.title
                        )?;
                    }
                    Ok(())
                })?;
            }
        }
        CasesCommand::Show { name, json } => {
            let c = load_case(&name)?;
            let j = json_case(&c);
            if json {
                let text = serde_json::to_string(&j)?;
                to_stdout(|out| writeln!(out, "{text}"))?;
            } else {
                to_stdout(|out| {
                    writeln!(out, "{} — {} ({})", j.name, j.title, j.patient)?;
                    let v = j.vignette;
                    writeln!(out, "age {}, Wells {}: {}", v.age, v.wells, v.symptoms)?;
                    writeln!(out, "diagnosis: {}", j.diagnosis)?;
                    for vein in &j.truth {
                        let parts: Vec<String> = vein
                            .segments
                            .iter()
                            .map(|s| format!("{:.0}–{:.0} mm {}", s.s_start_mm, s.s_end_mm, s.kind))
                            .collect();
                        writeln!(out, "  {:<4} {}", vein.vein, parts.join(", "))?;
                    }
                    Ok(())
                })?;
            }
        }
        CasesCommand::Generate {
            count,
            prevalence,
            seed,
            out,
        } => {
            anyhow::ensure!(
                count > 0 && count <= 100_000,
                "--count must be between 1 and 100000, got {count}"
            );
            let mut g = Generator::new(prevalence, seed)?;
            std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
            let mut positives = 0;
            for _ in 0..count {
                let d = g.draw();
                let file: &CaseFile = &d.file;
                positives += usize::from(file.truth.diagnosis.is_dvt());
                let path = out.join(format!("{}.toml", file.name));
                let text = format!(
                    "# Generated by `echothigh cases generate --prevalence {prevalence} --seed {seed}` (issue 13).\n{}",
                    file.to_toml_string()
                );
                std::fs::write(&path, text)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            let share = 100.0 * positives as f64 / count as f64;
            to_stdout(|o| {
                writeln!(
                    o,
                    "{count} cases in {} ({positives} acute DVT, {share:.1} %)",
                    out.display()
                )
            })?;
        }
    }
    Ok(())
}
