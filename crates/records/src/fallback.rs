//! A live exam's records that survive a failing database: each record goes
//! to the database first; the first write that fails (disk full, file
//! turned read-only, server stopped, connection dropped) turns the session
//! over to a fallback journal ([`crate::journal`]) next to the database,
//! where that record and every later one are appended and fsynced.
//!
//! The journal is self-contained: when the database fails, the session's
//! records already written to it (kept in memory since the session began:
//! a session is a handful of cases, kilobytes to a few megabytes of force
//! traces) are written to the journal first, so `echothigh records import`
//! rebuilds the whole session in a fresh database, and in the original one
//! adds only what is missing (the rows carry the session's and case's
//! unique ids).
//!
//! Bounded in the real-time path (the exam observer's thread, not the
//! haptic tick): once the database has failed it is not tried again in
//! this session, so each later record costs one append and one fsync. A
//! write to a database that hangs instead of failing waits at most the
//! pool's acquire timeout (10 s, [`crate::Store::open`]). When even the
//! journal cannot be written, the records wait in memory and the journal
//! is tried again at the next record; [`ExamLog::fault`] says so.

use crate::journal::{CaseKey, Journal, JournalLine, Record, SessionKey, FORMAT};
use crate::{BlockingStore, CaseId, RecordsError, SessionId, Trainee, TruthSegment};
use echothigh_exam::{
    Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall, ExamLog, LogError,
};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

/// What the session's records share: the database, the journal, and the
/// lines the journal would need.
struct Shared {
    store: BlockingStore,
    trainee: Trainee,
    dir: PathBuf,
    session: Option<SessionKey>,
    session_id: Option<SessionId>,
    /// Lines not (yet) in the journal: while the database works, every
    /// line of the session so far; after it failed, those the journal has
    /// not taken.
    pending: Vec<JournalLine>,
    /// Why the database failed (then it is no longer used).
    db_failed: Option<String>,
    journal: Option<Journal>,
    /// Why the journal could not be written, while it cannot.
    journal_failed: Option<String>,
}

/// One trainee's exam session, recorded with a fallback (module doc).
/// Cheap to clone: the clones and the [`CaseWriter`]s share one state.
#[derive(Clone)]
pub struct SessionRecorder {
    shared: Arc<Mutex<Shared>>,
}

/// One case attempt's records: the [`ExamLog`] the exam writes to.
pub struct CaseWriter {
    shared: Arc<Mutex<Shared>>,
    key: CaseKey,
    id: Option<CaseId>,
    /// Next sequence numbers of events, calls and Doppler calls.
    seq: [u32; 3],
}

fn lock(m: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    // The state is plain data: a panic elsewhere leaves it usable.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl SessionRecorder {
    /// A recorder for `trainee` (created in the database now: an exam does
    /// not start on a database that fails from the outset) in `store`; its
    /// journal, if needed, goes to [`crate::Store::fallback_dir`].
    pub fn new(store: BlockingStore, trainee: &str) -> Result<SessionRecorder, RecordsError> {
        let trainee = store.trainee(trainee)?;
        let dir = store.fallback_dir()?;
        Ok(SessionRecorder {
            shared: Arc::new(Mutex::new(Shared {
                store,
                trainee,
                dir,
                session: None,
                session_id: None,
                pending: Vec::new(),
                db_failed: None,
                journal: None,
                journal_failed: None,
            })),
        })
    }

    /// A recorder that goes on with `session`, a session of `trainee` that
    /// never ended ([`crate::Store::open_session`]): later cases join it,
    /// and [`Self::continue_case`] writes on into its unfinished attempt.
    /// The session's records so far are kept as journal lines, so that a
    /// database failing later still leaves a self-contained journal.
    pub fn resume(
        store: BlockingStore,
        trainee: &str,
        session: &crate::ResumedSession,
    ) -> Result<SessionRecorder, RecordsError> {
        let r = SessionRecorder::new(store, trainee)?;
        {
            let mut s = lock(&r.shared);
            s.session = Some(session.key.clone());
            s.session_id = Some(session.id);
            s.pending = session.journal_lines();
        }
        Ok(r)
    }

    /// Writes on into the attempt `case` of the resumed session: its events,
    /// calls and Doppler calls continue their numbering.
    pub fn continue_case(&self, case: &crate::ResumedCase) -> CaseWriter {
        let d = &case.detail;
        CaseWriter {
            shared: self.shared.clone(),
            key: case.key.clone(),
            id: Some(case.id),
            seq: [
                d.events.len() as u32,
                d.calls.len() as u32,
                d.doppler_calls.len() as u32,
            ],
        }
    }

    /// The database.
    pub fn store(&self) -> BlockingStore {
        lock(&self.shared).store.clone()
    }

    /// Starts an attempt at case `name` with its ground truth (the session
    /// begins with its first case, under `protocol`). Never fails: a case
    /// line that neither the database nor the journal takes waits in memory
    /// ([`Self::fault`] says so).
    pub fn begin_case(&self, protocol: &str, name: &str, truth: &[TruthSegment]) -> CaseWriter {
        let mut w = CaseWriter {
            shared: self.shared.clone(),
            key: CaseKey::new(name),
            id: None,
            seq: [0; 3],
        };
        {
            let mut s = lock(&self.shared);
            if s.session.is_none() {
                s.session = Some(SessionKey::new(&s.trainee.name, protocol));
            }
        }
        let _ = w.write(Record::Case {
            truth: truth.to_vec(),
        });
        w
    }

    /// Ends the session (its end time), if it began.
    pub fn end(&self) -> Result<(), LogError> {
        let mut s = lock(&self.shared);
        if s.session.is_none() {
            return Ok(());
        }
        let ended_ms = crate::now_ms();
        s.write(None, &mut None, Record::SessionEnd { ended_ms })
    }

    /// When the database has failed: what happened and where the records
    /// are, in plain words.
    pub fn fault(&self) -> Option<String> {
        lock(&self.shared).fault()
    }

    /// The journal the records go to since the database failed.
    pub fn journal_path(&self) -> Option<PathBuf> {
        lock(&self.shared)
            .journal
            .as_ref()
            .map(|j| j.path().to_path_buf())
    }
}

impl Shared {
    /// Sends `record` (of the case `case`, whose row id is `id`) to the
    /// database, or once it has failed, to the journal.
    fn write(
        &mut self,
        case: Option<&CaseKey>,
        id: &mut Option<CaseId>,
        record: Record,
    ) -> Result<(), LogError> {
        let Some(session) = self.session.clone() else {
            return Err(LogError("recording before the session began".into()));
        };
        let line = JournalLine {
            format: FORMAT,
            session,
            case: case.cloned(),
            record,
        };
        if self.db_failed.is_none() {
            match self.write_db(&line, id) {
                Ok(()) => {
                    self.pending.push(line);
                    return Ok(());
                }
                Err(e) => self.db_failed = Some(e.to_string()),
            }
        }
        self.pending.push(line);
        self.flush()
    }

    /// Writes one line's record into the database.
    fn write_db(
        &mut self,
        line: &JournalLine,
        id: &mut Option<CaseId>,
    ) -> Result<(), RecordsError> {
        let store = self.store.clone();
        let no_case = || RecordsError::WorkerGone {
            db: format!("{} (no case row to record into)", store.name()),
        };
        match line.record.clone() {
            Record::Case { truth } => {
                let session = match self.session_id {
                    Some(s) => s,
                    None => {
                        let (t, k) = (self.trainee.clone(), line.session.clone());
                        let s = store
                            .run(move |s| async move { s.begin_session_keyed(&t, &k).await })?;
                        self.session_id = Some(s);
                        s
                    }
                };
                let key = line.case.clone().ok_or_else(no_case)?;
                *id = Some(store.run(move |s| async move {
                    s.begin_case_keyed(session, &key, &truth).await
                })?);
                Ok(())
            }
            Record::Event { seq, event } => {
                let c = id.ok_or_else(no_case)?;
                store
                    .run(move |s| async move { s.record_event(c, seq, &event).await })
                    .map(drop)
            }
            Record::Call { seq, call } => {
                let c = id.ok_or_else(no_case)?;
                store
                    .run(move |s| async move { s.record_call(c, seq, &call).await })
                    .map(drop)
            }
            Record::Doppler { seq, call } => {
                let c = id.ok_or_else(no_case)?;
                store
                    .run(move |s| async move { s.record_doppler(c, seq, &call).await })
                    .map(drop)
            }
            Record::Finish {
                coverage,
                score,
                finished_ms,
            } => {
                let c = id.ok_or_else(no_case)?;
                store.run(move |s| async move {
                    s.finish_case_at(c, &coverage, &score, finished_ms).await
                })
            }
            Record::SessionEnd { ended_ms } => match self.session_id {
                Some(sid) => {
                    store.run(move |s| async move { s.end_session_at(sid, ended_ms).await })
                }
                None => Ok(()),
            },
        }
    }

    /// Appends the pending lines to the journal (creating it first); a
    /// journal whose append failed is dropped, its lines so far kept, and
    /// the next flush starts a new file (a torn line stays the old file's
    /// last, which the reader skips).
    fn flush(&mut self) -> Result<(), LogError> {
        if self.journal.is_none() {
            match Journal::create(&self.dir, &self.trainee.name) {
                Ok(j) => self.journal = Some(j),
                Err(e) => {
                    self.journal_failed = Some(e.to_string());
                    return Err(LogError(self.fault().unwrap_or_default()));
                }
            }
        }
        let mut taken = 0;
        if let Some(j) = self.journal.as_mut() {
            for line in &self.pending {
                if let Err(e) = j.append(line) {
                    self.journal_failed = Some(e.to_string());
                    break;
                }
                taken += 1;
            }
        }
        self.pending.drain(..taken);
        if self.pending.is_empty() {
            self.journal_failed = None;
            Ok(())
        } else {
            self.journal = None;
            Err(LogError(self.fault().unwrap_or_default()))
        }
    }

    fn fault(&self) -> Option<String> {
        let db = self.db_failed.as_ref()?;
        Some(match (&self.journal, &self.journal_failed) {
            (Some(j), None) => format!(
                "the records database failed ({db}); the exam goes on and its records are kept in {} \
                 (replay them with `echothigh records import {}` once the database works again)",
                j.path().display(),
                j.path().display()
            ),
            (_, why) => format!(
                "the records database failed ({db}) and the fallback journal in {} could not be written ({}): \
                 {} records are kept in memory only, and the journal is tried again at the next record",
                self.dir.display(),
                why.as_deref().unwrap_or("unknown"),
                self.pending.len()
            ),
        })
    }
}

impl CaseWriter {
    /// The case's unique id.
    pub fn key(&self) -> &CaseKey {
        &self.key
    }

    fn write(&mut self, record: Record) -> Result<(), LogError> {
        lock(&self.shared).write(Some(&self.key), &mut self.id, record)
    }

    fn next(&mut self, k: usize) -> u32 {
        let n = self.seq[k];
        self.seq[k] += 1;
        n
    }
}

impl ExamLog for CaseWriter {
    fn event(&mut self, event: &CompressionEvent) -> Result<(), LogError> {
        let seq = self.next(0);
        self.write(Record::Event {
            seq,
            event: event.clone(),
        })
    }
    fn call(&mut self, call: &Call) -> Result<(), LogError> {
        let seq = self.next(1);
        self.write(Record::Call {
            seq,
            call: call.clone(),
        })
    }
    fn doppler(&mut self, call: &DopplerCall) -> Result<(), LogError> {
        let seq = self.next(2);
        self.write(Record::Doppler {
            seq,
            call: call.clone(),
        })
    }
    fn finish(&mut self, coverage: &[CoverageBin], score: &CaseScore) -> Result<(), LogError> {
        self.write(Record::Finish {
            coverage: coverage.to_vec(),
            score: score.clone(),
            finished_ms: crate::now_ms(),
        })
    }
    fn fault(&self) -> Option<String> {
        lock(&self.shared).fault()
    }
}
