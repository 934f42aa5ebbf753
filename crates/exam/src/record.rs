//! What an exam leaves behind, as it is stored and reported: compression
//! events, coverage bins, calls, and a case's score. Lengths in metres,
//! forces in newtons, times in seconds since the case started.

use crate::{DopplerScore, Finding};
use serde::{Deserialize, Serialize};

/// One press of the probe, detected from the live state (issue 14
/// "Compression events"): from the force rising above the contact
/// threshold to its fall below it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompressionEvent {
    /// Start of the press (s since the case started).
    pub t_start: f64,
    /// End of the press (s).
    pub t_end: f64,
    /// The vein under the probe at the peak force (`cfv`, `fv`, `pv`, …),
    /// or `None` when no deep or superficial vein was in the image.
    pub vein: Option<String>,
    /// Distance below the inguinal ligament of the section at the peak
    /// force (m).
    pub s: f64,
    /// Peak probe force during the press (N).
    pub peak_force: f64,
    /// Minimum lumen area of that vein over its rest area reached during
    /// the press (1 = open at rest, 0 = walls met).
    pub min_lumen_ratio: f64,
    /// The companion artery began to deform (its lumen fell below 0.9 of
    /// rest): the pressure was adequate (fidelity review §1, "Positive
    /// criterion").
    pub artery_deformed: bool,
    /// The walls met (lumen ratio under 0.1 of rest, the coaptation
    /// criterion of the disease issue's tests).
    pub coapted: bool,
    /// Distance the probe slid along the skin while pressed (m); a press
    /// with more than 1 cm of sliding is recorded as a slide, not a
    /// compress–release–step.
    pub slide: f64,
    /// The probe force over the press, `[t (s), force (N)]`, resampled to
    /// at most 50 Hz (the report's force trace per compression).
    pub force_trace: Vec<[f64; 2]>,
}

/// The state of a 2 cm bin of a vein (issue 14 "Coverage").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BinState {
    /// No press there yet.
    NotExamined,
    /// Pressed, but neither coapted nor with adequate pressure.
    InadequatePressure,
    /// Pressed with adequate pressure (artery deformed) and the walls did
    /// not meet: the positive criterion.
    NotClosed,
    /// Pressed and the walls met.
    Closed,
}

impl BinState {
    /// The name used in JSON and the database.
    pub fn name(self) -> &'static str {
        match self {
            BinState::NotExamined => "not_examined",
            BinState::InadequatePressure => "inadequate_pressure",
            BinState::NotClosed => "not_closed",
            BinState::Closed => "closed",
        }
    }
}

/// One bin of a vein's coverage strip.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageBin {
    /// The vein (`cfv`, `fv`, …).
    pub vein: String,
    /// Proximal end of the bin (m below the inguinal ligament).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// What the presses there showed.
    pub state: BinState,
}

/// A trainee's call on a site (or on a segment the trainee marks).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Call {
    /// The site's name (a protocol site such as `cfv`, `fv-mid`,
    /// `popliteal`, or `vein@s_mm` for a marked segment).
    pub site: String,
    /// The vein the site is on.
    pub vein: String,
    /// Where on the vein (m below the inguinal ligament).
    pub s: f64,
    /// What the trainee called.
    pub finding: Finding,
    /// The truth there (from the case's ground truth).
    pub truth: Finding,
    /// When it was called (s since the case started).
    pub t: f64,
}

impl Call {
    /// Whether the call matches the truth.
    pub fn is_correct(&self) -> bool {
        self.finding == self.truth
    }
}

/// The score of one site of a case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteScore {
    /// The site's name.
    pub site: String,
    /// The call made there (`None`: no call).
    pub call: Option<Finding>,
    /// The truth there.
    pub truth: Finding,
    /// A press there reached adequate pressure (or coapted).
    pub pressure_adequate: bool,
    /// "Not compressible" (acute DVT) called without adequate pressure:
    /// marked as such (issue 14 "Scoring").
    pub called_without_adequate_pressure: bool,
}

/// The score of one case (issue 14 "Scoring and feedback").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseScore {
    /// The case's name.
    pub case: String,
    /// The protocol's name (`two-point`, `three-point`, `whole-leg`).
    pub protocol: String,
    /// Fraction of the protocol's bins examined with adequate pressure or
    /// closed, in [0, 1].
    pub coverage: f64,
    /// Calls matching the truth.
    pub calls_correct: u32,
    /// Calls the protocol asks for (a missing call counts as wrong).
    pub calls_total: u32,
    /// Fraction of presses with adequate pressure (coapted or artery
    /// deformed), in [0, 1]; 0 when there was no press.
    pub pressure_adequate: f64,
    /// Presses over a free-floating tail with more than the safe force.
    pub excessive_force_on_tail: u32,
    /// Time from the case's start to its last call (s).
    pub duration: f64,
    /// Peak probe force over the case (N).
    pub peak_force: f64,
    /// Mean probe force over the presses (N), 0 without presses.
    pub mean_force: f64,
    /// Per site.
    pub sites: Vec<SiteScore>,
    /// The diseased segments the exam never examined with adequate
    /// pressure nor called: where it missed the disease (e.g. the isolated
    /// femoral-vein thrombus a two-point exam skips). Added by issue 14's
    /// scorer; absent in older records (empty).
    #[serde(default)]
    pub missed: Vec<MissedSegment>,
    /// The Doppler calls' score (CFV and popliteal, `crate::doppler`),
    /// counted apart from the compression calls above. Absent in older
    /// records (empty).
    #[serde(default)]
    pub doppler: DopplerScore,
}

/// A thrombosed stretch of a deep vein the exam missed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissedSegment {
    /// The vein (`cfv`, `fv`, `pv`).
    pub vein: String,
    /// Proximal end (m below the inguinal ligament).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// The truth there.
    pub truth: Finding,
}
