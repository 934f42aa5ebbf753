//! Replaying a fallback journal into a database that works again
//! (`echothigh records import FILE`), idempotently: a session or case
//! attempt is found by its unique id (`uid`, schema version 3) before it is
//! created, an event, call or Doppler call by its case and sequence number
//! before it is inserted, a score only when the case is unfinished, a
//! session's end only when it has none. Importing a journal twice, or into
//! the database that already holds the records written before the fault,
//! adds each row once.
//!
//! Every line is committed as it is replayed, so an import that stops
//! half-way (the database fails again) is finished by running it again.
//! Two imports of the same journal at the same moment could both find a
//! row missing; run one at a time.

use crate::journal::{self, JournalLine, Record};
use crate::{BlockingStore, CaseId, RecordsError, SessionId, Store, Trainee};
use serde::Serialize;
use sqlx::Row;
use std::collections::HashMap;
use std::path::Path;

/// What an import did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct ImportReport {
    /// Records read from the journal.
    pub records: usize,
    /// Records written to the database.
    pub added: usize,
    /// Records the database already had (left as they were).
    pub present: usize,
    /// The journal's last line was torn (never acknowledged) and skipped.
    pub torn_tail: bool,
}

/// The row ids found or made so far.
#[derive(Default)]
struct Ids {
    trainees: HashMap<String, Trainee>,
    sessions: HashMap<String, SessionId>,
    cases: HashMap<String, CaseId>,
}

impl Store {
    /// Replays `lines` (read from the journal `path`, named in errors),
    /// adding what the database lacks.
    pub async fn import_lines(
        &self,
        path: &str,
        lines: &[(usize, JournalLine)],
    ) -> Result<ImportReport, RecordsError> {
        let mut ids = Ids::default();
        let mut report = ImportReport::default();
        for (n, line) in lines {
            report.records += 1;
            if self.replay(&mut ids, path, *n, line).await? {
                report.added += 1;
            } else {
                report.present += 1;
            }
        }
        Ok(report)
    }

    /// Replays one line; `true` when it added to the database.
    async fn replay(
        &self,
        ids: &mut Ids,
        path: &str,
        n: usize,
        line: &JournalLine,
    ) -> Result<bool, RecordsError> {
        let session = self.session_of(ids, line).await?;
        if let Record::SessionEnd { ended_ms } = line.record {
            let done =
                sqlx::query("UPDATE sessions SET ended_ms = $1 WHERE id = $2 AND ended_ms IS NULL")
                    .bind(ended_ms)
                    .bind(session.0)
                    .execute(&self.pool)
                    .await
                    .map_err(self.err("ending a session"))?;
            return Ok(done.rows_affected() > 0);
        }
        let orphan = || RecordsError::Orphan {
            path: path.to_string(),
            line: n,
            kind: line.record.kind(),
            case: line.case.as_ref().map_or("?", |c| c.name.as_str()).into(),
            uid: line.case.as_ref().map_or("?", |c| c.uid.as_str()).into(),
        };
        let key = line.case.as_ref().ok_or_else(orphan)?;
        let found = match ids.cases.get(&key.uid) {
            Some(c) => Some(*c),
            None => self
                .find_by_uid("case_attempts", &key.uid)
                .await?
                .map(CaseId),
        };
        if let Some(c) = found {
            ids.cases.insert(key.uid.clone(), c);
        }
        let case = match (&line.record, found) {
            (Record::Case { truth }, None) => {
                let c = self.begin_case_keyed(session, key, truth).await?;
                ids.cases.insert(key.uid.clone(), c);
                return Ok(true);
            }
            (Record::Case { .. }, Some(_)) => return Ok(false),
            (_, None) => return Err(orphan()),
            (_, Some(c)) => c,
        };
        match &line.record {
            Record::Event { seq, event } => {
                if self.has_seq("events", case, *seq).await? {
                    return Ok(false);
                }
                self.record_event(case, *seq, event).await?;
            }
            Record::Call { seq, call } => {
                if self.has_seq("calls", case, *seq).await? {
                    return Ok(false);
                }
                self.record_call(case, *seq, call).await?;
            }
            Record::Doppler { seq, call } => {
                if self.has_seq("doppler_calls", case, *seq).await? {
                    return Ok(false);
                }
                self.record_doppler(case, *seq, call).await?;
            }
            Record::Finish {
                coverage,
                score,
                finished_ms,
            } => {
                let done: Option<i64> =
                    sqlx::query("SELECT finished_ms FROM case_attempts WHERE id = $1")
                        .bind(case.0)
                        .fetch_one(&self.pool)
                        .await
                        .and_then(|r| r.try_get(0))
                        .map_err(self.err("reading a case's end"))?;
                if done.is_some() {
                    return Ok(false);
                }
                self.finish_case_at(case, coverage, score, *finished_ms)
                    .await?;
            }
            // Both returned above.
            Record::Case { .. } | Record::SessionEnd { .. } => return Ok(false),
        }
        Ok(true)
    }

    /// The session of `line`, found by its unique id or created.
    async fn session_of(
        &self,
        ids: &mut Ids,
        line: &JournalLine,
    ) -> Result<SessionId, RecordsError> {
        let key = &line.session;
        if let Some(s) = ids.sessions.get(&key.uid) {
            return Ok(*s);
        }
        let s = match self.find_by_uid("sessions", &key.uid).await? {
            Some(id) => SessionId(id),
            None => {
                let trainee = match ids.trainees.get(&key.trainee) {
                    Some(t) => t.clone(),
                    None => self.trainee(&key.trainee).await?,
                };
                ids.trainees.insert(key.trainee.clone(), trainee.clone());
                self.begin_session_keyed(&trainee, key).await?
            }
        };
        ids.sessions.insert(key.uid.clone(), s);
        Ok(s)
    }

    /// The row id in `table` (`sessions` or `case_attempts`) with `uid`.
    async fn find_by_uid(&self, table: &str, uid: &str) -> Result<Option<i64>, RecordsError> {
        let sql = format!("SELECT id FROM {table} WHERE uid = $1");
        sqlx::query(&sql)
            .bind(uid)
            .fetch_optional(&self.pool)
            .await
            .and_then(|r| r.map(|r| r.try_get(0)).transpose())
            .map_err(self.err("finding a journal's row"))
    }

    /// Whether `table` has the `seq`-th row of `case`.
    async fn has_seq(&self, table: &str, case: CaseId, seq: u32) -> Result<bool, RecordsError> {
        let sql = format!("SELECT COUNT(*) FROM {table} WHERE case_id = $1 AND seq = $2");
        let n: i64 = sqlx::query(&sql)
            .bind(case.0)
            .bind(i64::from(seq))
            .fetch_one(&self.pool)
            .await
            .and_then(|r| r.try_get(0))
            .map_err(self.err("finding a journal's row"))?;
        Ok(n > 0)
    }
}

impl BlockingStore {
    /// Reads the fallback journal at `path` and replays it (module doc).
    pub fn import_journal(&self, path: &Path) -> Result<ImportReport, RecordsError> {
        let file = journal::read(path)?;
        let shown = path.display().to_string();
        let torn_tail = file.torn_tail;
        let lines = file.lines;
        let mut report = self.run(move |s| async move { s.import_lines(&shown, &lines).await })?;
        report.torn_tail = torn_tail;
        Ok(report)
    }
}
