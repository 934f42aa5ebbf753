//! Named levels along the leg (m below the inguinal ligament), as fractions
//! of the knee joint line's level `knee_s` so that they scale with the leg.

use crate::patient::Patient;

/// SFJ: 0.05 knee_s (2.0 cm for knee_s = 0.40). The SFJ centre lies
/// 1.0 ± 0.9 cm below the pubic tubercle (ultrasound, 100 adults, Clin Anat
/// 2014, doi:10.1002/ca.22386); the ligament at the vein's level lies about
/// 1 cm above the tubercle's level (estimate).
pub const F_SFJ: f64 = 0.05;
/// CFA bifurcation: 0.10 knee_s (4.0 cm): "the average common femoral artery
/// is approximately 4 cm in length" (IMAIOS e-Anatomy, common femoral
/// artery); the profunda is marked from 3.5 cm below the mid-inguinal point
/// (surface anatomy, https://docsbay.net/surface-anatomy-of-arteries-and-veins-of-lower-limb).
pub const F_BIFURCATION: f64 = 0.10;
/// Profunda vein confluence (the CFV's start): 0.15 knee_s (6 cm; estimate:
/// below the arterial bifurcation and above the inguinal crease, which lies
/// 6.7 ± 1.9 cm below the ligament, CVIR doi:10.1007/BF02577111).
pub const F_CONFLUENCE: f64 = 0.15;
/// Apex of the femoral triangle, where sartorius crosses the vessels and the
/// adductor canal begins: 0.30 knee_s (12 cm; estimate).
pub const F_APEX: f64 = 0.30;
/// Adductor hiatus (the FV becomes the popliteal vein): 2/3 knee_s, "the
/// junction of the middle and lower thirds of the thigh" (surface anatomy
/// of the popliteal artery, docsbay reference above).
pub const F_HIATUS: f64 = 2.0 / 3.0;

/// The levels of one patient (m below the inguinal ligament).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Levels {
    /// Saphenofemoral junction.
    pub sfj: f64,
    /// CFA bifurcation into the FA and the DFA.
    pub bifurcation: f64,
    /// Confluence of the FV and the DFV into the CFV.
    pub confluence: f64,
    /// Apex of the femoral triangle (start of the adductor canal).
    pub apex: f64,
    /// Adductor hiatus (FV → PV, FA → PA).
    pub hiatus: f64,
    /// Knee joint line.
    pub knee: f64,
    /// End of the model (just below the knee).
    pub length: f64,
}

impl Levels {
    /// The levels of patient `p`.
    pub fn new(p: &Patient) -> Levels {
        let k = p.knee_s;
        Levels {
            sfj: F_SFJ * k,
            bifurcation: F_BIFURCATION * k,
            confluence: F_CONFLUENCE * k,
            apex: F_APEX * k,
            hiatus: F_HIATUS * k,
            knee: k,
            length: p.length,
        }
    }
}

/// The stretch of the leg a probe at `s` examines, named as a sonographer
/// reports it (the segments of the deep veins, reference §1 "Protocols").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegLevel {
    /// Above the inguinal ligament (s < 0): outside the thigh.
    AboveGroin,
    /// The common femoral vein, groin (from the ligament to the profunda's
    /// confluence), away from the SFJ.
    CommonFemoral,
    /// Within 1 cm of the saphenofemoral junction.
    Saphenofemoral,
    /// The proximal femoral vein in the femoral triangle (confluence to the
    /// triangle's apex).
    FemoralProximal,
    /// The femoral vein in the adductor canal (apex to hiatus).
    FemoralCanal,
    /// The popliteal vein (hiatus to the knee joint line and just below).
    Popliteal,
    /// Below the model's end.
    BelowKnee,
}

impl Levels {
    /// The level a probe at `s` (m below the inguinal ligament) examines.
    pub fn level_at(&self, s: f64) -> LegLevel {
        if s < 0.0 {
            LegLevel::AboveGroin
        } else if (s - self.sfj).abs() <= 0.01 {
            LegLevel::Saphenofemoral
        } else if s < self.confluence {
            LegLevel::CommonFemoral
        } else if s < self.apex {
            LegLevel::FemoralProximal
        } else if s < self.hiatus {
            LegLevel::FemoralCanal
        } else if s <= self.length {
            LegLevel::Popliteal
        } else {
            LegLevel::BelowKnee
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every named site lies at the level its name says (the sites of
    /// `Anatomy::site_pose` and the levels come from the same fractions).
    #[test]
    fn sites_lie_at_their_levels() {
        use crate::{Anatomy, Site};
        let a = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
        let lv = a.levels();
        let at = |site| lv.level_at(a.site_pose(site).s);
        assert_eq!(at(Site::Cfv), LegLevel::CommonFemoral);
        assert_eq!(at(Site::Sfj), LegLevel::Saphenofemoral);
        assert_eq!(at(Site::FvProximal), LegLevel::FemoralProximal);
        assert_eq!(at(Site::FvMid), LegLevel::FemoralCanal);
        assert_eq!(at(Site::FvDistal), LegLevel::FemoralCanal);
        assert_eq!(at(Site::Popliteal), LegLevel::Popliteal);
        assert_eq!(lv.level_at(-0.01), LegLevel::AboveGroin);
        assert_eq!(lv.level_at(lv.length + 0.01), LegLevel::BelowKnee);
    }
}
