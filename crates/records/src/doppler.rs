//! Doppler calls in the records (schema version 2,
//! `migrations/*/0002_doppler.sql`): each call as it is made, and a
//! finished case's Doppler score per site (inside the case's finishing
//! transaction), and their reading back.

use crate::{RecordsError, Store};
use echothigh_exam::{DopplerCall, DopplerFinding, DopplerScore, DopplerSiteScore, FlowPattern};
use sqlx::Row;

/// A Doppler reading as its two columns' values (`flow`, `augments` 0/1).
fn columns(f: &DopplerFinding) -> (&'static str, i64) {
    (f.flow.name(), i64::from(f.augments))
}

impl Store {
    /// Stores a Doppler call of `case` (row id) as its `seq`-th; returns
    /// its id once committed.
    pub async fn record_doppler(
        &self,
        case: crate::CaseId,
        seq: u32,
        c: &DopplerCall,
    ) -> Result<i64, RecordsError> {
        let (flow, augments) = columns(&c.finding);
        let (truth_flow, truth_augments) = columns(&c.truth);
        sqlx::query(
            "INSERT INTO doppler_calls (case_id, seq, site, vein, s, flow, augments, truth_flow, \
             truth_augments, t) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10) RETURNING id",
        )
        .bind(case.0)
        .bind(i64::from(seq))
        .bind(&c.site)
        .bind(&c.vein)
        .bind(c.s)
        .bind(flow)
        .bind(augments)
        .bind(truth_flow)
        .bind(truth_augments)
        .bind(c.t)
        .fetch_one(&self.pool)
        .await
        .and_then(|r| r.try_get(0))
        .map_err(self.err("storing a Doppler call"))
    }

    /// The per-site rows of a Doppler score, inside the finishing
    /// transaction `tx` of `case`.
    pub(crate) async fn insert_doppler_sites(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Any>,
        case: i64,
        score: &DopplerScore,
    ) -> Result<(), RecordsError> {
        for (seq, x) in score.sites.iter().enumerate() {
            let (flow, augments) = match &x.call {
                Some(f) => (Some(f.flow.name()), Some(i64::from(f.augments))),
                None => (None, None),
            };
            let (truth_flow, truth_augments) = columns(&x.truth);
            sqlx::query(
                "INSERT INTO doppler_site_scores (case_id, seq, site, flow, augments, truth_flow, \
                 truth_augments) VALUES ($1, $2, $3, $4, $5, $6, $7)",
            )
            .bind(case)
            .bind(seq as i64)
            .bind(&x.site)
            .bind(flow)
            .bind(augments)
            .bind(truth_flow)
            .bind(truth_augments)
            .execute(&mut **tx)
            .await
            .map_err(self.err("storing a case's Doppler score"))?;
        }
        Ok(())
    }

    /// A stored pattern name, or a `BadRow` naming the table and row.
    fn flow(&self, table: &'static str, id: i64, name: &str) -> Result<FlowPattern, RecordsError> {
        FlowPattern::from_name(name).ok_or_else(|| RecordsError::BadRow {
            db: self.db.to_string(),
            table,
            id,
            why: format!("unknown Doppler flow `{name}`"),
        })
    }

    /// The Doppler calls of case attempt `id`, in order.
    pub(crate) async fn doppler_calls(&self, id: i64) -> Result<Vec<DopplerCall>, RecordsError> {
        let rows = sqlx::query(
            "SELECT id, site, vein, s, flow, augments, truth_flow, truth_augments, t \
             FROM doppler_calls WHERE case_id = $1 ORDER BY seq, id",
        )
        .bind(id)
        .fetch_all(&self.pool)
        .await
        .map_err(self.err("reading the Doppler calls"))?;
        let mut out = Vec::with_capacity(rows.len());
        for r in &rows {
            let row: (i64, String, String, f64, String, i64, String, i64, f64) = (|| {
                Ok::<_, sqlx::Error>((
                    r.try_get(0)?,
                    r.try_get(1)?,
                    r.try_get(2)?,
                    r.try_get(3)?,
                    r.try_get(4)?,
                    r.try_get(5)?,
                    r.try_get(6)?,
                    r.try_get(7)?,
                    r.try_get(8)?,
                ))
            })()
            .map_err(|e| db_err(self, e))?;
            let (cid, site, vein, s, flow, augments, truth_flow, truth_augments, t) = row;
            out.push(DopplerCall {
                site,
                vein,
                s,
                finding: DopplerFinding {
                    flow: self.flow("doppler_calls", cid, &flow)?,
                    augments: augments != 0,
                },
                truth: DopplerFinding {
                    flow: self.flow("doppler_calls", cid, &truth_flow)?,
                    augments: truth_augments != 0,
                },
                t,
            });
        }
        Ok(out)
    }

    /// The Doppler score of finished case attempt `id`: its per-site rows
    /// and the counts stored with the case (`correct`, `total`: `None` for
    /// a case finished before schema version 2, then the score is empty).
    pub(crate) async fn doppler_score(
        &self,
        id: i64,
        counts: Option<(u32, u32)>,
    ) -> Result<DopplerScore, RecordsError> {
        let Some((correct, total)) = counts else {
            return Ok(DopplerScore::default());
        };
        let rows = sqlx::query(
            "SELECT id, site, flow, augments, truth_flow, truth_augments \
             FROM doppler_site_scores WHERE case_id = $1 ORDER BY seq",
        )
        .bind(id)
        .fetch_all(&self.pool)
        .await
        .map_err(self.err("reading a Doppler score"))?;
        let mut sites = Vec::with_capacity(rows.len());
        for r in &rows {
            let row: (i64, String, Option<String>, Option<i64>, String, i64) = (|| {
                Ok::<_, sqlx::Error>((
                    r.try_get(0)?,
                    r.try_get(1)?,
                    r.try_get(2)?,
                    r.try_get(3)?,
                    r.try_get(4)?,
                    r.try_get(5)?,
                ))
            })()
            .map_err(|e| db_err(self, e))?;
            let (sid, site, flow, augments, truth_flow, truth_augments) = row;
            let call = match (flow, augments) {
                (Some(f), Some(a)) => Some(DopplerFinding {
                    flow: self.flow("doppler_site_scores", sid, &f)?,
                    augments: a != 0,
                }),
                _ => None,
            };
            sites.push(DopplerSiteScore {
                site,
                call,
                truth: DopplerFinding {
                    flow: self.flow("doppler_site_scores", sid, &truth_flow)?,
                    augments: truth_augments != 0,
                },
            });
        }
        Ok(DopplerScore {
            correct,
            total,
            sites,
        })
    }
}

/// A read error on this store.
fn db_err(store: &Store, e: sqlx::Error) -> RecordsError {
    crate::store::db_error(&store.db, "reading the Doppler records", e)
}
