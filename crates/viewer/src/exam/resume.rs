//! A trainee's exam session resumed after a restart of the server (issue
//! 19: "a restart of the server keeps the exam session (it lives in the
//! database of the exam issue)").
//!
//! The server stopping (or dying) does not end the session: its records
//! stay in the database with the case under way unfinished
//! ([`ExamSession::suspend`]). The next `echothigh exam` for the same
//! trainee and protocol reads them back (`echothigh_records::Store::open_session`)
//! and goes on: the cases already examined keep their scores and count in
//! the session's totals, the case that was under way reopens with its
//! presses, coverage and calls, and its later records join the same
//! attempt. The plan is reordered to the order the session took: the cases
//! attempted, then the rest.

use super::plan::ExamPlan;
use super::session::ExamSession;
use super::sink::{CaseLog, RecordSink};
use echothigh_exam::{Call, CaseExam, CaseScore, CompressionEvent, DopplerCall};

/// The case that was under way, with the log that writes on into it.
pub struct OpenAttempt {
    /// The case's name.
    pub case: String,
    /// Its presses so far.
    pub events: Vec<CompressionEvent>,
    /// Its calls so far.
    pub calls: Vec<Call>,
    /// Its Doppler calls so far.
    pub doppler_calls: Vec<DopplerCall>,
    /// The log of the same attempt.
    pub log: CaseLog,
}

/// What the session had done before the restart.
pub struct ResumePoint {
    /// Every case attempted, in order, with its score once finished (an
    /// attempt abandoned before the last one stays unscored, as it was).
    pub attempted: Vec<(String, Option<CaseScore>)>,
    /// The last attempt, when it was under way.
    pub open: Option<OpenAttempt>,
}

impl ResumePoint {
    /// The resume point of `session` (its attempts as recorded), the last
    /// unfinished attempt reopened with `log_of`'s log.
    pub fn of_records(
        session: &echothigh_records::ResumedSession,
        log_of: impl FnOnce(&echothigh_records::ResumedCase) -> CaseLog,
    ) -> ResumePoint {
        let attempted = session
            .cases
            .iter()
            .map(|c| (c.key.name.clone(), c.detail.score.clone()))
            .collect();
        let open = session
            .cases
            .last()
            .filter(|c| c.finished_ms.is_none())
            .map(|c| OpenAttempt {
                case: c.key.name.clone(),
                events: c.detail.events.clone(),
                calls: c.detail.calls.clone(),
                doppler_calls: c.detail.doppler_calls.clone(),
                log: log_of(c),
            });
        ResumePoint { attempted, open }
    }
}

impl ExamSession {
    /// Goes on with a session of `plan` that stopped at `point`, recording
    /// to `sink` (whose session is the resumed one). Errors, naming it,
    /// when a case the session examined is not among `plan`'s cases (the
    /// server was restarted with other `--cases` or another `--generate`
    /// seed).
    pub fn resume(
        mut plan: ExamPlan,
        sink: Box<dyn RecordSink>,
        point: ResumePoint,
    ) -> Result<ExamSession, String> {
        // The plan in the order the session took: the attempted cases,
        // then the others in their order.
        let mut rest: Vec<_> = std::mem::take(&mut plan.cases)
            .into_iter()
            .map(Some)
            .collect();
        for (name, _) in &point.attempted {
            let i = rest
                .iter()
                .position(|c| c.as_ref().is_some_and(|c| &c.file.name == name))
                .ok_or_else(|| {
                    format!(
                        "case `{name}` of the unfinished session is not among this exam's cases"
                    )
                })?;
            plan.cases.extend(rest[i].take());
        }
        plan.cases.extend(rest.into_iter().flatten());
        let protocol = plan.protocol;
        let attempts = point.attempted.len();
        if let Some(o) = &point.open {
            if point.attempted.last().map(|(n, _)| n) != Some(&o.case) {
                return Err(format!(
                    "the case under way, `{}`, is not the session's last attempt",
                    o.case
                ));
            }
        }
        let mut x = ExamSession::new(plan, sink, false);
        x.next = attempts;
        x.status.case_number = attempts as u32;
        for s in point.attempted.iter().filter_map(|(_, s)| s.as_ref()) {
            x.status.cases_done += 1;
            x.status.calls_correct += s.calls_correct;
            x.status.calls_total += s.calls_total;
        }
        if let Some(o) = point.open {
            let index = attempts - 1;
            let case = &x.plan.cases[index];
            let exam = CaseExam::resume(case, protocol, o.events, o.calls, o.doppler_calls);
            x.reopen(index, exam, o.log);
        }
        x.refresh();
        Ok(x)
    }
}
