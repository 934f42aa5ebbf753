//! What an exam session examines: its trainee, protocol and cases.

use echothigh_cases::Case;
use echothigh_exam::Protocol;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// An exam session's plan.
pub struct ExamPlan {
    /// The trainee's name (`None`: an anonymous practice session).
    pub trainee: Option<String>,
    /// The protocol asked for.
    pub protocol: Protocol,
    /// The cases, in the order they are examined.
    pub cases: Vec<Case>,
}

impl ExamPlan {
    /// The practice plan of `echothigh view`: anonymous, three-point, every
    /// case of the built-in library in an order drawn from `seed`.
    pub fn practice(seed: u64) -> anyhow::Result<ExamPlan> {
        let mut cases = echothigh_cases::names()
            .map(echothigh_cases::builtin)
            .collect::<Result<Vec<_>, _>>()?;
        cases.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
        Ok(ExamPlan {
            trainee: None,
            protocol: Protocol::ThreePoint,
            cases,
        })
    }
}
