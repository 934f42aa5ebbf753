//! Exam mode for training: the server draws the vein state at random and
//! keeps it hidden; the trainee scans, presses and answers "compressible" or
//! "not compressible" (paper §1: a healthy vein compresses under the probe, a
//! thrombosed one partially or not at all). The truth lives only here, on the
//! server, and is revealed to the page once the question is answered.

use super::protocol::{ExamResult, ExamStatus};
use echothigh_runtime::live::VeinState;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Why an exam command was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ExamError {
    /// An answer arrived with no open question.
    #[error("no exam question is open: start one first")]
    NoQuestion,
}

/// One trainee's exam session (shared by the connections of one server).
#[derive(Debug)]
pub struct ExamSession {
    rng: ChaCha8Rng,
    /// The hidden vein state of the open question.
    hidden: Option<VeinState>,
    /// The trainee has placed the probe since the question opened: only
    /// then does the contact force count (issue 19: the force of the
    /// question's own reset is not the trainee's press).
    armed: bool,
    status: ExamStatus,
}

/// Whether `vein` collapses under the probe: only a healthy vein does.
pub fn is_compressible(vein: VeinState) -> bool {
    vein == VeinState::Healthy
}

impl ExamSession {
    /// A session whose draws come from `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            hidden: None,
            armed: false,
            status: ExamStatus::default(),
        }
    }

    /// A session seeded from the operating system's entropy.
    pub fn from_entropy() -> Self {
        Self::new(rand::thread_rng().gen())
    }

    /// Opens a question: draws a vein state uniformly among the three and
    /// returns it, for the caller to hand to the runtime. An open question
    /// is dropped unscored.
    pub fn start(&mut self) -> VeinState {
        let vein = match self.rng.gen_range(0..3) {
            0 => VeinState::Healthy,
            1 => VeinState::Acute,
            _ => VeinState::Chronic,
        };
        self.hidden = Some(vein);
        self.armed = false;
        self.status.open = true;
        self.status.question += 1;
        self.status.peak_force = 0.0;
        vein
    }

    /// The trainee placed or moved the probe: from now on the open
    /// question's contact forces are the trainee's own.
    pub fn trainee_pressed(&mut self) {
        self.armed = self.status.open;
    }

    /// Records the contact force magnitude on the thigh (N) while a question
    /// is open and the trainee has placed the probe since it opened
    /// ([`Self::trainee_pressed`]); the question's peak force is the largest seen.
    pub fn observe_force(&mut self, magnitude: f64) {
        if self.status.open && self.armed && magnitude.is_finite() {
            self.status.peak_force = self.status.peak_force.max(magnitude);
        }
    }

    /// Scores the answer to the open question and closes it.
    pub fn answer(&mut self, compressible: bool) -> Result<ExamResult, ExamError> {
        let truth = self.hidden.take().ok_or(ExamError::NoQuestion)?;
        let correct = compressible == is_compressible(truth);
        let result = ExamResult {
            question: self.status.question,
            answered_compressible: compressible,
            truth,
            correct,
            peak_force: self.status.peak_force,
        };
        self.status.open = false;
        self.status.answered += 1;
        self.status.correct += u32::from(correct);
        self.status.last = Some(result);
        Ok(result)
    }

    /// Leaves exam mode: an open question is dropped unscored.
    pub fn stop(&mut self) {
        self.hidden = None;
        self.status.open = false;
    }

    /// Whether a question is open (the vein must stay hidden).
    pub fn is_open(&self) -> bool {
        self.status.open
    }

    /// What the page may see.
    pub fn status(&self) -> ExamStatus {
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_cover_all_states_roughly_uniformly() {
        let mut s = ExamSession::new(7);
        let mut counts = [0u32; 3];
        for _ in 0..3000 {
            let v = s.start();
            counts[v as usize] += 1;
        }
        for c in counts {
            assert!((850..1150).contains(&c), "counts {counts:?}");
        }
        assert_eq!(s.status().question, 3000);
    }

    #[test]
    fn scoring_follows_compressibility() {
        let mut s = ExamSession::new(1);
        let mut expected_correct = 0;
        for i in 0..30 {
            let truth = s.start();
            let answer = i % 2 == 0;
            let r = s.answer(answer).unwrap();
            assert_eq!(r.truth, truth);
            assert_eq!(r.correct, answer == (truth == VeinState::Healthy));
            expected_correct += u32::from(r.correct);
        }
        let st = s.status();
        assert_eq!((st.answered, st.correct), (30, expected_correct));
        assert!(!st.open);
    }

    #[test]
    fn answer_without_question_is_refused_and_not_counted() {
        let mut s = ExamSession::new(2);
        assert_eq!(s.answer(true), Err(ExamError::NoQuestion));
        s.start();
        s.answer(false).unwrap();
        assert_eq!(s.answer(false), Err(ExamError::NoQuestion));
        assert_eq!(s.status().answered, 1);
    }

    #[test]
    fn peak_force_is_the_largest_finite_force_of_the_open_question() {
        let mut s = ExamSession::new(3);
        s.observe_force(50.0); // no question open: ignored
        s.start();
        s.trainee_pressed();
        for f in [1.0, 7.5, f64::NAN, 3.0, f64::INFINITY] {
            s.observe_force(f);
        }
        assert_eq!(s.status().peak_force, 7.5);
        let r = s.answer(true).unwrap();
        assert_eq!(r.peak_force, 7.5);
        s.observe_force(99.0); // closed: ignored
        assert_eq!(s.status().last.unwrap().peak_force, 7.5);
        s.start();
        assert_eq!(s.status().peak_force, 0.0);
    }

    /// Issue 19: the force before the trainee's first press of a question
    /// (the spike of a reset that restarts pressed in: 46.5 N was recorded
    /// when aiming at ~12 N) is not the trainee's; the recorded peak is
    /// exactly the trainee's own press.
    #[test]
    fn the_peak_counts_only_the_trainees_own_presses() {
        let mut s = ExamSession::new(5);
        s.trainee_pressed(); // no question open: does not arm the next one
        s.start();
        for f in [46.5, 30.0, 0.0] {
            s.observe_force(f); // the question's own reset, before any press
        }
        assert_eq!(s.status().peak_force, 0.0);
        s.trainee_pressed();
        for f in [0.0, 4.0, 12.1, 11.8] {
            s.observe_force(f);
        }
        assert_eq!(s.answer(true).unwrap().peak_force, 12.1);
        // The next question starts unarmed again.
        s.start();
        s.observe_force(41.6);
        assert_eq!(s.status().peak_force, 0.0);
    }

    #[test]
    fn stop_drops_the_question_unscored() {
        let mut s = ExamSession::new(4);
        s.start();
        s.stop();
        assert!(!s.is_open());
        assert_eq!(s.status().answered, 0);
        assert_eq!(s.answer(true), Err(ExamError::NoQuestion));
    }
}
