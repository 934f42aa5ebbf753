//! The patient description (TOML): the build, the leg's size and layers, the
//! vessel sizes and the anatomical variants of one leg (a right leg, DESIGN.md §7).
//!
//! A patient file names a `preset` (default `lean-male`) and overrides any of
//! its keys; unknown keys are refused (`deny_unknown_fields`), and
//! [`Patient::validate`] names the key of any value out of range. Every key
//! is in SI units (m, dimensionless ratios); each field's doc gives its
//! source. "(estimate)" marks a number for which no published value was
//! retrieved: it is a plausible anatomical value to be replaced by a measured
//! one; "(derived)" marks a number computed from sourced ones.

use crate::error::AnatomyError;
use serde::{Deserialize, Serialize};

const LEAN_MALE: &str = include_str!("../presets/lean-male.toml");
const AVERAGE_FEMALE: &str = include_str!("../presets/average-female.toml");
const OBESE: &str = include_str!("../presets/obese.toml");

/// Names of the built-in presets.
pub const PRESETS: [&str; 3] = ["lean-male", "average-female", "obese"];

/// Sex, which sets the defaults of the presets (informational otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sex {
    /// Male.
    Male,
    /// Female.
    Female,
}

/// One patient's leg. All lengths in metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Patient {
    /// Free-form name of the patient (shown in reports).
    pub name: String,
    /// Sex of the patient.
    pub sex: Sex,
    /// Distance (m) from the inguinal ligament to the knee joint line along
    /// the leg. Lean male 0.40, average female 0.37 (estimate: NHANES measures
    /// "upper leg length", Fryar et al. 2012, Vital Health Stat 11(252),
    /// https://pubmed.ncbi.nlm.nih.gov/25204692/; its value was not
    /// retrieved). Every landmark level (SFJ, bifurcation, adductor hiatus…)
    /// scales with it. Range (0.25, 0.60].
    pub knee_s: f64,
    /// Modelled length (m): from the inguinal ligament to just below the knee
    /// (issue 12: ~0.40–0.45 m). Must exceed `knee_s` by at least 0.02 m.
    pub length: f64,
    /// Leg circumference (m) at the inguinal ligament (s = 0). Lean male 0.56
    /// (estimate, see `circumference_mid`).
    pub circumference_groin: f64,
    /// Circumference (m) at mid-thigh (s = knee_s / 2). Lean male 0.50
    /// (estimate; NHANES "mid-thigh circumference", Fryar et al. 2012 above,
    /// value not retrieved; the previous echothigh default was 0.48).
    pub circumference_mid: f64,
    /// Circumference (m) of the distal thigh (s = 0.82 knee_s). Lean male 0.41 (estimate).
    pub circumference_distal: f64,
    /// Circumference (m) at the knee joint line (s = knee_s). Lean male 0.38 (estimate).
    pub circumference_knee: f64,
    /// Ratio of the antero-posterior to the medio-lateral diameter of the
    /// elliptic cross-section. 0.90 (the previous echothigh default 72/80 mm).
    /// Range [0.6, 1.2].
    pub ap_ratio: f64,
    /// Skin thickness (m). 1.8e-3 (Van Mulder 2017, as cited in
    /// `imaging/src/anatomy_config.rs`; reference row 16). Range [0.5, 5] mm.
    pub skin_thickness: f64,
    /// Subcutaneous fat thickness (m) at the groin. Lean male 6.5e-3 (no
    /// proximal value retrieved: the distal value, uniform), average female
    /// 16.7e-3 (same), obese 40e-3 (issue 12: obese 25–40 mm). Range [0, 0.12].
    pub fat_thickness_proximal: f64,
    /// Subcutaneous fat thickness (m) of the distal thigh, held to the knee.
    /// Men 6.5e-3, women 16.7e-3 (Krauze 2019, reference row 17); obese 25e-3
    /// (issue 12). Both fat keys must exceed `gsv_diameter_thigh` + 1 mm (the
    /// vein lies in the saphenous compartment within the fat). Range [0, 0.12].
    pub fat_thickness_distal: f64,
    /// Scale of every deep structure's depth below the muscular fascia (the
    /// muscle bulk over the vessels). 1.0 = the reference anatomy of
    /// `crate::vessels` (lean male). Range (0.3, 3].
    pub muscle_depth_scale: f64,
    /// Angle (degrees) of the femoral shaft to the leg's axis (the mechanical
    /// axis, hip centre to knee centre): the anatomical axis lies ≈ 6° valgus
    /// to the mechanical axis (Wheeless' Textbook of Orthopaedics, "Anatomic
    /// axis", https://www.wheelessonline.com/bones/tibia-fibula/anatomic-axis/).
    /// The shaft is central at the knee and lateral proximally. Range [0, 15].
    pub femur_obliquity_deg: f64,
    /// Common femoral vein diameter (m). 10.5e-3 (Hertzberg et al., AJR 1997,
    /// reference row 10). Obese 12.6e-3 (derived: 10.5 × 8.5/7.1, the
    /// obese/non-obese FV ratio of J Vasc Surg 2010, reference row 10).
    pub cfv_diameter: f64,
    /// Femoral vein diameter (m) at mid-thigh; the distal FV and the popliteal
    /// vein are 0.97× this. 6.6e-3 (Hertzberg 1997: 6.4–6.8 mm mid and
    /// distal FV); obese 8.5e-3 (J Vasc Surg 2010).
    pub fv_diameter_mid: f64,
    /// Great saphenous vein diameter (m) at the SFJ. 7.5e-3 (Mendoza et al.,
    /// Eur J Vasc Endovasc Surg 2013, controls: 7.5 ± 1.8 mm,
    /// http://47.251.13.51:8081/23219416).
    pub gsv_diameter_sfj: f64,
    /// GSV diameter (m) in the thigh (15 cm below the groin and beyond).
    /// 3.7e-3 (Mendoza 2013, controls: 3.7 ± 0.9 mm).
    pub gsv_diameter_thigh: f64,
    /// Vein : artery diameter ratio at the groin (CFV:CFA). 1.3 (Hertzberg
    /// 1997, reference row 11). Range [0.8, 3].
    pub vein_artery_ratio_groin: f64,
    /// Vein : artery diameter ratio below the profunda (FV:FA, PV:PA, DFV:DFA).
    /// 1.2 (Hertzberg 1997, reference row 11). Range [0.8, 3].
    pub vein_artery_ratio_below: f64,
    /// Scale of the soft tissue's stiffness (1 = the calibrated default
    /// curve). For the physical model; range (0, 20].
    pub stiffness_scale: f64,
    /// A tense (contracted) leg: muscle stiffness × 2 ("active muscle ≈ 2×
    /// inactive", reference row 19). For the physical model.
    pub tense_muscle: bool,
    /// Tissue force (N) the exam on this leg asks of the probe: the force at
    /// which the artery is clearly oval (120 mmHg of tissue pressure at its
    /// centre, reference §4 item 5) at the leg's hardest level from the groin
    /// to the knee, rounded up to a whole newton. The scenario lowers its
    /// force scale, when it must, so that the device renders this force
    /// unsaturated (issue 12: "the force scale and device limits must still
    /// let a trainee close a healthy vein there"). Lean male 36 (35.7 N over
    /// the popliteal vein 310 mm below the groin), average female 35 (34.7 N,
    /// popliteal, 270 mm), obese 50 (49.5 N, popliteal, 310 mm) (derived:
    /// measured on the physical model by
    /// `runtime/tests/suite/coaptation_along_leg.rs`, which checks each preset's
    /// value against its own presses). The force depends on the vessels'
    /// depth (the fat and muscle over them), not on the tissue's stiffness:
    /// the vein and the artery respond to the pressure a force puts at their
    /// depth. Range [5, 80] N (80 N: twice the clinical maximum of ~40 N).
    pub exam_force: f64,
    /// Variant: a duplicated femoral vein `fv2` along the mid-thigh
    /// (19.7% pooled prevalence, reference row 26).
    pub duplicated_fv: bool,
    /// Variant: a deep inguinal lymph node beside the CFV just below the SFJ
    /// (a node read as thrombus, reference row 28).
    pub lymph_node: bool,
}

impl Patient {
    /// A built-in preset (`lean-male`, `average-female`, `obese`).
    pub fn preset(name: &str) -> Result<Patient, AnatomyError> {
        let text = preset_text(name)?;
        Self::from_toml_str(text)
    }

    /// Parses a patient file: an optional `preset = "<name>"` (default
    /// `lean-male`) whose keys the file's other keys override. Unknown keys,
    /// wrong types and out-of-range values are errors naming the key.
    pub fn from_toml_str(text: &str) -> Result<Patient, AnatomyError> {
        let mut user: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| AnatomyError::Parse(e.to_string()))?;
        let preset = match user.remove("preset") {
            None => None,
            Some(toml::Value::String(s)) => Some(s),
            Some(_) => {
                return Err(AnatomyError::Parse(
                    "key `preset` must be a string (a preset name)".into(),
                ))
            }
        };
        let mut table: toml::Table = preset_text(preset.as_deref().unwrap_or("lean-male"))?
            .parse()
            .map_err(|e: toml::de::Error| AnatomyError::Parse(e.to_string()))?;
        for (k, v) in user {
            table.insert(k, v);
        }
        let p: Patient = table
            .try_into()
            .map_err(|e: toml::de::Error| AnatomyError::Parse(e.to_string()))?;
        p.validate()?;
        Ok(p)
    }

    /// Checks every value against its documented range; the error names the key.
    pub fn validate(&self) -> Result<(), AnatomyError> {
        let mm = 1e-3;
        let checks: [(&'static str, f64, f64, f64, &'static str); 21] = [
            (
                "knee_s",
                self.knee_s,
                0.25,
                0.60,
                "must lie in [0.25, 0.60] m",
            ),
            (
                "length",
                self.length,
                0.27,
                0.70,
                "must lie in [0.27, 0.70] m",
            ),
            (
                "circumference_groin",
                self.circumference_groin,
                0.2,
                1.5,
                "must lie in [0.2, 1.5] m",
            ),
            (
                "circumference_mid",
                self.circumference_mid,
                0.2,
                1.5,
                "must lie in [0.2, 1.5] m",
            ),
            (
                "circumference_distal",
                self.circumference_distal,
                0.15,
                1.5,
                "must lie in [0.15, 1.5] m",
            ),
            (
                "circumference_knee",
                self.circumference_knee,
                0.15,
                1.5,
                "must lie in [0.15, 1.5] m",
            ),
            (
                "ap_ratio",
                self.ap_ratio,
                0.6,
                1.2,
                "must lie in [0.6, 1.2]",
            ),
            (
                "skin_thickness",
                self.skin_thickness,
                0.5 * mm,
                5.0 * mm,
                "must lie in [0.5, 5] mm (a thickness cannot be negative)",
            ),
            (
                "fat_thickness_proximal",
                self.fat_thickness_proximal,
                0.0,
                0.12,
                "must lie in [0, 0.12] m (a thickness cannot be negative)",
            ),
            (
                "fat_thickness_distal",
                self.fat_thickness_distal,
                0.0,
                0.12,
                "must lie in [0, 0.12] m (a thickness cannot be negative)",
            ),
            (
                "muscle_depth_scale",
                self.muscle_depth_scale,
                0.3,
                3.0,
                "must lie in [0.3, 3]",
            ),
            (
                "femur_obliquity_deg",
                self.femur_obliquity_deg,
                0.0,
                15.0,
                "must lie in [0, 15] degrees",
            ),
            (
                "cfv_diameter",
                self.cfv_diameter,
                4.0 * mm,
                25.0 * mm,
                "must lie in [4, 25] mm",
            ),
            (
                "fv_diameter_mid",
                self.fv_diameter_mid,
                3.0 * mm,
                20.0 * mm,
                "must lie in [3, 20] mm",
            ),
            (
                "gsv_diameter_sfj",
                self.gsv_diameter_sfj,
                1.5 * mm,
                20.0 * mm,
                "must lie in [1.5, 20] mm",
            ),
            (
                "gsv_diameter_thigh",
                self.gsv_diameter_thigh,
                1.0 * mm,
                15.0 * mm,
                "must lie in [1, 15] mm",
            ),
            (
                "vein_artery_ratio_groin",
                self.vein_artery_ratio_groin,
                0.8,
                3.0,
                "must lie in [0.8, 3]",
            ),
            (
                "vein_artery_ratio_below",
                self.vein_artery_ratio_below,
                0.8,
                3.0,
                "must lie in [0.8, 3]",
            ),
            (
                "stiffness_scale",
                self.stiffness_scale,
                1e-3,
                20.0,
                "must lie in (0, 20]",
            ),
            (
                "exam_force",
                self.exam_force,
                5.0,
                80.0,
                "must lie in [5, 80] N",
            ),
            (
                "fv_diameter_mid",
                self.fv_diameter_mid,
                0.0,
                self.cfv_diameter,
                "must not exceed cfv_diameter",
            ),
        ];
        for (key, value, lo, hi, reason) in checks {
            if !value.is_finite() || value < lo || value > hi {
                return Err(AnatomyError::InvalidValue { key, value, reason });
            }
        }
        if self.length < self.knee_s + 0.02 {
            return Err(AnatomyError::InvalidValue {
                key: "length",
                value: self.length,
                reason: "must exceed knee_s by at least 0.02 m (the model ends below the knee)",
            });
        }
        let compartment = self.gsv_diameter_thigh + 1e-3;
        for (key, value) in [
            ("fat_thickness_proximal", self.fat_thickness_proximal),
            ("fat_thickness_distal", self.fat_thickness_distal),
        ] {
            if value < compartment {
                return Err(AnatomyError::InvalidValue {
                    key,
                    value,
                    reason: "must exceed the GSV diameter + 1 mm (the GSV lies within the fat, in its saphenous compartment)",
                });
            }
        }
        Ok(())
    }

    /// Factor on the muscle's stiffness for the physical model:
    /// `stiffness_scale × (2 if tense_muscle)` (reference row 19).
    pub fn muscle_stiffness_factor(&self) -> f64 {
        self.stiffness_scale * if self.tense_muscle { 2.0 } else { 1.0 }
    }
}

fn preset_text(name: &str) -> Result<&'static str, AnatomyError> {
    match name {
        "lean-male" => Ok(LEAN_MALE),
        "average-female" => Ok(AVERAGE_FEMALE),
        "obese" => Ok(OBESE),
        other => Err(AnatomyError::UnknownPreset(other.to_string())),
    }
}
