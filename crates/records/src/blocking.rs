//! The store from sync code: the headless exam, the CLI, and the exam loop
//! even when it runs beside the viewer's tokio runtime.
//!
//! [`BlockingStore`] owns a thread with its own current-thread tokio
//! runtime; every call is sent to it and waited for on a std channel. No
//! runtime is ever entered from the caller's thread, so calling it from
//! inside a tokio multi-thread runtime (an axum handler) cannot hit the
//! nested-runtime panic (it blocks that worker for the call's duration:
//! async code should prefer [`Store`] opened on its own runtime).

use crate::{
    CaseDetail, CaseId, RecordsError, SessionId, SiteStats, Store, Trainee, TraineeHistory,
    TraineeSummary, TruthSegment,
};
use echothigh_exam::{
    Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall, ExamLog, LogError,
};
use std::future::Future;
use std::pin::Pin;
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;

type Job = Box<dyn FnOnce(Store) -> Pin<Box<dyn Future<Output = ()> + Send>> + Send>;

struct Worker {
    jobs: Mutex<Option<mpsc::Sender<Job>>>,
    thread: Mutex<Option<JoinHandle<()>>>,
    db: String,
    /// [`Store::fallback_dir`], or `None` when it has none.
    fallback: Option<std::path::PathBuf>,
}

impl Drop for Worker {
    fn drop(&mut self) {
        // Closing the channel ends the thread's loop; it closes the pool.
        self.jobs.lock().map(|mut j| j.take()).ok();
        if let Some(t) = self.thread.lock().ok().and_then(|mut t| t.take()) {
            let _ = t.join();
        }
    }
}

/// The records database for sync callers (see the module doc). Cheap to
/// clone; the thread stops when the last clone (and recorder) is dropped.
#[derive(Clone)]
pub struct BlockingStore {
    worker: Arc<Worker>,
}

impl std::fmt::Debug for BlockingStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "BlockingStore({})", self.worker.db)
    }
}

impl BlockingStore {
    /// Opens (creating, migrating) the database at `url` (`None`: the
    /// default SQLite file) on a new records thread.
    pub fn open(url: Option<&str>) -> Result<BlockingStore, RecordsError> {
        let url = url.map(str::to_string);
        type Opened = (String, Option<std::path::PathBuf>);
        let (open_tx, open_rx) = mpsc::sync_channel::<Result<Opened, RecordsError>>(1);
        let (jobs_tx, jobs_rx) = mpsc::channel::<Job>();
        let thread = std::thread::Builder::new()
            .name("echothigh-records".into())
            .spawn(move || {
                let rt = match tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(source) => {
                        let _ = open_tx.send(Err(RecordsError::Io {
                            path: "the records thread's runtime".into(),
                            source,
                        }));
                        return;
                    }
                };
                let store = match rt.block_on(Store::open(url.as_deref())) {
                    Ok(s) => {
                        let _ = open_tx.send(Ok((s.name().to_string(), s.fallback_dir().ok())));
                        s
                    }
                    Err(e) => {
                        let _ = open_tx.send(Err(e));
                        return;
                    }
                };
                while let Ok(job) = jobs_rx.recv() {
                    rt.block_on(job(store.clone()));
                }
                rt.block_on(store.close());
            })
            .map_err(|source| RecordsError::Io {
                path: "the records thread".into(),
                source,
            })?;
        let (db, fallback) = match open_rx.recv() {
            Ok(Ok(x)) => x,
            Ok(Err(e)) => {
                let _ = thread.join();
                return Err(e);
            }
            Err(_) => {
                let _ = thread.join();
                return Err(RecordsError::WorkerGone { db: url_hint() });
            }
        };
        Ok(BlockingStore {
            worker: Arc::new(Worker {
                jobs: Mutex::new(Some(jobs_tx)),
                thread: Mutex::new(Some(thread)),
                db,
                fallback,
            }),
        })
    }

    /// The database as named in messages.
    pub fn name(&self) -> &str {
        &self.worker.db
    }

    /// [`Store::fallback_dir`]: where a fallback journal goes.
    pub fn fallback_dir(&self) -> Result<std::path::PathBuf, RecordsError> {
        self.worker.fallback.clone().ok_or(RecordsError::NoDataDir)
    }

    /// Runs `f` on the records thread and waits for its result.
    pub fn run<T, F, Fut>(&self, f: F) -> Result<T, RecordsError>
    where
        T: Send + 'static,
        F: FnOnce(Store) -> Fut + Send + 'static,
        Fut: Future<Output = Result<T, RecordsError>> + Send + 'static,
    {
        let gone = || RecordsError::WorkerGone {
            db: self.worker.db.clone(),
        };
        let (tx, rx) = mpsc::sync_channel(1);
        let job: Job = Box::new(move |store| {
            Box::pin(async move {
                let _ = tx.send(f(store).await);
            })
        });
        let sender = self
            .worker
            .jobs
            .lock()
            .map_err(|_| gone())?
            .clone()
            .ok_or_else(gone)?;
        sender.send(job).map_err(|_| gone())?;
        rx.recv().map_err(|_| gone())?
    }

    /// [`Store::trainee`].
    pub fn trainee(&self, name: &str) -> Result<Trainee, RecordsError> {
        let name = name.to_string();
        self.run(move |s| async move { s.trainee(&name).await })
    }

    /// [`Store::begin_session`].
    pub fn begin_session(
        &self,
        trainee: &Trainee,
        protocol: &str,
    ) -> Result<SessionId, RecordsError> {
        let (t, p) = (trainee.clone(), protocol.to_string());
        self.run(move |s| async move { s.begin_session(&t, &p).await })
    }

    /// [`Store::end_session`].
    pub fn end_session(&self, session: SessionId) -> Result<(), RecordsError> {
        self.run(move |s| async move { s.end_session(session).await })
    }

    /// Starts an attempt at `case` (with its ground truth) and returns its
    /// recorder, the [`ExamLog`] the exam writes to.
    pub fn begin_case(
        &self,
        session: SessionId,
        case: &str,
        truth: &[TruthSegment],
    ) -> Result<CaseRecorder, RecordsError> {
        let (c, t) = (case.to_string(), truth.to_vec());
        let id = self.run(move |s| async move { s.begin_case(session, &c, &t).await })?;
        Ok(CaseRecorder {
            store: self.clone(),
            case: id,
            events: 0,
            calls: 0,
            doppler: 0,
        })
    }
}

impl BlockingStore {
    /// [`Store::history`].
    pub fn history(&self, name: &str) -> Result<TraineeHistory, RecordsError> {
        let name = name.to_string();
        self.run(move |s| async move { s.history(&name).await })
    }

    /// [`Store::trainees`].
    pub fn trainees(&self) -> Result<Vec<TraineeSummary>, RecordsError> {
        self.run(|s| async move { s.trainees().await })
    }

    /// [`Store::site_stats`].
    pub fn site_stats(&self) -> Result<Vec<SiteStats>, RecordsError> {
        self.run(|s| async move { s.site_stats().await })
    }

    /// [`Store::case_detail`].
    pub fn case_detail(&self, id: i64) -> Result<CaseDetail, RecordsError> {
        self.run(move |s| async move { s.case_detail(id).await })
    }

    /// [`Store::open_session`].
    pub fn open_session(
        &self,
        trainee: &str,
        protocol: &str,
    ) -> Result<Option<crate::ResumedSession>, RecordsError> {
        let (t, p) = (trainee.to_string(), protocol.to_string());
        self.run(move |s| async move { s.open_session(&t, &p).await })
    }

    /// [`Store::end_session_at`].
    pub fn end_session_at(&self, session: SessionId, ended_ms: i64) -> Result<(), RecordsError> {
        self.run(move |s| async move { s.end_session_at(session, ended_ms).await })
    }
}

fn url_hint() -> String {
    "the records database".into()
}

/// The records of one case attempt as they happen: each method returns
/// once its rows are committed.
#[derive(Debug)]
pub struct CaseRecorder {
    store: BlockingStore,
    case: CaseId,
    events: u32,
    calls: u32,
    doppler: u32,
}

impl CaseRecorder {
    /// The attempt's row id.
    pub fn case_id(&self) -> CaseId {
        self.case
    }

    /// Stores an event; returns its row id once committed.
    pub fn record_event(&mut self, e: &CompressionEvent) -> Result<i64, RecordsError> {
        let (case, seq, e) = (self.case, self.events, e.clone());
        let id = self
            .store
            .run(move |s| async move { s.record_event(case, seq, &e).await })?;
        self.events += 1;
        Ok(id)
    }

    /// Stores a call; returns its row id once committed.
    pub fn record_call(&mut self, c: &Call) -> Result<i64, RecordsError> {
        let (case, seq, c) = (self.case, self.calls, c.clone());
        let id = self
            .store
            .run(move |s| async move { s.record_call(case, seq, &c).await })?;
        self.calls += 1;
        Ok(id)
    }

    /// Stores a Doppler call; returns its row id once committed.
    pub fn record_doppler(&mut self, c: &DopplerCall) -> Result<i64, RecordsError> {
        let (case, seq, c) = (self.case, self.doppler, c.clone());
        let id = self
            .store
            .run(move |s| async move { s.record_doppler(case, seq, &c).await })?;
        self.doppler += 1;
        Ok(id)
    }

    /// Stores the coverage and score (one transaction).
    pub fn record_finish(
        &mut self,
        coverage: &[CoverageBin],
        score: &CaseScore,
    ) -> Result<(), RecordsError> {
        let (case, cov, sc) = (self.case, coverage.to_vec(), score.clone());
        self.store
            .run(move |s| async move { s.finish_case(case, &cov, &sc).await })
    }
}

impl ExamLog for CaseRecorder {
    fn event(&mut self, event: &CompressionEvent) -> Result<(), LogError> {
        self.record_event(event)
            .map(drop)
            .map_err(|e| LogError(e.to_string()))
    }
    fn call(&mut self, call: &Call) -> Result<(), LogError> {
        self.record_call(call)
            .map(drop)
            .map_err(|e| LogError(e.to_string()))
    }
    fn doppler(&mut self, call: &DopplerCall) -> Result<(), LogError> {
        self.record_doppler(call)
            .map(drop)
            .map_err(|e| LogError(e.to_string()))
    }
    fn finish(&mut self, coverage: &[CoverageBin], score: &CaseScore) -> Result<(), LogError> {
        self.record_finish(coverage, score)
            .map_err(|e| LogError(e.to_string()))
    }
}
