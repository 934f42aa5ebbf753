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
