//! One case examined live (issue 14): the protocol's checklist on the
//! case's leg, the event detector fed from the live state, the coverage
//! strip, the trainee's calls, and the score at the end — each record sent
//! to the [`ExamLog`] the moment it exists (an event when its press ends, a
//! call when it is made, the score when the case is finished), so that a
//! crash loses nothing already done.
//!
//! Every record is kept in memory first, whatever the log says: a log that
//! fails (a database gone mid-exam) returns its error, but the event, call
//! or score is already in [`CaseExam::events`], [`CaseExam::calls`],
//! [`CaseExam::doppler_calls`] and [`CaseExam::score`], so the page and the
//! score still have it.

use crate::coverage::{event_state, Coverage};
use crate::detector::{DetectorError, EventDetector, ExamSample};
use crate::doppler::{doppler_sites, doppler_truth, score_doppler};
use crate::score::{score_case, truth_for_call, ScoreInput};
use crate::{
    BinState, Call, CaseScore, CompressionEvent, DopplerCall, DopplerFinding, ExamLog, Finding,
    LogError, Protocol, ProtocolSite,
};
use echothigh_anatomy::VeinTruth;
use echothigh_cases::Case;

/// Longest press whose force trace is kept at full rate (s); longer ones
/// are decimated by the detector. A compression is held a few seconds
/// (compress, release, step); a minute covers a trainee who rests on the leg.
pub const MAX_PRESS: f64 = 60.0;

/// Why a case-exam step was refused.
#[derive(Debug, thiserror::Error)]
pub enum CaseExamError {
    /// A sample was malformed (the detector names the field).
    #[error(transparent)]
    Sample(#[from] DetectorError),
    /// A Doppler call named no Doppler site.
    #[error("no Doppler site `{site}` (the Doppler sites: {known})")]
    UnknownDopplerSite {
        /// The name given.
        site: String,
        /// The names there are.
        known: String,
    },
    /// A call named no site of the protocol.
    #[error("no site `{site}` in the {protocol} protocol (its sites: {known})")]
    UnknownSite {
        /// The name given.
        site: String,
        /// The protocol.
        protocol: Protocol,
        /// The names it has.
        known: String,
    },
    /// The record could not be kept.
    #[error("recording the exam: {0}")]
    Log(#[from] LogError),
}

/// A case under examination.
pub struct CaseExam {
    case: String,
    protocol: Protocol,
    sites: Vec<ProtocolSite>,
    truth: Vec<VeinTruth>,
    detector: EventDetector,
    coverage: Coverage,
    events: Vec<CompressionEvent>,
    calls: Vec<Call>,
    doppler_sites: Vec<ProtocolSite>,
    doppler_truth: Vec<DopplerFinding>,
    doppler_calls: Vec<DopplerCall>,
    last_t: f64,
    peak_force: f64,
    score: Option<CaseScore>,
}

impl CaseExam {
    /// Starts examining `case` under `protocol`: every site undone, every
    /// bin not examined.
    pub fn new(case: &Case, protocol: Protocol) -> CaseExam {
        let doppler_sites = doppler_sites(&case.anatomy);
        CaseExam {
            doppler_truth: doppler_sites
                .iter()
                .map(|x| doppler_truth(case, x.s))
                .collect(),
            doppler_sites,
            doppler_calls: Vec::new(),
            case: case.file.name.clone(),
            protocol,
            sites: protocol.sites(&case.anatomy),
            truth: case.ground_truth(),
            detector: EventDetector::new(MAX_PRESS),
            coverage: Coverage::new(&case.anatomy),
            events: Vec::new(),
            calls: Vec::new(),
            last_t: 0.0,
            peak_force: 0.0,
            score: None,
        }
    }

    /// Goes on with an attempt at `case` under `protocol` whose `events`,
    /// `calls` and `doppler_calls` were recorded before a restart (issue 19):
    /// the coverage, the sites done and the peak force follow from the
    /// events as they did when each was kept; the calls stand as recorded
    /// (with the truth they were scored against). Nothing is sent to a log:
    /// these records are already there. The case's clock goes on from its
    /// last record ([`Self::last_time`]).
    pub fn resume(
        case: &Case,
        protocol: Protocol,
        events: Vec<CompressionEvent>,
        calls: Vec<Call>,
        doppler_calls: Vec<DopplerCall>,
    ) -> CaseExam {
        let mut x = CaseExam::new(case, protocol);
        for e in &events {
            x.peak_force = x.peak_force.max(e.peak_force);
            x.coverage.apply(e);
            x.coverage.mark_done(&mut x.sites);
            x.last_t = x.last_t.max(e.t_end);
        }
        for t in calls
            .iter()
            .map(|c| c.t)
            .chain(doppler_calls.iter().map(|c| c.t))
        {
            x.last_t = x.last_t.max(t);
        }
        x.events = events;
        x.calls = calls;
        x.doppler_calls = doppler_calls;
        x
    }

    /// Time of the case's latest sample, event or call (s since it started).
    pub fn last_time(&self) -> f64 {
        self.last_t
    }

    /// Feeds one sample of the live state; a press that ends with it is
    /// applied to the coverage and sent to `log`, and returned.
    pub fn observe(
        &mut self,
        sample: &ExamSample,
        log: &mut dyn ExamLog,
    ) -> Result<Option<&CompressionEvent>, CaseExamError> {
        let ended = self.detector.push(sample)?;
        self.last_t = sample.t;
        if self.detector.pressing() {
            self.peak_force = self.peak_force.max(sample.force);
        }
        match ended {
            Some(e) => self.keep_event(e, log).map(Some),
            None => Ok(None),
        }
    }

    fn keep_event(
        &mut self,
        e: CompressionEvent,
        log: &mut dyn ExamLog,
    ) -> Result<&CompressionEvent, CaseExamError> {
        self.peak_force = self.peak_force.max(e.peak_force);
        self.coverage.apply(&e);
        self.coverage.mark_done(&mut self.sites);
        self.events.push(e);
        let kept = self.events.last().expect("just pushed");
        log.event(kept)?;
        Ok(kept)
    }

    /// The trainee calls `finding` at the protocol's site `site` at time `t`
    /// (s since the case started); a later call on a site replaces an
    /// earlier one in the score, both are recorded. The call's truth is
    /// the one it is scored against ([`truth_for_call`]: a site within the
    /// probe's footprint of a thrombus's end accepts either finding).
    pub fn call(
        &mut self,
        site: &str,
        finding: Finding,
        t: f64,
        log: &mut dyn ExamLog,
    ) -> Result<&Call, CaseExamError> {
        let Some(x) = self.sites.iter().find(|x| x.name == site) else {
            return Err(CaseExamError::UnknownSite {
                site: site.to_string(),
                protocol: self.protocol,
                known: self
                    .sites
                    .iter()
                    .map(|x| x.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        let call = Call {
            site: x.name.clone(),
            vein: x.vein.clone(),
            s: x.s,
            finding,
            truth: truth_for_call(&self.truth, &x.vein, x.s, Some(finding)),
            t,
        };
        self.calls.push(call);
        let kept = self.calls.last().expect("just pushed");
        log.call(kept)?;
        Ok(kept)
    }

    /// The trainee reads the spectral Doppler at the Doppler site `site`
    /// (`cfv`, `popliteal`: [`crate::doppler::doppler_sites`]) as `finding`
    /// at time `t` (s); a later call replaces an earlier one in the score,
    /// both are recorded.
    pub fn call_doppler(
        &mut self,
        site: &str,
        finding: DopplerFinding,
        t: f64,
        log: &mut dyn ExamLog,
    ) -> Result<&DopplerCall, CaseExamError> {
        let Some(i) = self.doppler_sites.iter().position(|x| x.name == site) else {
            return Err(CaseExamError::UnknownDopplerSite {
                site: site.to_string(),
                known: self
                    .doppler_sites
                    .iter()
                    .map(|x| x.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        let x = &self.doppler_sites[i];
        let call = DopplerCall {
            site: x.name.clone(),
            vein: x.vein.clone(),
            s: x.s,
            finding,
            truth: self.doppler_truth[i],
            t,
        };
        self.doppler_calls.push(call);
        let kept = self.doppler_calls.last().expect("just pushed");
        log.doppler(kept)?;
        Ok(kept)
    }

    /// Ends the case at `t` (s): a press still under way is closed and
    /// recorded, the case is scored, and the coverage and score are sent to
    /// `log`. The score is kept ([`Self::score`]) before it is sent; when
    /// the log fails on the last press, the case is still scored and the
    /// log still gets the score, and the first error is returned.
    pub fn finish(&mut self, t: f64, log: &mut dyn ExamLog) -> Result<CaseScore, CaseExamError> {
        let t = t.max(self.last_t);
        let mut failed = None;
        if let Some(e) = self.detector.finish(t) {
            failed = self.keep_event(e, log).err();
        }
        let mut score = score_case(&ScoreInput {
            case: &self.case,
            protocol: self.protocol,
            sites: &self.sites,
            truth: &self.truth,
            events: &self.events,
            calls: &self.calls,
            coverage: &self.coverage,
        });
        score.doppler = score_doppler(
            &self.doppler_sites,
            &self.doppler_truth,
            &self.doppler_calls,
        );
        self.score = Some(score.clone());
        let sent = log.finish(self.coverage.bins(), &score);
        match failed {
            Some(e) => Err(e),
            None => sent.map(|()| score).map_err(CaseExamError::from),
        }
    }

    /// The case's score, once [`Self::finish`] has computed it (kept even
    /// when the log failed to take it).
    pub fn score(&self) -> Option<&CaseScore> {
        self.score.as_ref()
    }

    /// The case's name.
    pub fn case(&self) -> &str {
        &self.case
    }

    /// The protocol.
    pub fn protocol(&self) -> Protocol {
        self.protocol
    }

    /// The checklist, each site marked done once its bin is covered.
    pub fn sites(&self) -> &[ProtocolSite] {
        &self.sites
    }

    /// The coverage strip so far.
    pub fn coverage(&self) -> &Coverage {
        &self.coverage
    }

    /// The presses so far.
    pub fn events(&self) -> &[CompressionEvent] {
        &self.events
    }

    /// The calls so far.
    pub fn calls(&self) -> &[Call] {
        &self.calls
    }

    /// The latest call at `site`, if any.
    pub fn call_at(&self, site: &str) -> Option<Finding> {
        self.calls
            .iter()
            .rev()
            .find(|c| c.site == site)
            .map(|c| c.finding)
    }

    /// What the presses at the protocol's site `site` showed, strongest
    /// first (the coverage's precedence): walls met → normal; not met with
    /// adequate pressure (artery deformed) → acute DVT (review §1
    /// "Positive criterion"); pressed without adequate pressure →
    /// indeterminate. A press counts for the site when it was over the
    /// site's vein within half the site spacing (1 cm). `None` when no
    /// press examined it, or no such site.
    pub fn seen_at(&self, site: &str) -> Option<Finding> {
        let x = self.sites.iter().find(|x| x.name == site)?;
        let half = 0.5 * crate::protocol::WHOLE_LEG_SPACING + 1e-12;
        self.events
            .iter()
            .filter(|e| e.vein.as_deref() == Some(x.vein.as_str()) && (e.s - x.s).abs() <= half)
            .map(event_state)
            .max_by_key(|s| match s {
                BinState::NotExamined => 0,
                BinState::InadequatePressure => 1,
                BinState::NotClosed => 2,
                BinState::Closed => 3,
            })
            .map(|s| match s {
                BinState::Closed => Finding::Normal,
                BinState::NotClosed => Finding::AcuteDvt,
                _ => Finding::Indeterminate,
            })
    }

    /// The Doppler sites (`cfv`, `popliteal`).
    pub fn doppler_sites(&self) -> &[ProtocolSite] {
        &self.doppler_sites
    }

    /// The Doppler calls so far.
    pub fn doppler_calls(&self) -> &[DopplerCall] {
        &self.doppler_calls
    }

    /// The latest Doppler call at `site`, if any.
    pub fn doppler_at(&self, site: &str) -> Option<DopplerFinding> {
        self.doppler_calls
            .iter()
            .rev()
            .find(|c| c.site == site)
            .map(|c| c.finding)
    }

    /// Whether a press is under way.
    pub fn pressing(&self) -> bool {
        self.detector.pressing()
    }

    /// Peak probe force over the case so far (N), counting presses only.
    pub fn peak_force(&self) -> f64 {
        self.peak_force
    }

    /// The case's ground truth (revealed only once the case is finished).
    pub fn truth(&self) -> &[VeinTruth] {
        &self.truth
    }
}

#[cfg(test)]
#[path = "case_exam_tests.rs"]
mod tests;
