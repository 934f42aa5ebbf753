//! Parameters of the transverse section of the mid-thigh
//! (`[imaging.anatomy]`), in tissue coordinates: `u` lateral (m, from the
//! probe's centre; negative is medial) and depth below the undeformed skin (m).
//!
//! Defaults and their published sources:
//! - **Skin** 1.8 mm: ultrasound thickness of the thigh's skin ≈ 1.5–2 mm
//!   (Van Mulder et al. 2017, "High frequency ultrasound to assess skin
//!   thickness in healthy adults", Vaccine 35(14)).
//! - **Subcutaneous fat** 10 mm: anterior/medial thigh of normal-weight adults
//!   ≈ 5–15 mm (Störchle et al. 2018, "Standardized ultrasound measurement of
//!   subcutaneous fat patterning", Sci. Rep. 8).
//! - **Muscle** 28 mm over the femur (sartorius and vastus medialis), with the
//!   deep fascia on top and an intermuscular fascia at ≈ 20 mm; anterior
//!   thigh muscle thickness by B-mode ≈ 25–50 mm (Abe et al. 1994,
//!   "Prediction equations for body composition of Japanese adults by B-mode
//!   ultrasound", Am. J. Hum. Biol. 6).
//! - **Femoral vein** 10 mm in diameter, medial to the artery: femoral vein
//!   ≈ 8–11 mm (Fronek et al. 2001, "Common femoral vein dimensions and
//!   hemodynamics including Valsalva response as a function of sex, age, and
//!   ethnicity in a population study", J. Vasc. Surg. 33(5)).
//! - **Femoral artery** 7 mm: superficial femoral artery ≈ 6–8 mm (Sandgren
//!   et al. 1999, "The diameter of the common femoral artery in healthy human:
//!   influence of sex, age, and body size", J. Vasc. Surg. 29(3)). Diameter
//!   pulsation ≈ 5–10 % (same source's distension measurements). Heart rate
//!   1 Hz (60 bpm).
//! - Both vessels at ≈ 30 mm below the skin (25–35 mm in the adductor canal).
//! - **Femur** radius 13 mm (mid-shaft diameter ≈ 26–28 mm), cortex ≈ 4–7 mm
//!   (Duck 1990, "Physical Properties of Tissue", ch. 5).
//! - **Vein compressibility**: the supine femoral venous pressure is
//!   ≈ 8–10 mmHg; a healthy vein starts to flatten when the tissue pressure
//!   exceeds it and is closed at a few tens of mmHg (Shapiro 1977, "Steady
//!   flow in collapsible tubes", J. Biomech. Eng. 99; clinical compression
//!   ultrasound: full coaptation "with gentle pressure", Needleman et al.
//!   2018). Acute thrombus: distended vein (diameter ≈ +15–20 %), hypoechoic
//!   content, little compressibility; chronic: retracted, echogenic, thick
//!   wall, rigid (Needleman et al. 2018; Kearon et al. 1998, Ann. Intern. Med.
//!   128).

use crate::error::ImagingError;
use crate::structure_config::{StructureConfig, MAX_STRUCTURES};
use crate::vein_condition::VeinCondition;
use serde::{Deserialize, Serialize};

/// One millimetre of mercury in pascals.
pub const MMHG: f64 = 133.322;

/// The state of the femoral vein in a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum VeinState {
    /// Patent vein: anechoic, collapses under moderate pressure.
    #[default]
    Healthy,
    /// Acute thrombosis: distended, hypoechoic content, deforms a little.
    Acute,
    /// Chronic thrombosis: retracted, echogenic content, thick wall, rigid.
    Chronic,
}

impl VeinState {
    /// All states, in the order healthy, acute, chronic.
    pub const ALL: [VeinState; 3] = [VeinState::Healthy, VeinState::Acute, VeinState::Chronic];

    /// The lowercase name (`healthy`, `acute`, `chronic`).
    pub fn name(self) -> &'static str {
        match self {
            VeinState::Healthy => "healthy",
            VeinState::Acute => "acute",
            VeinState::Chronic => "chronic",
        }
    }
}

impl std::str::FromStr for VeinState {
    type Err = ImagingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "healthy" => Ok(VeinState::Healthy),
            "acute" => Ok(VeinState::Acute),
            "chronic" => Ok(VeinState::Chronic),
            _ => Err(ImagingError::VeinState(s.to_string())),
        }
    }
}

/// How the vein looks and yields in one [`VeinState`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VeinStateParams {
    /// Lumen diameter relative to `vein_diameter` (dimensionless).
    /// Accepted: in 0.2 to 2.
    pub diameter_factor: f64,
    /// Wall thickness (m).
    /// Accepted: in 0.1 to 5 mm.
    pub wall_thickness: f64,
    /// Backscatter of the lumen content relative to muscle (dB).
    /// Accepted: in -80 to 30 dB.
    pub content_echo: f64,
    /// Backscatter of the wall relative to muscle (dB).
    /// Accepted: in -80 to 30 dB.
    pub wall_echo: f64,
    /// Attenuation slope of the lumen content (dB/(cm·MHz), one way): blood
    /// ≈ 0.15–0.2 (Duck 1990, ch. 4), thrombus higher.
    /// Accepted: in 0 to 5 dB/(cm MHz) (blood 0.15, thrombus higher).
    pub content_attenuation: f64,
    /// Tissue pressure at the vein where the lumen starts to flatten (Pa).
    /// Accepted: in 0 to 1e5 Pa (750 mmHg).
    pub collapse_onset: f64,
    /// Tissue pressure at which the lumen reaches its smallest size (Pa).
    /// Accepted: in 1 to 1e5 Pa (750 mmHg).
    pub collapse_full: f64,
    /// Smallest lumen area relative to rest (dimensionless, in [0, 1]).
    /// Accepted: in [0, 1].
    pub min_lumen_ratio: f64,
}

impl VeinStateParams {
    /// Patent vein: anechoic blood, thin wall, closed at 35 mmHg.
    pub fn healthy() -> Self {
        VeinStateParams {
            diameter_factor: 1.0,
            wall_thickness: 0.5e-3,
            content_echo: -50.0,
            wall_echo: 4.0,
            content_attenuation: 0.15,
            collapse_onset: 8.0 * MMHG,
            collapse_full: 35.0 * MMHG,
            min_lumen_ratio: 0.0,
        }
    }
    /// Acute thrombus: distended, hypoechoic, yields 20 % at most.
    pub fn acute() -> Self {
        VeinStateParams {
            diameter_factor: 1.18,
            wall_thickness: 0.5e-3,
            content_echo: -24.0,
            wall_echo: 4.0,
            content_attenuation: 0.3,
            collapse_onset: 30.0 * MMHG,
            collapse_full: 150.0 * MMHG,
            min_lumen_ratio: 0.8,
        }
    }
    /// Chronic thrombus: retracted, echogenic, 1.5 mm wall, rigid. The
    /// wall is fibrous: +12 dB re muscle, the echo of fascia (derived; see
    /// `crate::post_thrombotic` for its thickness and irregularity).
    pub fn chronic() -> Self {
        VeinStateParams {
            diameter_factor: 0.85,
            wall_thickness: 1.5e-3,
            content_echo: -14.0,
            wall_echo: 12.0,
            content_attenuation: 0.5,
            collapse_onset: 60.0 * MMHG,
            collapse_full: 250.0 * MMHG,
            min_lumen_ratio: 0.95,
        }
    }

    fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "diameter_factor",
            self.diameter_factor,
            0.2,
            2.0,
            "must be between 0.2 and 2",
        )?;
        ImagingError::in_range(
            prefix,
            "wall_thickness",
            self.wall_thickness,
            0.0001,
            0.005,
            "must be between 0.1 and 5 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "content_echo",
            self.content_echo,
            -80.0,
            30.0,
            "must be between -80 and 30 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "wall_echo",
            self.wall_echo,
            -80.0,
            30.0,
            "must be between -80 and 30 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "content_attenuation",
            self.content_attenuation,
            0.0,
            5.0,
            "must be between 0 and 5 dB/(cm MHz) (blood 0.15, thrombus higher)",
        )?;
        ImagingError::in_range(
            prefix,
            "collapse_onset",
            self.collapse_onset,
            0.0,
            100000.0,
            "must be between 0 and 1e5 Pa (750 mmHg)",
        )?;
        ImagingError::in_range(
            prefix,
            "collapse_full",
            self.collapse_full,
            1.0,
            100000.0,
            "must be between 1 and 1e5 Pa (750 mmHg)",
        )?;
        if self.collapse_full <= self.collapse_onset {
            return Err(ImagingError::invalid(
                prefix,
                "collapse_full",
                self.collapse_full,
                "must exceed collapse_onset",
            ));
        }
        ImagingError::in_range(
            prefix,
            "min_lumen_ratio",
            self.min_lumen_ratio,
            0.0,
            1.0,
            "must be in [0, 1]",
        )
    }
}

/// Geometry and vessel behaviour of the section (`[imaging.anatomy]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnatomyConfig {
    /// Skin (epidermis + dermis) thickness (m). Default 1.8e-3.
    /// Accepted: in 0.5 to 5 mm (thigh skin 1.5-2 mm).
    pub skin_thickness: f64,
    /// Subcutaneous fat thickness (m). Default 10e-3.
    /// Accepted: in 1 to 100 mm (subcutaneous fat 5-15 mm, more in the obese).
    pub fat_thickness: f64,
    /// Muscle thickness from the deep fascia to the femur's top (m). Default 28e-3.
    /// Accepted: in 5 to 150 mm (anterior thigh muscle 25-50 mm).
    pub muscle_thickness: f64,
    /// Thickness of the fascia lines (m). Default 0.5e-3.
    /// Accepted: in 0.1 to 3 mm.
    pub fascia_thickness: f64,
    /// Depth of the intermuscular fascia below the skin at `u = 0` (m). Default 19e-3.
    /// Accepted: in 1 to 250 mm.
    pub intermuscular_fascia_depth: f64,
    /// Vein diameter at rest in the healthy state (m). Default 10e-3.
    /// Accepted: in 2 to 30 mm (femoral vein 8-11 mm).
    pub vein_diameter: f64,
    /// Lateral position of the vein's centre (m; negative is medial). Default −8e-3.
    /// Accepted: in -50 to 50 mm of the probe centre.
    pub vein_lateral: f64,
    /// Depth of the vein's centre below the skin at rest (m). Default 30e-3.
    pub vein_depth: f64,
    /// Artery diameter at diastole (m). Default 7e-3.
    /// Accepted: in 2 to 20 mm (femoral artery 6-8 mm).
    pub artery_diameter: f64,
    /// Lateral position of the artery's centre (m). Default 3e-3.
    /// Accepted: in -50 to 50 mm of the probe centre.
    pub artery_lateral: f64,
    /// Depth of the artery's centre below the skin at rest (m). Default 29e-3.
    pub artery_depth: f64,
    /// Artery wall thickness (m). Default 0.7e-3.
    /// Accepted: in 0.1 to 3 mm.
    pub artery_wall_thickness: f64,
    /// Peak systolic increase of the artery diameter, relative (dimensionless). Default 0.07.
    /// Accepted: in [0, 0.5].
    pub artery_distension: f64,
    /// Heart rate (Hz). Default 1.0 (60 bpm).
    /// Accepted: in 0 to 4 Hz (0 to 240 bpm).
    pub heart_rate: f64,
    /// Tissue pressure at which the artery starts to flatten (Pa). Default
    /// 60 mmHg: trainees press "until the artery just begins to deform"
    /// (cus-exam-fidelity row 5), so it must ovalise from roughly diastolic
    /// pressure, ~60–80 mmHg (§4 item 5; with the defaults below its area is
    /// down 6 % at 80 mmHg, 12 % at 90). Accepted: in 0 to 1e5 Pa (750 mmHg).
    pub artery_collapse_onset: f64,
    /// Tissue pressure at which the artery reaches its smallest size (Pa).
    /// Default 150 mmHg: "clearly oval by ~120 mmHg" (§4 item 5): area 67 %
    /// of rest at 120 mmHg with the defaults.
    pub artery_collapse_full: f64,
    /// Smallest artery lumen area relative to rest (dimensionless). Default
    /// 0.55 (estimate: a clearly flattened but patent artery, its height
    /// about half its width; arterial pressure keeps it open).
    /// Accepted: in [0, 1].
    pub artery_min_lumen_ratio: f64,
    /// Femur radius (m). Default 13e-3.
    /// Accepted: in 5 to 30 mm (mid-shaft femur).
    pub femur_radius: f64,
    /// Lateral position of the femur's centre (m). Default 6e-3.
    /// Accepted: in -50 to 50 mm of the probe centre.
    pub femur_lateral: f64,
    /// Femoral cortex thickness (m). Default 5e-3.
    /// Accepted: in 0.5 to 15 mm (femoral cortex 4-7 mm).
    pub cortex_thickness: f64,
    /// Vein in the healthy state (`[imaging.anatomy.healthy]`).
    pub healthy: VeinStateParams,
    /// Vein with an acute thrombus (`[imaging.anatomy.acute]`).
    pub acute: VeinStateParams,
    /// Vein with a chronic thrombus (`[imaging.anatomy.chronic]`).
    pub chronic: VeinStateParams,
    /// The section's other structures (`[[imaging.anatomy.structures]]`):
    /// vessels, muscle outlines, lymph nodes, as the plane through the 3D
    /// leg cuts them (`echothigh image --at/--site` fills them). Default
    /// none (the mid-thigh pair alone). At most 12.
    pub structures: Vec<StructureConfig>,
    /// The studied vein's own condition (`[imaging.anatomy.vein_condition]`,
    /// issue 13: a case's thrombus segment state at the section's `s`).
    /// Default none: the vein follows the renderer's global [`VeinState`]
    /// (`healthy`, `acute`, `chronic` above).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vein_condition: Option<VeinCondition>,
}

impl Default for AnatomyConfig {
    fn default() -> Self {
        AnatomyConfig {
            skin_thickness: 1.8e-3,
            fat_thickness: 10e-3,
            muscle_thickness: 28e-3,
            fascia_thickness: 0.5e-3,
            intermuscular_fascia_depth: 19e-3,
            vein_diameter: 10e-3,
            vein_lateral: -8e-3,
            vein_depth: 30e-3,
            artery_diameter: 7e-3,
            artery_lateral: 3e-3,
            artery_depth: 29e-3,
            artery_wall_thickness: 0.7e-3,
            artery_distension: 0.07,
            heart_rate: 1.0,
            artery_collapse_onset: 60.0 * MMHG,
            artery_collapse_full: 150.0 * MMHG,
            artery_min_lumen_ratio: 0.55,
            femur_radius: 13e-3,
            femur_lateral: 6e-3,
            cortex_thickness: 5e-3,
            healthy: VeinStateParams::healthy(),
            acute: VeinStateParams::acute(),
            chronic: VeinStateParams::chronic(),
            structures: Vec::new(),
            vein_condition: None,
        }
    }
}

impl AnatomyConfig {
    /// The vein parameters of `state`.
    pub fn vein(&self, state: VeinState) -> &VeinStateParams {
        match state {
            VeinState::Healthy => &self.healthy,
            VeinState::Acute => &self.acute,
            VeinState::Chronic => &self.chronic,
        }
    }

    /// The studied vein's condition: `vein_condition` if set, else that of `state`.
    pub fn studied_condition(&self, state: VeinState) -> VeinCondition {
        self.vein_condition
            .unwrap_or_else(|| VeinCondition::of_state(state, self.vein(state), &self.healthy))
    }

    /// Depth of the femur's top below the skin at rest (m): skin + fat + muscle.
    pub fn femur_top(&self) -> f64 {
        self.skin_thickness + self.fat_thickness + self.muscle_thickness
    }

    /// Whether a vessel of outer radius `r` (m) centred at `(lateral,
    /// depth)` (m) lies under the skin and outside the femur's disc. The
    /// renderer draws lumens and walls before the layers, so a vessel may
    /// cross the fascia into the fat (the common femoral vessels lie just
    /// under the fascia lata, and thick fat in the obese groin reaches
    /// their level) and may lie beside the femur deeper than its top (the
    /// popliteal vessels beside the condyles; the column compression of
    /// [`crate::deformation`] stops at the femur's depth either way).
    pub fn vessel_fits(&self, lateral: f64, depth: f64, r: f64) -> bool {
        let fc = self.femur_top() + self.femur_radius;
        let apart = (lateral - self.femur_lateral).hypot(depth - fc);
        depth - r > self.skin_thickness && apart > self.femur_radius + r
    }

    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        let p = prefix;
        if self.structures.len() > MAX_STRUCTURES {
            return Err(ImagingError::invalid(
                p,
                "structures",
                self.structures.len(),
                "at most 12 structures",
            ));
        }
        for (i, st) in self.structures.iter().enumerate() {
            st.validate(&format!("{p}.structures[{i}]"))?;
        }
        ImagingError::in_range(
            p,
            "skin_thickness",
            self.skin_thickness,
            0.0005,
            0.005,
            "must be between 0.5 and 5 mm (thigh skin 1.5-2 mm)",
        )?;
        ImagingError::in_range(
            p,
            "fat_thickness",
            self.fat_thickness,
            0.001,
            0.1,
            "must be between 1 and 100 mm (subcutaneous fat 5-15 mm, more in the obese)",
        )?;
        ImagingError::in_range(
            p,
            "muscle_thickness",
            self.muscle_thickness,
            0.005,
            0.15,
            "must be between 5 and 150 mm (anterior thigh muscle 25-50 mm)",
        )?;
        ImagingError::in_range(
            p,
            "fascia_thickness",
            self.fascia_thickness,
            0.0001,
            0.003,
            "must be between 0.1 and 3 mm",
        )?;
        ImagingError::in_range(
            p,
            "intermuscular_fascia_depth",
            self.intermuscular_fascia_depth,
            0.001,
            0.25,
            "must be between 1 and 250 mm",
        )?;
        ImagingError::in_range(
            p,
            "vein_diameter",
            self.vein_diameter,
            0.002,
            0.03,
            "must be between 2 and 30 mm (femoral vein 8-11 mm)",
        )?;
        ImagingError::in_range(
            p,
            "vein_lateral",
            self.vein_lateral,
            -0.05,
            0.05,
            "must be between -50 and 50 mm of the probe centre",
        )?;
        ImagingError::in_range(
            p,
            "artery_diameter",
            self.artery_diameter,
            0.002,
            0.02,
            "must be between 2 and 20 mm (femoral artery 6-8 mm)",
        )?;
        ImagingError::in_range(
            p,
            "artery_lateral",
            self.artery_lateral,
            -0.05,
            0.05,
            "must be between -50 and 50 mm of the probe centre",
        )?;
        ImagingError::in_range(
            p,
            "artery_wall_thickness",
            self.artery_wall_thickness,
            0.0001,
            0.003,
            "must be between 0.1 and 3 mm",
        )?;
        ImagingError::in_range(
            p,
            "artery_distension",
            self.artery_distension,
            0.0,
            0.5,
            "must be in [0, 0.5]",
        )?;
        ImagingError::in_range(
            p,
            "heart_rate",
            self.heart_rate,
            0.0,
            4.0,
            "must be between 0 and 4 Hz (0 to 240 bpm)",
        )?;
        ImagingError::in_range(
            p,
            "artery_collapse_onset",
            self.artery_collapse_onset,
            0.0,
            100000.0,
            "must be between 0 and 1e5 Pa (750 mmHg)",
        )?;
        if self.artery_collapse_full.is_nan()
            || self.artery_collapse_full > 1e5
            || self.artery_collapse_full <= self.artery_collapse_onset
        {
            return Err(ImagingError::invalid(
                p,
                "artery_collapse_full",
                self.artery_collapse_full,
                "must exceed artery_collapse_onset and be at most 1e5 Pa (750 mmHg)",
            ));
        }
        ImagingError::in_range(
            p,
            "artery_min_lumen_ratio",
            self.artery_min_lumen_ratio,
            0.0,
            1.0,
            "must be in [0, 1]",
        )?;
        ImagingError::in_range(
            p,
            "femur_radius",
            self.femur_radius,
            0.005,
            0.03,
            "must be between 5 and 30 mm (mid-shaft femur)",
        )?;
        ImagingError::in_range(
            p,
            "femur_lateral",
            self.femur_lateral,
            -0.05,
            0.05,
            "must be between -50 and 50 mm of the probe centre",
        )?;
        ImagingError::in_range(
            p,
            "cortex_thickness",
            self.cortex_thickness,
            0.0005,
            0.015,
            "must be between 0.5 and 15 mm (femoral cortex 4-7 mm)",
        )?;
        if self.cortex_thickness >= self.femur_radius {
            return Err(ImagingError::invalid(
                p,
                "cortex_thickness",
                self.cortex_thickness,
                "must be less than femur_radius",
            ));
        }
        let muscle_top = self.skin_thickness + self.fat_thickness;
        let femur_top = self.femur_top();
        if self.intermuscular_fascia_depth <= muscle_top
            || self.intermuscular_fascia_depth >= femur_top
        {
            return Err(ImagingError::invalid(
                p,
                "intermuscular_fascia_depth",
                self.intermuscular_fascia_depth,
                "must lie inside the muscle layer",
            ));
        }
        self.healthy.validate(&format!("{p}.healthy"))?;
        self.acute.validate(&format!("{p}.acute"))?;
        self.chronic.validate(&format!("{p}.chronic"))?;
        if let Some(vc) = &self.vein_condition {
            vc.validate(&format!("{p}.vein_condition"))?;
            // A distended vein may bulge into the fat (lumens are drawn
            // first), but must stay under the skin and clear of the femur.
            let r = 0.5 * self.vein_diameter * vc.diameter_factor + vc.wall_thickness;
            if !self.vessel_fits(self.vein_lateral, self.vein_depth, r) {
                return Err(ImagingError::invalid(
                    p,
                    "vein_condition.diameter_factor",
                    vc.diameter_factor,
                    "the vein so distended would cross the skin or the femur",
                ));
            }
        }
        // Vessels (largest state) must sit under the skin and clear of the
        // femur (`vessel_fits`).
        let vein_r = 0.5
            * self.vein_diameter
            * VeinState::ALL
                .iter()
                .map(|&s| self.vein(s).diameter_factor)
                .fold(0.0, f64::max)
            + VeinState::ALL
                .iter()
                .map(|&s| self.vein(s).wall_thickness)
                .fold(0.0, f64::max);
        let art_r = 0.5 * self.artery_diameter * (1.0 + self.artery_distension)
            + self.artery_wall_thickness;
        for (field, depth, r) in [
            ("vein_depth", self.vein_depth, vein_r),
            ("artery_depth", self.artery_depth, art_r),
        ] {
            let lateral = if field == "vein_depth" {
                self.vein_lateral
            } else {
                self.artery_lateral
            };
            if !self.vessel_fits(lateral, depth, r) {
                return Err(ImagingError::invalid(
                    p,
                    field,
                    depth,
                    "the vessel (with its wall) must lie under the skin and clear of the femur",
                ));
            }
        }
        Ok(())
    }
}
