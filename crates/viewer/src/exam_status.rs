//! The exam session as the page may see it (issue 14): never a case's truth
//! before the trainee finishes the case.

use echothigh_cases::Vignette;
use echothigh_exam::{CaseScore, CoverageBin, DopplerFinding, Finding};
use serde::{Deserialize, Serialize};

/// The exam session's state for the page. Sent with a state push only when
/// [`ExamStatus::rev`] changed since the connection's last one.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ExamStatus {
    /// Revision: grows by one at every change.
    pub rev: u64,
    /// Exam mode is on.
    pub active: bool,
    /// The trainee (`None`: anonymous practice).
    pub trainee: Option<String>,
    /// The protocol's name (`two-point`, `three-point`, `whole-leg`).
    pub protocol: String,
    /// Where the records go, in plain words.
    pub recording: String,
    /// Number of the open (or last) case in the session, from 1.
    pub case_number: u32,
    /// Cases in the session's plan.
    pub cases_total: u32,
    /// A case is being examined: its truth is hidden.
    pub open: bool,
    /// The open case's vignette (age, symptoms, Wells score).
    pub vignette: Option<Vignette>,
    /// The protocol's checklist on the open case's leg.
    pub sites: Vec<SiteStatus>,
    /// The Doppler sites of the open case (`cfv`, `popliteal`) and the
    /// trainee's latest Doppler call at each.
    #[serde(default)]
    pub doppler: Vec<DopplerSiteStatus>,
    /// The open case's coverage strip (deep veins, 2 cm bins, groin to knee).
    pub coverage: Vec<CoverageBin>,
    /// Compressions detected in the open case.
    pub presses: u32,
    /// Peak probe force of the open case's presses (N).
    pub peak_force: f64,
    /// Cases finished in this session.
    pub cases_done: u32,
    /// Calls right over the finished cases.
    pub calls_correct: u32,
    /// Calls asked for over the finished cases.
    pub calls_total: u32,
    /// The last finished case, its truth revealed.
    pub last: Option<CaseFeedback>,
    /// The last recording or sample error, in plain words.
    pub error: Option<String>,
}

/// One checklist item.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteStatus {
    /// The site's name (`cfv`, `fv-mid`, `popliteal`, `fv@190mm`).
    pub name: String,
    /// The vein examined there.
    pub vein: String,
    /// Where (m below the inguinal ligament).
    pub s: f64,
    /// A press there was adequate (its bin is covered).
    pub done: bool,
    /// The trainee's latest call there.
    pub call: Option<Finding>,
    /// The probe angle that centres the site's vein in the image (rad, the
    /// page's `theta` of a probe command: `−θ_leg` of
    /// `echothigh_anatomy::Anatomy::pose_over`); `None` where the vein
    /// cannot be centred.
    #[serde(default)]
    pub theta: Option<f64>,
}

/// One Doppler site of the open case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DopplerSiteStatus {
    /// The site's name (`cfv`, `popliteal`).
    pub name: String,
    /// The vein there.
    pub vein: String,
    /// The trainee's latest Doppler call there.
    pub call: Option<DopplerFinding>,
}

/// A finished case, as the feedback shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseFeedback {
    /// The case's name.
    pub case: String,
    /// Its title.
    pub title: String,
    /// Its diagnosis (`normal`, `acute_dvt`, …).
    pub diagnosis: String,
    /// What it teaches.
    pub teaching: Option<String>,
    /// The score.
    pub score: CaseScore,
    /// The truth along the veins, to draw over the coverage strip.
    pub truth: Vec<TruthSegment>,
    /// The coverage strip at the end.
    pub coverage: Vec<CoverageBin>,
}

/// A piece of a vein's ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthSegment {
    /// The vein.
    pub vein: String,
    /// Proximal end (m below the inguinal ligament).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// `normal` or the thrombus kind.
    pub kind: String,
}
