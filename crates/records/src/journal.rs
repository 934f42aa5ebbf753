//! The fallback journal: where an exam's records go when the database
//! fails mid-exam (disk full, file turned read-only, server stopped,
//! connection dropped), and what `echothigh records import` replays once
//! the database works again.
//!
//! One JSON object per line (JSON Lines), appended and fsynced record by
//! record in a file next to the database
//! (`records-fallback-<trainee>-<unix ms>.jsonl`). Each line carries the
//! format version, the session's identity (its unique id, trainee,
//! protocol, host, start time), the case's identity (unique id, name, start
//! time) when the record belongs to a case, and the record itself tagged
//! by its `kind`: `case` (the attempt begins, with its ground truth),
//! `event`, `call`, `doppler` (each with its sequence number in the case),
//! `finish` (coverage and score) or `session_end`. A line alone says where
//! its record belongs, so a replay needs nothing but the file.

use crate::{RecordsError, TruthSegment};
use echothigh_exam::{Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The journal format this build writes and reads.
pub const FORMAT: u32 = 1;

/// A new unique id: 128 random bits in hex (collision odds ~n²/2¹²⁹, nil
/// for any number of sessions a school keeps).
fn new_uid() -> String {
    format!("{:032x}", rand::random::<u128>())
}

/// A session's identity, as stored in its row and on every journal line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SessionKey {
    /// The unique id (`sessions.uid`).
    pub uid: String,
    /// The trainee's name.
    pub trainee: String,
    /// The protocol (`two-point`, `three-point`, `whole-leg`).
    pub protocol: String,
    /// The host the session ran on.
    pub host: String,
    /// Start time (Unix ms, UTC).
    pub started_ms: i64,
}

impl SessionKey {
    /// A new session of `trainee` under `protocol`, on this host, now.
    pub fn new(trainee: &str, protocol: &str) -> SessionKey {
        SessionKey {
            uid: new_uid(),
            trainee: trainee.to_string(),
            protocol: protocol.to_string(),
            host: gethostname::gethostname().to_string_lossy().into_owned(),
            started_ms: crate::now_ms(),
        }
    }
}

/// A case attempt's identity.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CaseKey {
    /// The unique id (`case_attempts.uid`).
    pub uid: String,
    /// The case's name.
    pub name: String,
    /// Start time (Unix ms, UTC).
    pub started_ms: i64,
}

impl CaseKey {
    /// A new attempt at case `name`, now.
    pub fn new(name: &str) -> CaseKey {
        CaseKey {
            uid: new_uid(),
            name: name.to_string(),
            started_ms: crate::now_ms(),
        }
    }
}

/// One record of an exam, tagged by its kind.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Record {
    /// The attempt begins, with the case's ground truth.
    Case {
        /// Every piece of every vein.
        truth: Vec<TruthSegment>,
    },
    /// A compression event, the case's `seq`-th (from 0).
    Event {
        /// Its place among the case's events.
        seq: u32,
        /// The event.
        event: CompressionEvent,
    },
    /// A call, the case's `seq`-th.
    Call {
        /// Its place among the case's calls.
        seq: u32,
        /// The call.
        call: Call,
    },
    /// A Doppler call, the case's `seq`-th.
    Doppler {
        /// Its place among the case's Doppler calls.
        seq: u32,
        /// The call.
        call: DopplerCall,
    },
    /// The case is over.
    Finish {
        /// The coverage strip.
        coverage: Vec<CoverageBin>,
        /// The score.
        score: CaseScore,
        /// When (Unix ms).
        finished_ms: i64,
    },
    /// The session is over.
    SessionEnd {
        /// When (Unix ms).
        ended_ms: i64,
    },
}

impl Record {
    /// The kind as written in the journal.
    pub fn kind(&self) -> &'static str {
        match self {
            Record::Case { .. } => "case",
            Record::Event { .. } => "event",
            Record::Call { .. } => "call",
            Record::Doppler { .. } => "doppler",
            Record::Finish { .. } => "finish",
            Record::SessionEnd { .. } => "session_end",
        }
    }
}

/// One line of the journal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JournalLine {
    /// The format version ([`FORMAT`]).
    pub format: u32,
    /// The session the record belongs to.
    pub session: SessionKey,
    /// The case it belongs to (none for `session_end`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub case: Option<CaseKey>,
    /// The record.
    pub record: Record,
}

/// An open journal file, appended to and fsynced line by line.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
}

/// `name` with every character but ASCII letters, digits, `-` and `_`
/// replaced by `_` (a trainee's name may hold spaces or `/`).
fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

impl Journal {
    /// Creates a new journal for `trainee` in `dir` (created when missing):
    /// `records-fallback-<trainee>-<unix ms>.jsonl`, never an existing
    /// file (a suffix `-1`, `-2`, … when the name is taken).
    pub fn create(dir: &Path, trainee: &str) -> Result<Journal, RecordsError> {
        let io = |path: &Path| {
            let path = path.display().to_string();
            move |source| RecordsError::Io { path, source }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let stem = format!(
            "records-fallback-{}-{}",
            file_safe(trainee),
            crate::now_ms()
        );
        for k in 0..100 {
            let name = match k {
                0 => format!("{stem}.jsonl"),
                k => format!("{stem}-{k}.jsonl"),
            };
            let path = dir.join(name);
            match std::fs::OpenOptions::new()
                .append(true)
                .create_new(true)
                .open(&path)
            {
                Ok(file) => return Ok(Journal { path, file }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(io(&path)(e)),
            }
        }
        Err(io(dir)(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("{stem}.jsonl and 99 suffixed names are all taken"),
        )))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends `line` and waits until it is on the disk (`fsync` of the
    /// data): once this returns, a crash or power cut keeps the line.
    pub fn append(&mut self, line: &JournalLine) -> Result<(), RecordsError> {
        let mut text = serde_json::to_string(line).map_err(|e| RecordsError::Journal {
            path: self.path.display().to_string(),
            line: 0,
            why: format!(
                "a {} record is not representable as JSON: {e}",
                line.record.kind()
            ),
        })?;
        text.push('\n');
        let io = |source| RecordsError::Io {
            path: self.path.display().to_string(),
            source,
        };
        self.file.write_all(text.as_bytes()).map_err(io)?;
        self.file.sync_data().map_err(io)
    }
}

/// A journal as read back.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalFile {
    /// Its lines, in order, each with its line number (from 1).
    pub lines: Vec<(usize, JournalLine)>,
    /// The last line was cut short (no newline, not valid JSON: the
    /// process died while appending it) and was left out. Such a line was
    /// never acknowledged, so nothing acknowledged is lost.
    pub torn_tail: bool,
}

/// Reads the journal at `path`. A malformed line is an error naming the
/// file and the line (from 1), except a torn last line ([`JournalFile`]).
pub fn read(path: &Path) -> Result<JournalFile, RecordsError> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| RecordsError::Io {
        path: shown.clone(),
        source,
    })?;
    let bad = |line: usize, why: String| RecordsError::Journal {
        path: shown.clone(),
        line,
        why,
    };
    let complete = text.ends_with('\n');
    let rows: Vec<&str> = text.lines().collect();
    let mut out = JournalFile {
        lines: Vec::with_capacity(rows.len()),
        torn_tail: false,
    };
    for (i, row) in rows.iter().enumerate() {
        if row.trim().is_empty() {
            continue;
        }
        let parsed = serde_json::from_str::<JournalLine>(row);
        let last = i + 1 == rows.len();
        match parsed {
            Ok(l) if l.format > FORMAT => {
                return Err(bad(
                    i + 1,
                    format!(
                        "journal format {} is newer than this echothigh (reads {FORMAT}); update echothigh",
                        l.format
                    ),
                ))
            }
            Ok(l) => out.lines.push((i + 1, l)),
            Err(e) if last && !complete && e.is_eof() => out.torn_tail = true,
            Err(e) => return Err(bad(i + 1, e.to_string())),
        }
    }
    if out.lines.is_empty() {
        return Err(bad(0, "no record in the file".into()));
    }
    Ok(out)
}
