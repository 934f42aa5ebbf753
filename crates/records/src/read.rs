//! The read side: a trainee's history, every trainee's summary (the
//! instructor's page), per-site statistics and one case in full. Rows are
//! read plainly and the arithmetic is done by [`crate::stats`], so both
//! databases give the same numbers.

use crate::stats::{by_site, CaseOutcome, Confusion, Rates};
use crate::{RecordsError, Store, TruthSegment};
use echothigh_exam::{
    BinState, Call, CaseScore, CompressionEvent, CoverageBin, DopplerCall, Finding, SiteScore,
};
use serde::Serialize;
use sqlx::any::AnyRow;
use sqlx::Row;
use std::collections::HashMap;

/// A finished case's score numbers (the columns of `case_attempts`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScoreNumbers {
    /// Protocol scored against.
    pub protocol: String,
    /// Coverage, in [0, 1].
    pub coverage: f64,
    /// Calls matching the truth.
    pub calls_correct: u32,
    /// Calls asked for.
    pub calls_total: u32,
    /// Fraction of presses with adequate pressure, in [0, 1].
    pub pressure_adequate: f64,
    /// Presses over a free-floating tail above the safe force.
    pub excessive_force_on_tail: u32,
    /// Case duration (s).
    pub duration: f64,
    /// Peak probe force (N).
    pub peak_force: f64,
    /// Mean probe force over presses (N).
    pub mean_force: f64,
}

/// One case attempt in a history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseSummary {
    /// Row id (for [`Store::case_detail`]).
    pub id: i64,
    /// The case's name.
    pub case: String,
    /// Start (Unix ms).
    pub started_ms: i64,
    /// End (Unix ms), `None` while unfinished (or interrupted).
    pub finished_ms: Option<i64>,
    /// The score, once finished.
    pub score: Option<ScoreNumbers>,
}

/// One session in a history, with its rates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionRecord {
    /// Row id.
    pub id: i64,
    /// Protocol.
    pub protocol: String,
    /// Host the session ran on.
    pub host: String,
    /// Start (Unix ms).
    pub started_ms: i64,
    /// End (Unix ms), `None` if never ended.
    pub ended_ms: Option<i64>,
    /// Its case attempts, in order.
    pub cases: Vec<CaseSummary>,
    /// The rates over its finished cases.
    pub rates: Rates,
}

/// Statistics of one site over a set of cases.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SiteStats {
    /// The site's name.
    pub site: String,
    /// Acute-DVT counts there.
    pub confusion: Confusion,
    /// TP / (TP + FN).
    pub sensitivity: Option<f64>,
    /// TN / (TN + FP).
    pub specificity: Option<f64>,
}

/// A trainee's whole record (the trainee page, the report).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TraineeHistory {
    /// The trainee's name.
    pub name: String,
    /// Sessions, oldest first (their rates are the trend).
    pub sessions: Vec<SessionRecord>,
    /// Rates over every finished case.
    pub rates: Rates,
    /// Per site, over every finished case.
    pub sites: Vec<SiteStats>,
    /// The diseased segments the finished cases missed.
    pub missed: Vec<crate::breakdown::MissedInCase>,
    /// Doppler accuracy per Doppler site, over every finished case.
    pub doppler: Vec<crate::breakdown::DopplerAccuracy>,
}

/// One row of the instructor's page.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TraineeSummary {
    /// Name.
    pub name: String,
    /// Sessions started.
    pub sessions: u32,
    /// Case attempts started.
    pub cases: u32,
    /// Latest activity (Unix ms): a session's start or end, a case's end.
    pub last_seen_ms: Option<i64>,
    /// Rates over every finished case.
    pub rates: Rates,
}

/// One case attempt in full (the report's plots and table).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseDetail {
    /// Row id.
    pub id: i64,
    /// The case's name.
    pub case: String,
    /// The ground truth stored with it.
    pub truth: Vec<TruthSegment>,
    /// Compression events, in order.
    pub events: Vec<CompressionEvent>,
    /// Calls, in order.
    pub calls: Vec<Call>,
    /// Doppler calls, in order.
    pub doppler_calls: Vec<DopplerCall>,
    /// The coverage strip (empty until finished).
    pub coverage: Vec<CoverageBin>,
    /// The score, once finished.
    pub score: Option<CaseScore>,
}

struct CaseRow {
    id: i64,
    session: i64,
    summary: CaseSummary,
}

/// Rows of one or all trainees, read with three plain queries.
struct Loaded {
    cases: Vec<CaseRow>,
    outcomes: HashMap<i64, CaseOutcome>,
}

const CASES: &str = "SELECT c.id, c.session_id, c.case_name, c.started_ms, c.finished_ms, c.protocol, \
    c.coverage, c.calls_correct, c.calls_total, c.pressure_adequate, c.excessive_force_on_tail, \
    c.duration, c.peak_force, c.mean_force FROM case_attempts c JOIN sessions s ON c.session_id = s.id";
const SITES: &str = "SELECT ss.case_id, ss.site, ss.finding, ss.truth FROM site_scores ss \
    JOIN case_attempts c ON ss.case_id = c.id JOIN sessions s ON c.session_id = s.id";
const PRESSES: &str = "SELECT e.case_id, e.artery_deformed, e.coapted FROM events e \
    JOIN case_attempts c ON e.case_id = c.id JOIN sessions s ON c.session_id = s.id";

fn u32_of(v: i64) -> u32 {
    u32::try_from(v.max(0)).unwrap_or(u32::MAX)
}

impl Store {
    fn bad_row(&self, table: &'static str, id: i64, why: String) -> RecordsError {
        RecordsError::BadRow {
            db: self.db.to_string(),
            table,
            id,
            why,
        }
    }

    fn finding(&self, table: &'static str, id: i64, name: &str) -> Result<Finding, RecordsError> {
        Finding::from_name(name)
            .ok_or_else(|| self.bad_row(table, id, format!("unknown finding `{name}`")))
    }

    pub(crate) async fn rows(
        &self,
        sql: String,
        trainee: Option<i64>,
    ) -> Result<Vec<AnyRow>, RecordsError> {
        let q = sqlx::query(&sql);
        let q = match trainee {
            Some(t) => q.bind(t),
            None => q,
        };
        q.fetch_all(&self.pool)
            .await
            .map_err(self.err("reading the records"))
    }

    async fn load(&self, trainee: Option<i64>) -> Result<Loaded, RecordsError> {
        let filter = if trainee.is_some() {
            " WHERE s.trainee_id = $1"
        } else {
            ""
        };
        let mut cases = Vec::new();
        let mut outcomes = HashMap::new();
        for r in self
            .rows(format!("{CASES}{filter} ORDER BY c.id"), trainee)
            .await?
        {
            let id: i64 = self.get(&r, 0)?;
            let finished: Option<i64> = self.get(&r, 4)?;
            let score = match finished {
                None => None,
                Some(_) => Some(decode_score(&r).map_err(self.err("reading a score"))?),
            };
            if let Some(s) = &score {
                outcomes.insert(
                    id,
                    CaseOutcome {
                        coverage: s.coverage,
                        calls_correct: s.calls_correct,
                        calls_total: s.calls_total,
                        ..CaseOutcome::default()
                    },
                );
            }
            cases.push(CaseRow {
                id,
                session: self.get(&r, 1)?,
                summary: CaseSummary {
                    id,
                    case: self.get(&r, 2)?,
                    started_ms: self.get(&r, 3)?,
                    finished_ms: finished,
                    score,
                },
            });
        }
        for r in self
            .rows(
                format!("{SITES}{filter} ORDER BY ss.case_id, ss.seq"),
                trainee,
            )
            .await?
        {
            let case: i64 = self.get(&r, 0)?;
            let call: Option<String> = self.get(&r, 2)?;
            let call = match call {
                Some(c) => Some(self.finding("site_scores", case, &c)?),
                None => None,
            };
            let truth: String = self.get(&r, 3)?;
            let truth = self.finding("site_scores", case, &truth)?;
            if let Some(o) = outcomes.get_mut(&case) {
                o.sites.push((self.get(&r, 1)?, call, truth));
            }
        }
        for r in self.rows(format!("{PRESSES}{filter}"), trainee).await? {
            let case: i64 = self.get(&r, 0)?;
            let adequate = self.get::<i64>(&r, 1)? != 0 || self.get::<i64>(&r, 2)? != 0;
            if let Some(o) = outcomes.get_mut(&case) {
                o.presses += 1;
                o.adequate_presses += u32::from(adequate);
            }
        }
        Ok(Loaded { cases, outcomes })
    }

    pub(crate) fn get<'r, T>(&self, r: &'r AnyRow, i: usize) -> Result<T, RecordsError>
    where
        T: sqlx::Decode<'r, sqlx::Any> + sqlx::Type<sqlx::Any>,
    {
        r.try_get(i).map_err(self.err("reading the records"))
    }
}

/// The score columns 5.. of a `CASES` row.
fn decode_score(r: &AnyRow) -> Result<ScoreNumbers, sqlx::Error> {
    Ok(ScoreNumbers {
        protocol: r.try_get::<Option<String>, _>(5)?.unwrap_or_default(),
        coverage: r.try_get::<Option<f64>, _>(6)?.unwrap_or(0.0),
        calls_correct: u32_of(r.try_get::<Option<i64>, _>(7)?.unwrap_or(0)),
        calls_total: u32_of(r.try_get::<Option<i64>, _>(8)?.unwrap_or(0)),
        pressure_adequate: r.try_get::<Option<f64>, _>(9)?.unwrap_or(0.0),
        excessive_force_on_tail: u32_of(r.try_get::<Option<i64>, _>(10)?.unwrap_or(0)),
        duration: r.try_get::<Option<f64>, _>(11)?.unwrap_or(0.0),
        peak_force: r.try_get::<Option<f64>, _>(12)?.unwrap_or(0.0),
        mean_force: r.try_get::<Option<f64>, _>(13)?.unwrap_or(0.0),
    })
}

fn site_stats(outcomes: &[&CaseOutcome]) -> Vec<SiteStats> {
    by_site(outcomes.iter().copied())
        .into_iter()
        .map(|(site, confusion)| SiteStats {
            site,
            sensitivity: confusion.sensitivity(),
            specificity: confusion.specificity(),
            confusion,
        })
        .collect()
}

const BIN_STATES: [BinState; 4] = [
    BinState::NotExamined,
    BinState::InadequatePressure,
    BinState::NotClosed,
    BinState::Closed,
];

impl Store {
    /// The record of the trainee named `name` (`UnknownTrainee` if none).
    pub async fn history(&self, name: &str) -> Result<TraineeHistory, RecordsError> {
        let t = self.find_trainee(name).await?;
        let loaded = self.load(Some(t.id)).await?;
        let mut sessions = Vec::new();
        let sql =
            "SELECT id, protocol, host, started_ms, ended_ms FROM sessions WHERE trainee_id = $1 \
                   ORDER BY started_ms, id";
        for r in self.rows(sql.to_string(), Some(t.id)).await? {
            let id: i64 = self.get(&r, 0)?;
            let cases: Vec<&CaseRow> = loaded.cases.iter().filter(|c| c.session == id).collect();
            let outs: Vec<&CaseOutcome> = cases
                .iter()
                .filter_map(|c| loaded.outcomes.get(&c.id))
                .collect();
            sessions.push(SessionRecord {
                id,
                protocol: self.get(&r, 1)?,
                host: self.get(&r, 2)?,
                started_ms: self.get(&r, 3)?,
                ended_ms: self.get(&r, 4)?,
                cases: cases.iter().map(|c| c.summary.clone()).collect(),
                rates: Rates::of(outs),
            });
        }
        let all: Vec<&CaseOutcome> = loaded
            .cases
            .iter()
            .filter_map(|c| loaded.outcomes.get(&c.id))
            .collect();
        Ok(TraineeHistory {
            name: t.name,
            sessions,
            rates: Rates::of(all.iter().copied()),
            sites: site_stats(&all),
            missed: self.missed_of(t.id).await?,
            doppler: self.doppler_of(t.id).await?,
        })
    }

    /// Every trainee's summary, by name.
    pub async fn trainees(&self) -> Result<Vec<TraineeSummary>, RecordsError> {
        let loaded = self.load(None).await?;
        let mut session_of: HashMap<i64, (i64, Option<i64>)> = HashMap::new(); // session → (trainee, last)
        let mut out = Vec::new();
        let mut index: HashMap<i64, usize> = HashMap::new();
        for r in self
            .rows("SELECT id, name FROM trainees ORDER BY name".into(), None)
            .await?
        {
            index.insert(self.get(&r, 0)?, out.len());
            out.push((
                self.get::<String>(&r, 1)?,
                0u32,
                0u32,
                None::<i64>,
                Vec::<i64>::new(),
            ));
        }
        for r in self
            .rows(
                "SELECT id, trainee_id, started_ms, ended_ms FROM sessions".into(),
                None,
            )
            .await?
        {
            let (sid, tid): (i64, i64) = (self.get(&r, 0)?, self.get(&r, 1)?);
            let last = [
                Some(self.get::<i64>(&r, 2)?),
                self.get::<Option<i64>>(&r, 3)?,
            ]
            .into_iter()
            .flatten()
            .max();
            session_of.insert(sid, (tid, last));
            if let Some(&i) = index.get(&tid) {
                out[i].1 += 1;
                out[i].3 = out[i].3.max(last);
            }
        }
        for c in &loaded.cases {
            if let Some(&i) = session_of
                .get(&c.session)
                .and_then(|(tid, _)| index.get(tid))
            {
                out[i].2 += 1;
                out[i].3 = out[i].3.max(c.summary.finished_ms);
                out[i].4.push(c.id);
            }
        }
        Ok(out
            .into_iter()
            .map(
                |(name, sessions, cases, last_seen_ms, ids)| TraineeSummary {
                    name,
                    sessions,
                    cases,
                    last_seen_ms,
                    rates: Rates::of(ids.iter().filter_map(|id| loaded.outcomes.get(id))),
                },
            )
            .collect())
    }

    /// Per-site statistics over every finished case of every trainee (the
    /// trainee's own are in [`TraineeHistory::sites`]).
    pub async fn site_stats(&self) -> Result<Vec<SiteStats>, RecordsError> {
        let loaded = self.load(None).await?;
        let all: Vec<&CaseOutcome> = loaded
            .cases
            .iter()
            .filter_map(|c| loaded.outcomes.get(&c.id))
            .collect();
        Ok(site_stats(&all))
    }

    /// One case attempt in full.
    pub async fn case_detail(&self, id: i64) -> Result<CaseDetail, RecordsError> {
        let sql = format!("{CASES} WHERE c.id = $1");
        let rows = self.rows(sql, Some(id)).await?;
        let r = rows
            .first()
            .ok_or_else(|| self.bad_row("case_attempts", id, "no such case attempt".into()))?;
        let case: String = self.get(r, 2)?;
        let finished: Option<i64> = self.get(r, 4)?;
        let numbers = match finished {
            Some(_) => Some(decode_score(r).map_err(self.err("reading a score"))?),
            None => None,
        };
        let mut truth = Vec::new();
        let sql =
            "SELECT vein, s_start, s_end, kind FROM truth_pieces WHERE case_id = $1 ORDER BY seq";
        for r in self.rows(sql.into(), Some(id)).await? {
            truth.push(TruthSegment {
                vein: self.get(&r, 0)?,
                s_start: self.get(&r, 1)?,
                s_end: self.get(&r, 2)?,
                kind: self.get(&r, 3)?,
            });
        }
        let mut events = Vec::new();
        let sql = "SELECT id, t_start, t_end, vein, s, peak_force, min_lumen_ratio, artery_deformed, coapted, \
                   slide, force_trace FROM events WHERE case_id = $1 ORDER BY seq, id";
        for r in self.rows(sql.into(), Some(id)).await? {
            let eid: i64 = self.get(&r, 0)?;
            let trace: String = self.get(&r, 10)?;
            events.push(CompressionEvent {
                t_start: self.get(&r, 1)?,
                t_end: self.get(&r, 2)?,
                vein: self.get(&r, 3)?,
                s: self.get(&r, 4)?,
                peak_force: self.get(&r, 5)?,
                min_lumen_ratio: self.get(&r, 6)?,
                artery_deformed: self.get::<i64>(&r, 7)? != 0,
                coapted: self.get::<i64>(&r, 8)? != 0,
                slide: self.get(&r, 9)?,
                force_trace: serde_json::from_str(&trace)
                    .map_err(|e| self.bad_row("events", eid, format!("force trace: {e}")))?,
            });
        }
        let mut calls = Vec::new();
        let sql = "SELECT id, site, vein, s, finding, truth, t FROM calls WHERE case_id = $1 ORDER BY seq, id";
        for r in self.rows(sql.into(), Some(id)).await? {
            let cid: i64 = self.get(&r, 0)?;
            calls.push(Call {
                site: self.get(&r, 1)?,
                vein: self.get(&r, 2)?,
                s: self.get(&r, 3)?,
                finding: self.finding("calls", cid, &self.get::<String>(&r, 4)?)?,
                truth: self.finding("calls", cid, &self.get::<String>(&r, 5)?)?,
                t: self.get(&r, 6)?,
            });
        }
        let mut coverage = Vec::new();
        let sql = "SELECT id, vein, s_start, s_end, state FROM coverage_bins WHERE case_id = $1 ORDER BY seq";
        for r in self.rows(sql.into(), Some(id)).await? {
            let bid: i64 = self.get(&r, 0)?;
            let state: String = self.get(&r, 4)?;
            coverage.push(CoverageBin {
                vein: self.get(&r, 1)?,
                s_start: self.get(&r, 2)?,
                s_end: self.get(&r, 3)?,
                state: BIN_STATES
                    .into_iter()
                    .find(|b| b.name() == state)
                    .ok_or_else(|| {
                        self.bad_row("coverage_bins", bid, format!("unknown state `{state}`"))
                    })?,
            });
        }
        let mut sites = Vec::new();
        let sql =
            "SELECT id, site, finding, truth, pressure_adequate, called_without_adequate_pressure \
                   FROM site_scores WHERE case_id = $1 ORDER BY seq";
        for r in self.rows(sql.into(), Some(id)).await? {
            let sid: i64 = self.get(&r, 0)?;
            let call = match self.get::<Option<String>>(&r, 2)? {
                Some(c) => Some(self.finding("site_scores", sid, &c)?),
                None => None,
            };
            sites.push(SiteScore {
                site: self.get(&r, 1)?,
                call,
                truth: self.finding("site_scores", sid, &self.get::<String>(&r, 3)?)?,
                pressure_adequate: self.get::<i64>(&r, 4)? != 0,
                called_without_adequate_pressure: self.get::<i64>(&r, 5)? != 0,
            });
        }
        let doppler_calls = self.doppler_calls(id).await?;
        let doppler = match &numbers {
            Some(_) => {
                let sql = "SELECT doppler_correct, doppler_total FROM case_attempts WHERE id = $1";
                let counts = match self.rows(sql.into(), Some(id)).await?.first() {
                    Some(r) => match (
                        self.get::<Option<i64>>(r, 0)?,
                        self.get::<Option<i64>>(r, 1)?,
                    ) {
                        (Some(c), Some(t)) => Some((u32_of(c), u32_of(t))),
                        _ => None,
                    },
                    None => None,
                };
                self.doppler_score(id, counts).await?
            }
            None => Default::default(),
        };
        let missed = match &numbers {
            Some(_) => {
                let sql = "SELECT missed FROM case_attempts WHERE id = $1";
                let text: Option<String> = match self.rows(sql.into(), Some(id)).await?.first() {
                    Some(r) => self.get(r, 0)?,
                    None => None,
                };
                match text {
                    Some(t) => serde_json::from_str(&t)
                        .map_err(|e| self.bad_row("case_attempts", id, format!("missed: {e}")))?,
                    None => Vec::new(),
                }
            }
            None => Vec::new(),
        };
        let score = numbers.map(|n| CaseScore {
            case: case.clone(),
            protocol: n.protocol,
            coverage: n.coverage,
            calls_correct: n.calls_correct,
            calls_total: n.calls_total,
            pressure_adequate: n.pressure_adequate,
            excessive_force_on_tail: n.excessive_force_on_tail,
            duration: n.duration,
            peak_force: n.peak_force,
            mean_force: n.mean_force,
            sites,
            missed,
            doppler,
        });
        Ok(CaseDetail {
            id,
            case,
            truth,
            events,
            calls,
            doppler_calls,
            coverage,
            score,
        })
    }
}
