//! `echothigh records import FILE… [--db URL]` (issue 14): replays the
//! fallback journals a live exam wrote when its database failed
//! (`records-fallback-<trainee>-<ms>.jsonl`, next to the database) into
//! the database once it works again. Idempotent: importing a journal
//! twice, or into the database that already has the records written before
//! the fault, adds each row once (`echothigh_records::BlockingStore::import_journal`).

use anyhow::{Context, Result};
use echothigh_records::BlockingStore;
use std::path::PathBuf;

/// `echothigh records …`.
#[derive(clap::Subcommand, Debug)]
pub enum RecordsCommand {
    /// Replay fallback journals into the records database (idempotent).
    Import(ImportArgs),
}

/// Arguments of `echothigh records import`.
#[derive(clap::Args, Debug)]
pub struct ImportArgs {
    /// The journals (`records-fallback-*.jsonl`), replayed in the order given.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The records database: `sqlite://PATH` or `postgres://USER@HOST/DB`
    /// (default: the SQLite file under the user's data directory).
    #[arg(long)]
    pub db: Option<String>,
    /// Print the counts as JSON (one object per journal) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `echothigh records …`.
pub fn run(c: RecordsCommand) -> Result<()> {
    match c {
        RecordsCommand::Import(a) => import(a),
    }
}

fn import(a: ImportArgs) -> Result<()> {
    let store = BlockingStore::open(a.db.as_deref())?;
    for f in &a.files {
        let r = store
            .import_journal(f)
            .with_context(|| format!("importing {} into {}", f.display(), store.name()))?;
        if a.json {
            let mut v = serde_json::to_value(r).context("encoding the counts")?;
            v["file"] = serde_json::Value::String(f.display().to_string());
            println!("{v}");
        } else {
            println!(
                "{}: {} records, {} added, {} already in {}{}",
                f.display(),
                r.records,
                r.added,
                r.present,
                store.name(),
                if r.torn_tail {
                    " (its last line was cut short by a crash, never acknowledged: skipped)"
                } else {
                    ""
                }
            );
        }
    }
    Ok(())
}
