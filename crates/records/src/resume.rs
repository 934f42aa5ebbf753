//! A trainee's session that never ended, read back so that the live exam
//! resumes it (issue 19: "a restart of the server keeps the exam session").
//!
//! A session ends when the trainee leaves the exam or has examined every
//! case; a server that stops or dies first leaves it open (`ended_ms` NULL),
//! with the case that was under way unfinished. Everything the exam needs
//! to go on is in the rows: each attempt's ground truth, events, calls,
//! Doppler calls and, once finished, its score. Only sessions written with
//! unique ids (schema 3 on) are resumed: the journal and `records import`
//! identify rows by them.

use crate::journal::{CaseKey, JournalLine, Record, SessionKey, FORMAT};
use crate::{CaseDetail, CaseId, RecordsError, SessionId, Store};

/// One case attempt of an open session, in full.
#[derive(Debug, Clone, PartialEq)]
pub struct ResumedCase {
    /// Its row id.
    pub id: CaseId,
    /// Its unique id, name and start.
    pub key: CaseKey,
    /// When it finished (Unix ms); `None`: it was under way.
    pub finished_ms: Option<i64>,
    /// Its truth, events, calls, Doppler calls, and score once finished.
    pub detail: CaseDetail,
}

/// A session that never ended, with its attempts oldest first.
#[derive(Debug, Clone, PartialEq)]
pub struct ResumedSession {
    /// Its row id.
    pub id: SessionId,
    /// Its unique id, trainee, protocol, host and start.
    pub key: SessionKey,
    /// Its case attempts, oldest first.
    pub cases: Vec<ResumedCase>,
}

impl ResumedSession {
    /// The journal lines that would have recorded the session so far (the
    /// fallback journal's replay of it: see [`crate::SessionRecorder`]).
    pub fn journal_lines(&self) -> Vec<JournalLine> {
        let mut out = Vec::new();
        for c in &self.cases {
            let line = |record| JournalLine {
                format: FORMAT,
                session: self.key.clone(),
                case: Some(c.key.clone()),
                record,
            };
            let d = &c.detail;
            out.push(line(Record::Case {
                truth: d.truth.clone(),
            }));
            for (seq, event) in d.events.iter().enumerate() {
                out.push(line(Record::Event {
                    seq: seq as u32,
                    event: event.clone(),
                }));
            }
            for (seq, call) in d.calls.iter().enumerate() {
                out.push(line(Record::Call {
                    seq: seq as u32,
                    call: call.clone(),
                }));
            }
            for (seq, call) in d.doppler_calls.iter().enumerate() {
                out.push(line(Record::Doppler {
                    seq: seq as u32,
                    call: call.clone(),
                }));
            }
            if let (Some(finished_ms), Some(score)) = (c.finished_ms, &d.score) {
                out.push(line(Record::Finish {
                    coverage: d.coverage.clone(),
                    score: score.clone(),
                    finished_ms,
                }));
            }
        }
        out
    }
}

impl Store {
    /// The latest session of the trainee named `trainee` under `protocol`
    /// that never ended, with every attempt in full; `None` when there is
    /// none (or the trainee is unknown, or its rows predate unique ids).
    pub async fn open_session(
        &self,
        trainee: &str,
        protocol: &str,
    ) -> Result<Option<ResumedSession>, RecordsError> {
        let t = match self.find_trainee(trainee).await {
            Ok(t) => t,
            Err(RecordsError::UnknownTrainee { .. }) => return Ok(None),
            Err(e) => return Err(e),
        };
        let sql = "SELECT id, uid, protocol, host, started_ms FROM sessions \
                   WHERE trainee_id = $1 AND ended_ms IS NULL ORDER BY started_ms DESC, id DESC";
        let rows = self.rows(sql.into(), Some(t.id)).await?;
        let mut open = None;
        for r in &rows {
            if self.get::<String>(r, 2)? == protocol {
                open = Some(r);
                break;
            }
        }
        let Some(r) = open else {
            return Ok(None);
        };
        let id: i64 = self.get(r, 0)?;
        let Some(uid) = self.get::<Option<String>>(r, 1)? else {
            return Ok(None);
        };
        let key = SessionKey {
            uid,
            trainee: t.name.clone(),
            protocol: protocol.to_string(),
            host: self.get(r, 3)?,
            started_ms: self.get(r, 4)?,
        };
        let sql = "SELECT id, uid, case_name, started_ms, finished_ms FROM case_attempts \
                   WHERE session_id = $1 ORDER BY started_ms, id";
        let mut cases = Vec::new();
        for r in self.rows(sql.into(), Some(id)).await? {
            let cid: i64 = self.get(&r, 0)?;
            let Some(uid) = self.get::<Option<String>>(&r, 1)? else {
                return Ok(None);
            };
            cases.push(ResumedCase {
                id: CaseId(cid),
                key: CaseKey {
                    uid,
                    name: self.get(&r, 2)?,
                    started_ms: self.get(&r, 3)?,
                },
                finished_ms: self.get(&r, 4)?,
                detail: self.case_detail(cid).await?,
            });
        }
        Ok(Some(ResumedSession {
            id: SessionId(id),
            key,
            cases,
        }))
    }
}
