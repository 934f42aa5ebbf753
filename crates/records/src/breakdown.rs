//! The instructor's per-site breakdown of a trainee beyond the acute-DVT
//! counts of [`crate::stats`]: the diseased segments the trainee's finished
//! cases missed, and the accuracy of the Doppler calls per site.
//!
//! Counting rule of the Doppler accuracy: a site of a finished case counts
//! once (its latest call, as scored); it is right when the pattern and the
//! augmentation both match the truth; a site without a call counts in the
//! total and as wrong (as `DopplerScore` counts it). The pattern and the
//! augmentation are also counted apart, over the sites called.

use crate::{RecordsError, Store};
use echothigh_exam::{DopplerFinding, FlowPattern, MissedSegment};
use serde::Serialize;
use sqlx::Row;

/// A missed segment and the case attempt it was missed in.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissedInCase {
    /// The case attempt's row id.
    pub case_id: i64,
    /// The case's name.
    pub case: String,
    /// The segment.
    pub segment: MissedSegment,
}

/// Doppler accuracy at one site over a set of finished cases.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct DopplerAccuracy {
    /// The Doppler site (`cfv`, `popliteal`).
    pub site: String,
    /// Sites scored (called or not).
    pub total: u32,
    /// Sites called.
    pub called: u32,
    /// Calls right in pattern and augmentation.
    pub correct: u32,
    /// Calls whose pattern was right.
    pub flow_correct: u32,
    /// Calls whose augmentation was right.
    pub augments_correct: u32,
}

impl DopplerAccuracy {
    /// correct / total, `None` without a site.
    pub fn accuracy(&self) -> Option<f64> {
        (self.total > 0).then(|| f64::from(self.correct) / f64::from(self.total))
    }
}

/// Per-site Doppler accuracy over `(site, call, truth)` rows, sites in
/// first-seen order (module docs for the counting).
pub fn doppler_accuracy<'a>(
    rows: impl IntoIterator<Item = (&'a str, Option<DopplerFinding>, DopplerFinding)>,
) -> Vec<DopplerAccuracy> {
    let mut out: Vec<DopplerAccuracy> = Vec::new();
    for (site, call, truth) in rows {
        let i = match out.iter().position(|a| a.site == site) {
            Some(i) => i,
            None => {
                out.push(DopplerAccuracy {
                    site: site.to_string(),
                    ..DopplerAccuracy::default()
                });
                out.len() - 1
            }
        };
        let a = &mut out[i];
        a.total += 1;
        if let Some(c) = call {
            a.called += 1;
            a.correct += u32::from(c == truth);
            a.flow_correct += u32::from(c.flow == truth.flow);
            a.augments_correct += u32::from(c.augments == truth.augments);
        }
    }
    out
}

impl Store {
    /// The missed segments of `trainee`'s finished cases, by case order.
    pub(crate) async fn missed_of(&self, trainee: i64) -> Result<Vec<MissedInCase>, RecordsError> {
        let rows = sqlx::query(
            "SELECT c.id, c.case_name, c.missed FROM case_attempts c JOIN sessions s \
             ON c.session_id = s.id WHERE s.trainee_id = $1 AND c.finished_ms IS NOT NULL ORDER BY c.id",
        )
        .bind(trainee)
        .fetch_all(&self.pool)
        .await
        .map_err(self.err("reading the missed segments"))?;
        let mut out = Vec::new();
        for r in &rows {
            let get = self.err("reading the missed segments");
            let (id, case, text): (i64, String, Option<String>) =
                (|| Ok::<_, sqlx::Error>((r.try_get(0)?, r.try_get(1)?, r.try_get(2)?)))()
                    .map_err(get)?;
            let segments: Vec<MissedSegment> = match text {
                Some(t) => serde_json::from_str(&t).map_err(|e| RecordsError::BadRow {
                    db: self.db.to_string(),
                    table: "case_attempts",
                    id,
                    why: format!("missed: {e}"),
                })?,
                None => Vec::new(),
            };
            out.extend(segments.into_iter().map(|segment| MissedInCase {
                case_id: id,
                case: case.clone(),
                segment,
            }));
        }
        Ok(out)
    }

    /// The Doppler accuracy per site over `trainee`'s finished cases.
    pub(crate) async fn doppler_of(
        &self,
        trainee: i64,
    ) -> Result<Vec<DopplerAccuracy>, RecordsError> {
        let rows = sqlx::query(
            "SELECT d.id, d.site, d.flow, d.augments, d.truth_flow, d.truth_augments \
             FROM doppler_site_scores d JOIN case_attempts c ON d.case_id = c.id \
             JOIN sessions s ON c.session_id = s.id WHERE s.trainee_id = $1 ORDER BY d.case_id, d.seq",
        )
        .bind(trainee)
        .fetch_all(&self.pool)
        .await
        .map_err(self.err("reading the Doppler scores"))?;
        let flow = |id: i64, name: &str| {
            FlowPattern::from_name(name).ok_or_else(|| RecordsError::BadRow {
                db: self.db.to_string(),
                table: "doppler_site_scores",
                id,
                why: format!("unknown Doppler flow `{name}`"),
            })
        };
        let mut decoded = Vec::with_capacity(rows.len());
        for r in &rows {
            let get = self.err("reading the Doppler scores");
            type RowT = (i64, String, Option<String>, Option<i64>, String, i64);
            let (id, site, f, a, tf, ta): RowT = (|| {
                Ok::<_, sqlx::Error>((
                    r.try_get(0)?,
                    r.try_get(1)?,
                    r.try_get(2)?,
                    r.try_get(3)?,
                    r.try_get(4)?,
                    r.try_get(5)?,
                ))
            })()
            .map_err(get)?;
            let call = match (f, a) {
                (Some(f), Some(a)) => Some(DopplerFinding {
                    flow: flow(id, &f)?,
                    augments: a != 0,
                }),
                _ => None,
            };
            let truth = DopplerFinding {
                flow: flow(id, &tf)?,
                augments: ta != 0,
            };
            decoded.push((site, call, truth));
        }
        Ok(doppler_accuracy(
            decoded.iter().map(|(s, c, t)| (s.as_str(), *c, *t)),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use FlowPattern::*;

    /// Four cfv sites (right; wrong augmentation; wrong pattern; not
    /// called) and one popliteal (right): cfv 1 right of 4 (0.25), 3
    /// called, pattern right in 2, augmentation right in 2; popliteal 1/1.
    #[test]
    fn doppler_accuracy_counts_both_parts_and_uncalled_sites() {
        let d = |flow, augments| DopplerFinding { flow, augments };
        let rows = [
            ("cfv", Some(d(Phasic, true)), d(Phasic, true)),
            ("cfv", Some(d(Phasic, true)), d(Phasic, false)),
            ("popliteal", Some(d(Absent, false)), d(Absent, false)),
            ("cfv", Some(d(Continuous, true)), d(Phasic, true)),
            ("cfv", None, d(Continuous, true)),
        ];
        let a = doppler_accuracy(rows);
        assert_eq!(a.len(), 2);
        assert_eq!(
            (a[0].site.as_str(), a[0].total, a[0].called, a[0].correct),
            ("cfv", 4, 3, 1)
        );
        assert_eq!((a[0].flow_correct, a[0].augments_correct), (2, 2));
        assert_eq!(a[0].accuracy(), Some(0.25));
        assert_eq!(a[1].accuracy(), Some(1.0));
        assert_eq!(DopplerAccuracy::default().accuracy(), None);
    }
}
