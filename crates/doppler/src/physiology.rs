//! The physiological numbers of the flow model (`[doppler.flow]`), SI units,
//! each with its source.
//!
//! - **Venous velocity.** The maximum flow velocity in adult femoral veins
//!   is 12–30 cm/s (radiologyspirit 2010, "Normal spectral waveforms from
//!   lower limb veins", after Selis et al.); the default resting CFV peak
//!   (spectral maximum, i.e. centreline) is the middle, 20 cm/s, and the
//!   other deep veins a little lower inside that range.
//! - **Breathing.** Inspiration raises intra-abdominal pressure and slows
//!   leg venous return, expiration speeds it (same source); diaphragmatic
//!   breathing can stop it (Miller et al., J Physiol 2005). The velocity is
//!   modulated by `1 + depth · sin(2π f t)` (clamped at 0), default rate
//!   15 /min (adult resting 12–20 /min) and depth 0.5.
//! - **Arterial flow.** Peak systolic velocity 114 ± 25 cm/s in the CFA,
//!   91 ± 14 cm/s in the proximal SFA, 69 ± 14 cm/s in the popliteal artery
//!   (Jager et al., Ultrasound Med Biol 1985, 55 healthy subjects); the
//!   shape is triphasic (forward systole, reversal in early diastole, late
//!   forward flow: Persson et al., J Cardiovasc Surg 1981), see
//!   [`crate::arterial`]; heart rate 70 /min.
//! - **Augmentation.** A calf squeeze raises the femoral venous peak
//!   velocity several-fold: 62 cm/s in the FV during ankle plantar flexion
//!   (BMC Musculoskelet Disord 2022, 23:405) against 12–30 cm/s at rest;
//!   intermittent pneumatic calf compression raises it likewise (Morris &
//!   Woodcock, Ann Surg 2004 review). Default factor 3 on the resting peak.
//!   The extra velocity is a gamma-variate pulse `(t/τ) e^{1 − t/τ}` with
//!   τ = 0.3 s (peak at τ, back to 9 % by 5τ = 1.5 s). Derivation of τ: the
//!   volume ejected past a CFV of 10.5 mm (Hertzberg 1997) is
//!   `ΔV = Δv̄ · A · e · τ` = (0.2 m/s mean extra) · 0.87 cm² · e · 0.3 s
//!   ≈ 14 mL, the order of the calf's venous volume a manual squeeze
//!   empties (tens of mL).
//! - **Valsalva.** Flow stops for the strain and overshoots on release
//!   (Wexler et al., Circ Res 1968, caval flow); the CFV diameter rises by
//!   50–200 % when healthy and only 10–50 % with DVT (Lin et al., J
//!   Ultrasound Med; ../shared/reference/cus-exam-fidelity.md row 19):
//!   defaults +100 % and +30 %.

use crate::error::DopplerError;
use serde::{Deserialize, Serialize};

/// The flow model's parameters (see the module docs for sources).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FlowConfig {
    /// Breathing rate (Hz). Default 0.25 (15 /min). Accepted 0.05–1.
    pub breathing_rate: f64,
    /// Fractional modulation of venous velocity by breathing. Default 0.5. Accepted 0–1.5.
    pub breathing_depth: f64,
    /// Resting peak (centreline) velocity of the CFV (m/s). Default 0.20. Accepted 0.02–1.
    pub cfv_peak_velocity: f64,
    /// Peak velocity of the FV, DFV and duplicated FV relative to the CFV. Default 0.9.
    pub thigh_vein_ratio: f64,
    /// Peak velocity of the popliteal vein and the GSV relative to the CFV. Default 0.75.
    pub distal_vein_ratio: f64,
    /// Heart rate (Hz). Default 70/60. Accepted 0.5–3.
    pub heart_rate: f64,
    /// Peak systolic velocity of the CFA (m/s). Default 1.14. Accepted 0.2–3.
    pub cfa_psv: f64,
    /// PSV of the FA (and DFA) (m/s). Default 0.91.
    pub fa_psv: f64,
    /// PSV of the popliteal artery (m/s). Default 0.69.
    pub pa_psv: f64,
    /// Peak venous velocity during a calf squeeze relative to rest. Default 3. Accepted 1–10.
    pub augmentation_factor: f64,
    /// Time to peak of the augmentation pulse (s). Default 0.3. Accepted 0.05–3.
    pub augmentation_rise: f64,
    /// Time constant of the stop at Valsalva onset and of its release (s). Default 0.3.
    pub valsalva_time_constant: f64,
    /// Overshoot on Valsalva release, relative to rest. Default 2. Accepted 1–10.
    pub valsalva_release_factor: f64,
    /// CFV diameter rise on Valsalva, healthy (fraction). Default 1.0. Accepted 0–3.
    pub valsalva_distension_healthy: f64,
    /// CFV diameter rise on Valsalva with thrombus or proximal obstruction. Default 0.3.
    pub valsalva_distension_obstructed: f64,
    /// Peak velocity on release of a probe compression relative to rest. Default 1.5.
    pub release_factor: f64,
    /// Lumen area ratio under the probe below which the vein is closed (no flow). Default 0.05.
    pub closed_ratio: f64,
    /// Open fraction of a lumen below which a segment is occluded (no flow). Default 0.02.
    pub occluded_open_fraction: f64,
}

impl Default for FlowConfig {
    fn default() -> Self {
        FlowConfig {
            breathing_rate: 0.25,
            breathing_depth: 0.5,
            cfv_peak_velocity: 0.20,
            thigh_vein_ratio: 0.9,
            distal_vein_ratio: 0.75,
            heart_rate: 70.0 / 60.0,
            cfa_psv: 1.14,
            fa_psv: 0.91,
            pa_psv: 0.69,
            augmentation_factor: 3.0,
            augmentation_rise: 0.3,
            valsalva_time_constant: 0.3,
            valsalva_release_factor: 2.0,
            valsalva_distension_healthy: 1.0,
            valsalva_distension_obstructed: 0.3,
            release_factor: 1.5,
            closed_ratio: 0.05,
            occluded_open_fraction: 0.02,
        }
    }
}

impl FlowConfig {
    /// Checks every field, naming `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), DopplerError> {
        let r = DopplerError::in_range;
        r(
            prefix,
            "breathing_rate",
            self.breathing_rate,
            0.05,
            1.0,
            "must be 0.05 to 1 Hz",
        )?;
        r(
            prefix,
            "breathing_depth",
            self.breathing_depth,
            0.0,
            1.5,
            "must be 0 to 1.5",
        )?;
        r(
            prefix,
            "cfv_peak_velocity",
            self.cfv_peak_velocity,
            0.02,
            1.0,
            "must be 0.02 to 1 m/s",
        )?;
        r(
            prefix,
            "thigh_vein_ratio",
            self.thigh_vein_ratio,
            0.1,
            2.0,
            "must be 0.1 to 2",
        )?;
        r(
            prefix,
            "distal_vein_ratio",
            self.distal_vein_ratio,
            0.1,
            2.0,
            "must be 0.1 to 2",
        )?;
        r(
            prefix,
            "heart_rate",
            self.heart_rate,
            0.5,
            3.0,
            "must be 0.5 to 3 Hz",
        )?;
        for (k, v) in [
            ("cfa_psv", self.cfa_psv),
            ("fa_psv", self.fa_psv),
            ("pa_psv", self.pa_psv),
        ] {
            r(prefix, k, v, 0.2, 3.0, "must be 0.2 to 3 m/s")?;
        }
        r(
            prefix,
            "augmentation_factor",
            self.augmentation_factor,
            1.0,
            10.0,
            "must be 1 to 10",
        )?;
        r(
            prefix,
            "augmentation_rise",
            self.augmentation_rise,
            0.05,
            3.0,
            "must be 0.05 to 3 s",
        )?;
        r(
            prefix,
            "valsalva_time_constant",
            self.valsalva_time_constant,
            0.05,
            3.0,
            "must be 0.05 to 3 s",
        )?;
        r(
            prefix,
            "valsalva_release_factor",
            self.valsalva_release_factor,
            1.0,
            10.0,
            "must be 1 to 10",
        )?;
        r(
            prefix,
            "valsalva_distension_healthy",
            self.valsalva_distension_healthy,
            0.0,
            3.0,
            "must be 0 to 3",
        )?;
        r(
            prefix,
            "valsalva_distension_obstructed",
            self.valsalva_distension_obstructed,
            0.0,
            3.0,
            "must be 0 to 3",
        )?;
        r(
            prefix,
            "release_factor",
            self.release_factor,
            1.0,
            10.0,
            "must be 1 to 10",
        )?;
        r(
            prefix,
            "closed_ratio",
            self.closed_ratio,
            0.0,
            0.5,
            "must be 0 to 0.5",
        )?;
        r(
            prefix,
            "occluded_open_fraction",
            self.occluded_open_fraction,
            0.0,
            0.5,
            "must be 0 to 0.5",
        )
    }
}
