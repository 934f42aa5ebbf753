//! Exam mode (issue 14): the trainee examines cases of the library one
//! after the other under a protocol; the server keeps each case's truth,
//! detects the compressions from the live state, keeps the coverage strip
//! and the calls, scores the case when the trainee finishes it, reveals the
//! truth then, and records everything as it happens ([`sink`]).

mod observer;
mod plan;
mod resume;
mod session;
pub mod sink;

pub use observer::{sample, ExamObserver};
pub use plan::ExamPlan;
pub use resume::{OpenAttempt, ResumePoint};
pub use session::ExamSession;
