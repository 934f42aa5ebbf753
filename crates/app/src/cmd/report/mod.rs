//! `echothigh report --trainee NAME [--db URL] --out DIR` (issue 14): a
//! trainee's record as one self-contained HTML page (inline SVG plots, no
//! network) plus the same numbers as JSON.

mod html;
mod plots;

use anyhow::{Context, Result};
use echothigh_records::{BlockingStore, CaseDetail, TraineeHistory};
use std::path::PathBuf;

/// Arguments of `echothigh report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The trainee's name.
    #[arg(long)]
    pub trainee: String,
    /// The records database: `sqlite://PATH` or `postgres://USER@HOST/DB`
    /// (default: the SQLite file under the user's data directory).
    #[arg(long)]
    pub db: Option<String>,
    /// Output directory (created): `index.html` and `report.json`.
    #[arg(long)]
    pub out: PathBuf,
}

/// Everything the page shows: the history and each case in full.
#[derive(serde::Serialize)]
pub struct Report {
    /// The trainee's sessions, rates and per-site statistics.
    pub history: TraineeHistory,
    /// Every case attempt, in session order.
    pub cases: Vec<CaseDetail>,
}

/// Reads the trainee's records and writes the report.
pub fn run(a: Args) -> Result<()> {
    let store = BlockingStore::open(a.db.as_deref())?;
    let history = store.history(&a.trainee)?;
    let mut cases = Vec::new();
    for s in &history.sessions {
        for c in &s.cases {
            cases.push(store.case_detail(c.id)?);
        }
    }
    let report = Report { history, cases };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let page = html::page(&report)?;
    let index = a.out.join("index.html");
    std::fs::write(&index, page).with_context(|| format!("writing {}", index.display()))?;
    let json = a.out.join("report.json");
    let text = serde_json::to_string_pretty(&report).context("encoding the report as JSON")?;
    std::fs::write(&json, text).with_context(|| format!("writing {}", json.display()))?;
    println!("{}", index.display());
    Ok(())
}
