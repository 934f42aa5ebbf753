//! The async store: open (checks, migrations), and the write side. Every
//! write is its own committed statement or transaction, committed before
//! the call returns, so a crash loses nothing already acknowledged.
//!
//! One code path for both databases: sqlx's Any driver with `$n`
//! placeholders (PostgreSQL's, which SQLite also reads) and `RETURNING id`
//! (both; SQLite ≥ 3.35). The only dialect branches are the migration
//! files (identity columns) and the schema-version probe.

use crate::journal::{CaseKey, SessionKey};
use crate::url::{check_sqlite_file, Backend, DbUrl};
use crate::{schema, RecordsError};
use echothigh_exam::{Call, CaseScore, CompressionEvent, CoverageBin};
use serde::Serialize;
use sqlx::any::AnyPoolOptions;
use sqlx::{AnyPool, Row};
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// A trainee (a name is the identity for now).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Trainee {
    /// Row id.
    pub id: i64,
    /// The validated name.
    pub name: String,
}

/// A session's row id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct SessionId(pub i64);

/// A case attempt's row id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct CaseId(pub i64);

/// One piece of a case's ground truth (`kind`: `normal` or a thrombus
/// kind), stored with the attempt so the report can overlay it.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct TruthSegment {
    /// The vein (`cfv`, `fv`, …).
    pub vein: String,
    /// Proximal end (m below the inguinal ligament).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// `normal` or a thrombus kind's name.
    pub kind: String,
}

impl TruthSegment {
    /// The ground truth of `case`, every piece of every vein.
    pub fn of_case(case: &echothigh_cases::Case) -> Vec<TruthSegment> {
        case.ground_truth()
            .into_iter()
            .flat_map(|v| {
                v.pieces.into_iter().map(move |p| TruthSegment {
                    vein: v.vein.to_string(),
                    s_start: p.s_start,
                    s_end: p.s_end,
                    kind: p.kind.to_string(),
                })
            })
            .collect()
    }
}

/// The records database (async). Cheap to clone; use it on the tokio
/// runtime that opened it (a PostgreSQL connection belongs to its
/// runtime's reactor). Sync code uses [`crate::BlockingStore`].
#[derive(Clone)]
pub struct Store {
    pub(crate) pool: AnyPool,
    pub(crate) db: Arc<str>,
    backend: Backend,
    /// The SQLite file (SQLite only).
    path: Option<std::path::PathBuf>,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Store({})", self.db)
    }
}

/// Milliseconds since the Unix epoch (UTC), now.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// The longest trainee name accepted (characters).
pub const MAX_NAME_CHARS: usize = 64;

/// Checks a trainee's name: 1–64 characters, no surrounding blanks, no
/// control characters.
pub fn validate_name(name: &str) -> Result<(), RecordsError> {
    let bad = |why| {
        Err(RecordsError::BadName {
            name: name.to_string(),
            why,
        })
    };
    if name.trim().is_empty() {
        return bad("empty");
    }
    if name.trim() != name {
        return bad("leading or trailing blanks");
    }
    if name.chars().count() > MAX_NAME_CHARS {
        return bad("longer than 64 characters");
    }
    if name.chars().any(char::is_control) {
        return bad("contains a control character");
    }
    Ok(())
}

/// Maps a driver error to a clear one: SQLite's "not a database" (26), "corrupt" (11) and
/// "read-only" (8) result codes (primary code = extended code & 0xff,
/// sqlite.org/rescode.html), connection failures to `Unreachable`.
pub(crate) fn db_error(db: &str, doing: &'static str, e: sqlx::Error) -> RecordsError {
    if let sqlx::Error::Database(d) = &e {
        let primary = d
            .code()
            .and_then(|c| c.parse::<i32>().ok())
            .map(|c| c & 0xff);
        match primary {
            Some(26) => {
                return RecordsError::NotADatabase {
                    path: db.to_string(),
                }
            }
            Some(11) => {
                return RecordsError::NotADatabase {
                    path: db.to_string(),
                }
            }
            Some(8) => {
                return RecordsError::ReadOnly {
                    path: db.to_string(),
                    why: d.message().to_string(),
                }
            }
            _ => {}
        }
    }
    if matches!(
        e,
        sqlx::Error::Io(_) | sqlx::Error::PoolTimedOut | sqlx::Error::Tls(_)
    ) {
        return RecordsError::Unreachable {
            db: db.to_string(),
            source: e,
        };
    }
    RecordsError::Db {
        db: db.to_string(),
        doing,
        source: e,
    }
}

impl Store {
    /// Opens (creating a SQLite file and its directories when missing) and
    /// migrates the database at `url` (`None`: the default file).
    pub async fn open(url: Option<&str>) -> Result<Store, RecordsError> {
        sqlx::any::install_default_drivers();
        let u = DbUrl::parse(url)?;
        if let Some(path) = &u.path {
            check_sqlite_file(path)?;
        }
        let db: Arc<str> = u.shown.clone().into();
        let pool = AnyPoolOptions::new()
            .max_connections(match u.backend {
                Backend::Sqlite => 2,
                Backend::Postgres => 4,
            })
            .acquire_timeout(Duration::from_secs(10))
            .connect(&u.connect)
            .await
            .map_err(|e| db_error(&db, "opening", e))?;
        schema::migrate(&pool, u.backend, &db).await?;
        Ok(Store {
            pool,
            db,
            backend: u.backend,
            path: u.path,
        })
    }

    /// Where a fallback journal goes when this database fails mid-exam
    /// ([`crate::SessionRecorder`]): the SQLite file's directory, or for
    /// PostgreSQL the directory of the default records file (the user's
    /// data directory).
    pub fn fallback_dir(&self) -> Result<std::path::PathBuf, RecordsError> {
        let file = match &self.path {
            Some(p) => p.clone(),
            None => crate::default_path()?,
        };
        Ok(file
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_else(|| std::path::PathBuf::from(".")))
    }

    /// The database as named in messages (path, or URL without password).
    pub fn name(&self) -> &str {
        &self.db
    }

    /// The backend behind this store.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Closes the pool (waits for its connections to close).
    pub async fn close(&self) {
        self.pool.close().await;
    }

    pub(crate) fn err(&self, doing: &'static str) -> impl FnOnce(sqlx::Error) -> RecordsError + '_ {
        move |e| db_error(&self.db, doing, e)
    }

    /// The trainee named `name`, created on first use.
    pub async fn trainee(&self, name: &str) -> Result<Trainee, RecordsError> {
        validate_name(name)?;
        sqlx::query(
            "INSERT INTO trainees (name, created_ms) VALUES ($1, $2) ON CONFLICT (name) DO NOTHING",
        )
        .bind(name)
        .bind(now_ms())
        .execute(&self.pool)
        .await
        .map_err(self.err("adding a trainee"))?;
        let id: i64 = sqlx::query("SELECT id FROM trainees WHERE name = $1")
            .bind(name)
            .fetch_one(&self.pool)
            .await
            .and_then(|r| r.try_get(0))
            .map_err(self.err("finding a trainee"))?;
        Ok(Trainee {
            id,
            name: name.to_string(),
        })
    }

    /// The trainee named `name`, or `UnknownTrainee` (the read side never
    /// creates one).
    pub async fn find_trainee(&self, name: &str) -> Result<Trainee, RecordsError> {
        validate_name(name)?;
        let row = sqlx::query("SELECT id FROM trainees WHERE name = $1")
            .bind(name)
            .fetch_optional(&self.pool)
            .await
            .map_err(self.err("finding a trainee"))?;
        match row {
            Some(r) => Ok(Trainee {
                id: r.try_get(0).map_err(self.err("finding a trainee"))?,
                name: name.to_string(),
            }),
            None => Err(RecordsError::UnknownTrainee {
                db: self.db.to_string(),
                name: name.to_string(),
            }),
        }
    }

    /// Starts a session of `trainee` under `protocol` (`two-point`, …) on
    /// this host, now, with a new unique id.
    pub async fn begin_session(
        &self,
        trainee: &Trainee,
        protocol: &str,
    ) -> Result<SessionId, RecordsError> {
        let key = SessionKey::new(&trainee.name, protocol);
        self.begin_session_keyed(trainee, &key).await
    }

    /// Starts the session `key` of `trainee` (its unique id, protocol, host
    /// and start time as given: the live exam's, or a journal's on replay).
    pub async fn begin_session_keyed(
        &self,
        trainee: &Trainee,
        key: &SessionKey,
    ) -> Result<SessionId, RecordsError> {
        let id: i64 = sqlx::query(
            "INSERT INTO sessions (trainee_id, protocol, host, started_ms, uid) VALUES ($1, $2, $3, $4, $5) RETURNING id",
        )
        .bind(trainee.id)
        .bind(&key.protocol)
        .bind(&key.host)
        .bind(key.started_ms)
        .bind(&key.uid)
        .fetch_one(&self.pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(self.err("starting a session"))?;
        Ok(SessionId(id))
    }

    /// Ends a session (its end time: now).
    pub async fn end_session(&self, session: SessionId) -> Result<(), RecordsError> {
        self.end_session_at(session, now_ms()).await
    }

    /// Ends a session at `ended_ms` (Unix ms).
    pub async fn end_session_at(
        &self,
        session: SessionId,
        ended_ms: i64,
    ) -> Result<(), RecordsError> {
        sqlx::query("UPDATE sessions SET ended_ms = $1 WHERE id = $2")
            .bind(ended_ms)
            .bind(session.0)
            .execute(&self.pool)
            .await
            .map_err(self.err("ending a session"))?;
        Ok(())
    }

    /// Starts an attempt at case `case` in `session`, with the case's
    /// ground truth (one transaction), now, with a new unique id.
    pub async fn begin_case(
        &self,
        session: SessionId,
        case: &str,
        truth: &[TruthSegment],
    ) -> Result<CaseId, RecordsError> {
        self.begin_case_keyed(session, &CaseKey::new(case), truth)
            .await
    }

    /// Starts the attempt `key` (its unique id, case name and start time as
    /// given) in `session`, with the case's ground truth (one transaction).
    pub async fn begin_case_keyed(
        &self,
        session: SessionId,
        key: &CaseKey,
        truth: &[TruthSegment],
    ) -> Result<CaseId, RecordsError> {
        let mut tx = self
            .pool
            .begin()
            .await
            .map_err(self.err("starting a case"))?;
        let id: i64 = sqlx::query(
            "INSERT INTO case_attempts (session_id, case_name, started_ms, uid) VALUES ($1, $2, $3, $4) RETURNING id",
        )
        .bind(session.0)
        .bind(&key.name)
        .bind(key.started_ms)
        .bind(&key.uid)
        .fetch_one(&mut *tx)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(self.err("starting a case"))?;
        for (seq, t) in truth.iter().enumerate() {
            sqlx::query(
                "INSERT INTO truth_pieces (case_id, seq, vein, s_start, s_end, kind) VALUES ($1, $2, $3, $4, $5, $6)",
            )
            .bind(id)
            .bind(seq as i64)
            .bind(&t.vein)
            .bind(t.s_start)
            .bind(t.s_end)
            .bind(&t.kind)
            .execute(&mut *tx)
            .await
            .map_err(self.err("storing a case's truth"))?;
        }
        tx.commit().await.map_err(self.err("starting a case"))?;
        Ok(CaseId(id))
    }

    /// Stores a compression event of `case` as its `seq`-th; returns its id.
    pub async fn record_event(
        &self,
        case: CaseId,
        seq: u32,
        e: &CompressionEvent,
    ) -> Result<i64, RecordsError> {
        let trace = serde_json::to_string(&e.force_trace).map_err(|err| RecordsError::BadRow {
            db: self.db.to_string(),
            table: "events",
            id: -1,
            why: format!("force trace not representable as JSON: {err}"),
        })?;
        sqlx::query(
            "INSERT INTO events (case_id, seq, t_start, t_end, vein, s, peak_force, min_lumen_ratio, \
             artery_deformed, coapted, slide, force_trace) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12) RETURNING id",
        )
        .bind(case.0)
        .bind(i64::from(seq))
        .bind(e.t_start)
        .bind(e.t_end)
        .bind(e.vein.clone())
        .bind(e.s)
        .bind(e.peak_force)
        .bind(e.min_lumen_ratio)
        .bind(i64::from(e.artery_deformed))
        .bind(i64::from(e.coapted))
        .bind(e.slide)
        .bind(trace)
        .fetch_one(&self.pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(self.err("storing an event"))
    }

    /// Stores a call of `case` as its `seq`-th; returns its id.
    pub async fn record_call(&self, case: CaseId, seq: u32, c: &Call) -> Result<i64, RecordsError> {
        sqlx::query(
            "INSERT INTO calls (case_id, seq, site, vein, s, finding, truth, t) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8) RETURNING id",
        )
        .bind(case.0)
        .bind(i64::from(seq))
        .bind(&c.site)
        .bind(&c.vein)
        .bind(c.s)
        .bind(c.finding.name())
        .bind(c.truth.name())
        .bind(c.t)
        .fetch_one(&self.pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(self.err("storing a call"))
    }

    /// Stores the end of `case` now: its coverage strip, its score, its
    /// sites and its Doppler score, in one transaction (all or nothing).
    pub async fn finish_case(
        &self,
        case: CaseId,
        coverage: &[CoverageBin],
        score: &CaseScore,
    ) -> Result<(), RecordsError> {
        self.finish_case_at(case, coverage, score, now_ms()).await
    }

    /// [`Self::finish_case`] at `finished_ms` (Unix ms: the live exam's
    /// time, kept by a journal for its replay).
    pub async fn finish_case_at(
        &self,
        case: CaseId,
        coverage: &[CoverageBin],
        score: &CaseScore,
        finished_ms: i64,
    ) -> Result<(), RecordsError> {
        let doing = "storing a case's score";
        let mut tx = self.pool.begin().await.map_err(self.err(doing))?;
        for (seq, b) in coverage.iter().enumerate() {
            sqlx::query(
                "INSERT INTO coverage_bins (case_id, seq, vein, s_start, s_end, state) VALUES ($1, $2, $3, $4, $5, $6)",
            )
            .bind(case.0)
            .bind(seq as i64)
            .bind(&b.vein)
            .bind(b.s_start)
            .bind(b.s_end)
            .bind(b.state.name())
            .execute(&mut *tx)
            .await
            .map_err(self.err(doing))?;
        }
        for (seq, s) in score.sites.iter().enumerate() {
            sqlx::query(
                "INSERT INTO site_scores (case_id, seq, site, finding, truth, pressure_adequate, \
                 called_without_adequate_pressure) VALUES ($1, $2, $3, $4, $5, $6, $7)",
            )
            .bind(case.0)
            .bind(seq as i64)
            .bind(&s.site)
            .bind(s.call.map(|f| f.name()))
            .bind(s.truth.name())
            .bind(i64::from(s.pressure_adequate))
            .bind(i64::from(s.called_without_adequate_pressure))
            .execute(&mut *tx)
            .await
            .map_err(self.err(doing))?;
        }
        self.insert_doppler_sites(&mut tx, case.0, &score.doppler)
            .await?;
        sqlx::query(
            "UPDATE case_attempts SET finished_ms = $1, protocol = $2, coverage = $3, calls_correct = $4, \
             calls_total = $5, pressure_adequate = $6, excessive_force_on_tail = $7, duration = $8, \
             peak_force = $9, mean_force = $10, missed = $11, doppler_correct = $12, doppler_total = $13 \
             WHERE id = $14",
        )
        .bind(finished_ms)
        .bind(&score.protocol)
        .bind(score.coverage)
        .bind(i64::from(score.calls_correct))
        .bind(i64::from(score.calls_total))
        .bind(score.pressure_adequate)
        .bind(i64::from(score.excessive_force_on_tail))
        .bind(score.duration)
        .bind(score.peak_force)
        .bind(score.mean_force)
        .bind(serde_json::to_string(&score.missed).map_err(|err| RecordsError::BadRow {
            db: self.db.to_string(),
            table: "case_attempts",
            id: case.0,
            why: format!("missed segments not representable as JSON: {err}"),
        })?)
        .bind(i64::from(score.doppler.correct))
        .bind(i64::from(score.doppler.total))
        .bind(case.0)
        .execute(&mut *tx)
        .await
        .map_err(self.err(doing))?;
        tx.commit().await.map_err(self.err(doing))
    }
}
