//! A case file (TOML, SI units): the patient (a preset and its overrides,
//! `[patient]`), the thrombus segments (`[[thrombus]]`, see
//! `echothigh_anatomy::thrombus`), a clinical vignette (`[vignette]`) and the
//! written diagnosis (`[truth]`), which must agree with the segments.
//!
//! ```toml
//! name = "isolated-fv-mid-acute"
//! title = "Isolated femoral vein thrombus at mid-thigh"
//! [patient]
//! preset = "lean-male"
//! [vignette]
//! age = 58
//! symptoms = "Left calf and thigh swelling for 4 days after a long flight"
//! wells = 2
//! [[thrombus]]
//! vein = "fv"
//! s_start = 0.17
//! s_end = 0.23
//! kind = "acute_occlusive"
//! [truth]
//! diagnosis = "acute_dvt"
//! ```

use crate::doppler_spec::DopplerSpec;
use crate::error::CaseError;
use echothigh_anatomy::{Anatomy, Kind, Patient, Thrombi, ThrombusKind, ThrombusSpec, VeinTruth};
use serde::{Deserialize, Serialize};

/// The clinical vignette shown to the trainee.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vignette {
    /// Age (years), 18 to 100.
    pub age: u32,
    /// Presenting symptoms (free text, not empty).
    pub symptoms: String,
    /// Wells score for DVT (Wells et al., Lancet 1997; range −2 to 9).
    pub wells: i32,
}

/// The written diagnosis of a case (checked against its segments).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Diagnosis {
    /// No thrombus.
    Normal,
    /// Acute thrombus in a deep vein (cfv, fv, pv, dfv, fv2).
    AcuteDvt,
    /// Acute thrombus in the GSV only (superficial thrombophlebitis: not a DVT).
    SuperficialThrombophlebitis,
    /// Chronic post-thrombotic change only (no acute thrombus).
    ChronicPostThrombotic,
}

impl Diagnosis {
    /// The name written in case files.
    pub fn name(self) -> &'static str {
        match self {
            Diagnosis::Normal => "normal",
            Diagnosis::AcuteDvt => "acute_dvt",
            Diagnosis::SuperficialThrombophlebitis => "superficial_thrombophlebitis",
            Diagnosis::ChronicPostThrombotic => "chronic_post_thrombotic",
        }
    }

    /// Whether this is a positive study for acute DVT.
    pub fn is_dvt(self) -> bool {
        self == Diagnosis::AcuteDvt
    }
}

/// `[truth]` of a case file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruthSpec {
    /// The diagnosis, which the segments must imply.
    pub diagnosis: Diagnosis,
    /// What the case teaches (free text), optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teaching: Option<String>,
}

/// A case file as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// Short name (lowercase letters, digits and `-`), unique in the library.
    pub name: String,
    /// One-line title.
    pub title: String,
    /// The patient: `preset = "…"` and any overrides (echothigh-anatomy's `Patient` keys).
    pub patient: toml::Table,
    /// The vignette.
    pub vignette: Vignette,
    /// The thrombus segments (none for a normal leg).
    #[serde(default)]
    pub thrombus: Vec<ThrombusSpec>,
    /// The written ground truth.
    pub truth: TruthSpec,
    /// Doppler flow settings (issue 17), optional.
    #[serde(default, skip_serializing_if = "DopplerSpec::is_default")]
    pub doppler: DopplerSpec,
}

/// A loaded, validated case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The file it came from.
    pub file: CaseFile,
    /// The patient's anatomy.
    pub anatomy: Anatomy,
    /// The validated segments.
    pub thrombi: Thrombi,
}

impl CaseFile {
    /// Parses a case file; TOML errors carry the parser's message, which
    /// names the key and line.
    pub fn from_toml_str(text: &str) -> Result<CaseFile, CaseError> {
        toml::from_str(text).map_err(|e: toml::de::Error| CaseError::Parse(e.to_string()))
    }

    /// The file as TOML text.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("a case file always serializes")
    }

    /// Validates the file and builds its anatomy and segments.
    pub fn load(self) -> Result<Case, CaseError> {
        let key = |k: &str, reason: String| CaseError::Key {
            key: k.into(),
            reason,
        };
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
        {
            return Err(key(
                "name",
                format!("= \"{}\": use lowercase letters, digits and '-'", self.name),
            ));
        }
        if self.title.trim().is_empty() {
            return Err(key("title", "must not be empty".into()));
        }
        let v = &self.vignette;
        if !(18..=100).contains(&v.age) {
            return Err(key(
                "vignette.age",
                format!("= {}: must be between 18 and 100 years", v.age),
            ));
        }
        if !(-2..=9).contains(&v.wells) {
            return Err(key(
                "vignette.wells",
                format!("= {}: the Wells DVT score lies between -2 and 9", v.wells),
            ));
        }
        if v.symptoms.trim().is_empty() {
            return Err(key("vignette.symptoms", "must not be empty".into()));
        }
        let text = toml::to_string(&self.patient).map_err(|e| CaseError::Parse(e.to_string()))?;
        let patient = Patient::from_toml_str(&text).map_err(CaseError::Patient)?;
        let anatomy = Anatomy::new(patient).map_err(CaseError::Patient)?;
        let thrombi = Thrombi::new(&anatomy, &self.thrombus).map_err(CaseError::Thrombus)?;
        let implied = implied_diagnosis(&anatomy, &thrombi);
        if implied != self.truth.diagnosis {
            return Err(key(
                "truth.diagnosis",
                format!(
                    "= \"{}\" but the thrombus segments make it \"{}\"",
                    self.truth.diagnosis.name(),
                    implied.name()
                ),
            ));
        }
        Ok(Case {
            file: self,
            anatomy,
            thrombi,
        })
    }
}

/// The diagnosis the segments imply: any acute segment on a deep vein is an
/// acute DVT; else an acute GSV segment is superficial thrombophlebitis;
/// else any chronic segment is chronic post-thrombotic change; else normal.
pub fn implied_diagnosis(anatomy: &Anatomy, thrombi: &Thrombi) -> Diagnosis {
    let deep = |t: &echothigh_anatomy::Thrombus| {
        anatomy
            .tube(t.vein)
            .is_some_and(|tube| tube.kind() == Kind::DeepVein)
    };
    let segs = thrombi.segments();
    if segs.iter().any(|t| t.kind.is_acute() && deep(t)) {
        Diagnosis::AcuteDvt
    } else if segs.iter().any(|t| t.kind.is_acute()) {
        Diagnosis::SuperficialThrombophlebitis
    } else if segs.iter().any(|t| t.kind == ThrombusKind::Chronic) {
        Diagnosis::ChronicPostThrombotic
    } else {
        Diagnosis::Normal
    }
}

impl Case {
    /// The case's name.
    pub fn name(&self) -> &str {
        &self.file.name
    }

    /// The ground truth per vein (every vein of the leg, each covered once).
    pub fn ground_truth(&self) -> Vec<VeinTruth> {
        self.thrombi.ground_truth(&self.anatomy)
    }
}
