//! One trainee's exam session, shared by the server's connections and the
//! exam observer thread: the plan's cases one after the other, each
//! examined through a [`CaseExam`] whose records go to the sink's log.

use super::plan::ExamPlan;
use super::sink::{CaseLog, RecordSink};
use crate::exam_status::{CaseFeedback, DopplerSiteStatus, ExamStatus, SiteStatus, TruthSegment};
use echothigh_cases::Case;
use echothigh_exam::{CaseExam, CaseExamError, DopplerFinding, ExamSample, Finding, LogError};
use std::time::Instant;

/// Why an exam command was refused.
#[derive(Debug, thiserror::Error)]
pub enum ExamError {
    /// A command that needs an open case came with none.
    #[error("no case is open: start one first")]
    NoCase,
    /// A case is already open.
    #[error("case {0} is open: finish it (or leave the exam) first")]
    CaseOpen(u32),
    /// Every case of the plan has been examined.
    #[error("all {0} cases of this session have been examined")]
    NoMoreCases(usize),
    /// A step of the case was refused (unknown site, bad sample, record).
    #[error(transparent)]
    Case(#[from] CaseExamError),
    /// The record sink failed.
    #[error("recording the exam: {0}")]
    Log(#[from] LogError),
}

/// The open case.
struct Open {
    index: usize,
    exam: CaseExam,
    log: CaseLog,
    started: Instant,
    /// The trainee has moved the probe since the case opened: only then do
    /// the samples count (the case's own reset is not the trainee's press).
    armed: bool,
    /// Each site's probe angle over its vein ([`SiteStatus::theta`]),
    /// computed once when the case opens.
    thetas: Vec<Option<f64>>,
}

/// The probe angle (page convention) over each of `exam`'s sites on `case`.
fn site_thetas(case: &Case, exam: &CaseExam) -> Vec<Option<f64>> {
    let a = &case.anatomy;
    exam.sites()
        .iter()
        .map(|x| a.pose_over(x.s, a.deep_vein_at(x.s)).ok().map(|p| -p.theta))
        .collect()
}

/// A trainee's exam session.
pub struct ExamSession {
    pub(super) plan: ExamPlan,
    sink: Box<dyn RecordSink>,
    /// Index of the next case of the plan.
    pub(super) next: usize,
    /// The plan starts over once examined (practice).
    cycle: bool,
    open: Option<Open>,
    pub(super) status: ExamStatus,
}

impl ExamSession {
    /// A session over `plan` recording to `sink`; `cycle` starts the plan
    /// over once every case has been examined.
    pub fn new(plan: ExamPlan, sink: Box<dyn RecordSink>, cycle: bool) -> Self {
        let status = ExamStatus {
            trainee: plan.trainee.clone(),
            protocol: plan.protocol.name().to_string(),
            recording: sink.describe(),
            cases_total: plan.cases.len() as u32,
            ..ExamStatus::default()
        };
        ExamSession {
            plan,
            sink,
            next: 0,
            cycle,
            open: None,
            status,
        }
    }

    /// Opens the plan's next case (exam mode turns on) and returns it, for
    /// the caller to load into the live system ([`Self::abandon`] if that
    /// fails).
    pub fn start(&mut self) -> Result<&Case, ExamError> {
        if self.open.is_some() {
            return Err(ExamError::CaseOpen(self.status.case_number));
        }
        if self.next >= self.plan.cases.len() {
            if !self.cycle || self.plan.cases.is_empty() {
                return Err(ExamError::NoMoreCases(self.plan.cases.len()));
            }
            self.next = 0;
        }
        let index = self.next;
        let case = &self.plan.cases[index];
        let log = self.sink.begin_case(case, self.plan.protocol)?;
        let exam = CaseExam::new(case, self.plan.protocol);
        self.open = Some(Open {
            index,
            thetas: site_thetas(case, &exam),
            exam,
            log,
            started: Instant::now(),
            armed: false,
        });
        self.next += 1;
        self.status.active = true;
        self.status.case_number += 1;
        self.status.error = None;
        self.refresh();
        Ok(&self.plan.cases[index])
    }

    /// Reopens the plan's case `index` as `exam`, writing on with `log`,
    /// its clock going on from the exam's last record (a resumed session,
    /// [`super::resume`]). The trainee's samples count once the probe
    /// moves, as in a case just started.
    pub(super) fn reopen(&mut self, index: usize, exam: CaseExam, log: CaseLog) {
        let case = &self.plan.cases[index];
        let back = std::time::Duration::from_secs_f64(exam.last_time().clamp(0.0, 1e6));
        let now = Instant::now();
        self.open = Some(Open {
            index,
            thetas: site_thetas(case, &exam),
            exam,
            log,
            started: now.checked_sub(back).unwrap_or(now),
            armed: false,
        });
        self.status.active = true;
        self.status.error = None;
    }

    /// Drops the open case unscored (the live system could not load it, or
    /// the trainee left): its records so far stay, unfinished.
    pub fn abandon(&mut self) {
        if self.open.take().is_some() {
            self.refresh();
        }
    }

    /// The server is stopping: an open case stays unfinished in the
    /// records, and the session stays open for the next server to resume
    /// ([`super::resume`]) unless every case of the plan has been examined,
    /// when it ends as [`Self::stop`] ends it.
    pub fn suspend(&mut self) {
        let examined = !self.cycle && self.open.is_none() && self.next >= self.plan.cases.len();
        if examined {
            self.stop();
        } else {
            self.open = None;
            self.status.active = false;
            self.refresh();
        }
    }

    /// Leaves exam mode: an open case is dropped unscored.
    pub fn stop(&mut self) {
        self.open = None;
        self.status.active = false;
        if let Err(e) = self.sink.end() {
            self.status.error = Some(format!("closing the session's records: {e}"));
        }
        self.refresh();
    }

    /// The trainee moved the probe: from now on the samples are theirs.
    pub fn trainee_pressed(&mut self) {
        if let Some(o) = self.open.as_mut() {
            o.armed = true;
        }
    }

    /// Seconds since the open case started, at `now`, once armed.
    pub fn case_time(&self, now: Instant) -> Option<f64> {
        let o = self.open.as_ref().filter(|o| o.armed)?;
        Some(now.saturating_duration_since(o.started).as_secs_f64())
    }

    /// Feeds a sample of the live state (its `t` from [`Self::case_time`]).
    /// The status changes only when a press starts or ends.
    pub fn observe(&mut self, sample: &ExamSample) -> Result<(), ExamError> {
        let Some(o) = self.open.as_mut().filter(|o| o.armed) else {
            return Ok(());
        };
        let was = o.exam.pressing();
        // A failed record (the log's error) still ended a press: the
        // press is kept in memory and the page hears of it.
        let seen = o.exam.observe(sample, o.log.as_mut()).map(|e| e.is_some());
        let ended = matches!(seen, Ok(true) | Err(CaseExamError::Log(_)));
        if ended || was != o.exam.pressing() {
            self.refresh();
        }
        seen.map(drop).map_err(ExamError::from)
    }

    /// The trainee calls `finding` at `site` of the open case.
    pub fn call(&mut self, site: &str, finding: Finding) -> Result<(), ExamError> {
        let o = self.open.as_mut().ok_or(ExamError::NoCase)?;
        let t = o.started.elapsed().as_secs_f64();
        let made = o.exam.call(site, finding, t, o.log.as_mut()).map(drop);
        self.refresh();
        Ok(made?)
    }

    /// The trainee calls the spectral Doppler at the Doppler site `site`
    /// of the open case.
    pub fn call_doppler(&mut self, site: &str, finding: DopplerFinding) -> Result<(), ExamError> {
        let o = self.open.as_mut().ok_or(ExamError::NoCase)?;
        let t = o.started.elapsed().as_secs_f64();
        let made = o
            .exam
            .call_doppler(site, finding, t, o.log.as_mut())
            .map(drop);
        self.refresh();
        Ok(made?)
    }

    /// Finishes the open case: scores it and reveals its truth.
    pub fn finish(&mut self) -> Result<(), ExamError> {
        let mut o = self.open.take().ok_or(ExamError::NoCase)?;
        let t = o.started.elapsed().as_secs_f64();
        let mut log_error = None;
        let score = match o.exam.finish(t, o.log.as_mut()) {
            Ok(s) => s,
            Err(e) => match (e, o.exam.score().cloned()) {
                // The records could not be kept where they go (the log's
                // fault says where they are): the score is in memory, the
                // case ends.
                (CaseExamError::Log(e), Some(s)) => {
                    log_error = Some(format!("recording the exam: {e}"));
                    s
                }
                (e, _) => {
                    // Keep the case open: the trainee may retry the finish.
                    self.open = Some(o);
                    return Err(e.into());
                }
            },
        };
        let case = &self.plan.cases[o.index];
        self.status.cases_done += 1;
        self.status.calls_correct += score.calls_correct;
        self.status.calls_total += score.calls_total;
        self.status.last = Some(CaseFeedback {
            case: case.file.name.clone(),
            title: case.file.title.clone(),
            diagnosis: case.file.truth.diagnosis.name().to_string(),
            teaching: case.file.truth.teaching.clone(),
            score,
            truth: o
                .exam
                .truth()
                .iter()
                .flat_map(|v| {
                    v.pieces.iter().map(|p| TruthSegment {
                        vein: v.vein.to_string(),
                        s_start: p.s_start,
                        s_end: p.s_end,
                        kind: p.kind.to_string(),
                    })
                })
                .collect(),
            coverage: o.exam.coverage().bins().to_vec(),
        });
        if let Some(e) = log_error {
            self.status.error = Some(e);
        }
        self.refresh();
        Ok(())
    }

    /// Records an error the page should show (a failed sample or record).
    pub fn report(&mut self, error: String) {
        if self.status.error.as_deref() != Some(error.as_str()) {
            self.status.error = Some(error);
            self.status.rev += 1;
        }
    }

    /// The records database the session writes to, if any.
    pub fn store(&self) -> Option<echothigh_records::BlockingStore> {
        self.sink.store()
    }

    /// The open case, if any.
    pub fn open_case(&self) -> Option<&Case> {
        self.open.as_ref().map(|o| &self.plan.cases[o.index])
    }

    /// Whether a case is open (its truth must stay hidden).
    pub fn is_open(&self) -> bool {
        self.open.is_some()
    }

    /// What the page may see.
    pub fn status(&self) -> &ExamStatus {
        &self.status
    }

    /// Rebuilds the page's view of the open case and bumps the revision.
    /// A records fault (the database failed: where the records are kept
    /// now) replaces `recording` and stands in `error` until a later error.
    pub(super) fn refresh(&mut self) {
        let fault = self
            .open
            .as_ref()
            .and_then(|o| o.log.fault())
            .or_else(|| self.sink.fault());
        let st = &mut self.status;
        st.rev += 1;
        if let Some(f) = fault {
            if st.recording != f {
                st.recording = f.clone();
                st.error = Some(f);
            }
        }
        st.open = self.open.is_some();
        match &self.open {
            Some(o) => {
                let case = &self.plan.cases[o.index];
                st.vignette = Some(case.file.vignette.clone());
                st.sites = o
                    .exam
                    .sites()
                    .iter()
                    .zip(&o.thetas)
                    .map(|(x, &theta)| SiteStatus {
                        name: x.name.clone(),
                        vein: x.vein.clone(),
                        s: x.s,
                        done: x.done,
                        call: o.exam.call_at(&x.name),
                        theta,
                    })
                    .collect();
                st.doppler = o
                    .exam
                    .doppler_sites()
                    .iter()
                    .map(|x| DopplerSiteStatus {
                        name: x.name.clone(),
                        vein: x.vein.clone(),
                        call: o.exam.doppler_at(&x.name),
                    })
                    .collect();
                st.coverage = o.exam.coverage().bins().to_vec();
                st.presses = o.exam.events().len() as u32;
                st.peak_force = o.exam.peak_force();
            }
            None => {
                st.vignette = None;
                st.sites.clear();
                st.doppler.clear();
                st.coverage.clear();
                st.presses = 0;
                st.peak_force = 0.0;
            }
        }
    }
}

#[cfg(test)]
#[path = "session_tests.rs"]
mod tests;
