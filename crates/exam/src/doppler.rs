//! Doppler calls (issue 14, fidelity review §1 "Doppler" and §2 row 29):
//! the trainee's reading of the spectral Doppler of a vein — flow phasic
//! with breathing, continuous (non-phasic), or absent — and whether it
//! augments on a calf squeeze; its truth from the case through
//! `echothigh-doppler`'s flow model; and its score, kept apart from the
//! compression calls.
//!
//! **Sites.** The SRU consensus (Needleman et al., *Circulation* 2018;
//! review §1 "Protocols") asks for spectral Doppler of the common femoral
//! vein and of the popliteal vein. Every protocol here asks for both, at
//! the two-point protocol's CFV site (the SFJ's level) and popliteal site
//! ([`doppler_sites`]): the complete exam (whole-leg) by the consensus, and
//! the limited ones because they visit these two sites anyway and the CFV
//! waveform is the only sign of an iliac obstruction above the imaged leg
//! (review §1 "Doppler": a continuous CFV signal means proximal
//! obstruction). The model has one leg: "both CFVs" is the one CFV.
//!
//! **Truth** ([`doppler_truth`], from `SegmentFlow::of` with the default
//! `FlowConfig` and the case's `[doppler] proximal_obstruction`): an
//! occluded segment has no flow (absent, no augmentation); a proximal
//! obstruction (the iliac flag, or an occluded stretch of the deep line
//! above) makes it continuous; otherwise phasic. It augments when no
//! occlusion lies below it on the deep line. A non-occlusive thrombus
//! leaves the flow present (phasic or continuous by what lies above).

use crate::protocol::ProtocolSite;
use crate::Protocol;
use echothigh_anatomy::Anatomy;
use echothigh_cases::Case;
use echothigh_doppler::{FlowConfig, SegmentFlow};
use serde::{Deserialize, Serialize};

/// The spectral pattern of a vein's flow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlowPattern {
    /// Spontaneous and phasic with breathing: the normal signal.
    Phasic,
    /// Continuous (monophasic, non-phasic): proximal obstruction.
    Continuous,
    /// No flow: an occluded segment.
    Absent,
}

impl FlowPattern {
    /// Every pattern, in the order the page lists them.
    pub const ALL: [FlowPattern; 3] = [
        FlowPattern::Phasic,
        FlowPattern::Continuous,
        FlowPattern::Absent,
    ];

    /// The name used in scripts, JSON and the database.
    pub fn name(self) -> &'static str {
        match self {
            FlowPattern::Phasic => "phasic",
            FlowPattern::Continuous => "continuous",
            FlowPattern::Absent => "absent",
        }
    }

    /// The pattern named `name` ([`FlowPattern::name`]).
    pub fn from_name(name: &str) -> Option<FlowPattern> {
        FlowPattern::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// A reading of one vein's spectral Doppler: the pattern and whether a
/// calf squeeze augments it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct DopplerFinding {
    /// Phasic, continuous or absent.
    pub flow: FlowPattern,
    /// The flow rises on a calf squeeze.
    pub augments: bool,
}

/// A trainee's Doppler call at a site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DopplerCall {
    /// The Doppler site's name (`cfv`, `popliteal`).
    pub site: String,
    /// The vein there (`cfv`, `pv`).
    pub vein: String,
    /// Where (m below the inguinal ligament).
    pub s: f64,
    /// What the trainee called.
    pub finding: DopplerFinding,
    /// The truth there ([`doppler_truth`]).
    pub truth: DopplerFinding,
    /// When it was called (s since the case started).
    pub t: f64,
}

impl DopplerCall {
    /// Right when both the pattern and the augmentation match the truth.
    pub fn is_correct(&self) -> bool {
        self.finding == self.truth
    }
}

/// The Doppler score of one site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DopplerSiteScore {
    /// The Doppler site's name.
    pub site: String,
    /// The latest call there (`None`: no call).
    pub call: Option<DopplerFinding>,
    /// The truth there.
    pub truth: DopplerFinding,
}

/// A case's Doppler score, counted apart from the compression calls (so
/// `CaseScore::calls_correct` keeps its meaning).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DopplerScore {
    /// Sites whose latest call matches the truth in pattern and augmentation.
    pub correct: u32,
    /// Doppler sites asked for (a missing call counts as wrong).
    pub total: u32,
    /// Per site.
    pub sites: Vec<DopplerSiteScore>,
}

/// The Doppler sites on `anatomy`, the same for every protocol (module
/// docs): the CFV at the SFJ's level and the popliteal vein, named `cfv`
/// and `popliteal` as in the two-point checklist.
pub fn doppler_sites(anatomy: &Anatomy) -> Vec<ProtocolSite> {
    Protocol::TwoPoint.sites(anatomy)
}

/// The truth of the Doppler at `s` (m) on the deep vein there, in `case`
/// (module docs).
pub fn doppler_truth(case: &Case, s: f64) -> DopplerFinding {
    let id = case.anatomy.deep_vein_at(s);
    let f = SegmentFlow::of(
        &FlowConfig::default(),
        &case.anatomy,
        &case.thrombi,
        id,
        s,
        case.file.doppler.proximal_obstruction,
    );
    let flow = if f.occluded {
        FlowPattern::Absent
    } else if f.phasic {
        FlowPattern::Phasic
    } else {
        FlowPattern::Continuous
    };
    DopplerFinding {
        flow,
        augments: f.augmentable,
    }
}

/// Scores the Doppler calls `calls` (in order; a later call on a site
/// replaces an earlier one) over `sites`, whose truths are `truths`.
pub fn score_doppler(
    sites: &[ProtocolSite],
    truths: &[DopplerFinding],
    calls: &[DopplerCall],
) -> DopplerScore {
    let sites: Vec<DopplerSiteScore> = sites
        .iter()
        .zip(truths)
        .map(|(x, &truth)| DopplerSiteScore {
            site: x.name.clone(),
            call: calls
                .iter()
                .rev()
                .find(|c| c.site == x.name)
                .map(|c| c.finding),
            truth,
        })
        .collect();
    DopplerScore {
        correct: sites.iter().filter(|x| x.call == Some(x.truth)).count() as u32,
        total: sites.len() as u32,
        sites,
    }
}

#[cfg(test)]
#[path = "doppler_tests.rs"]
mod tests;
