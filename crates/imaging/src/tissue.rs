//! Tissue classes of the section and their acoustic properties.
//!
//! Backscatter is given relative to muscle (dB of mean echo intensity) and
//! attenuation as a one-way slope (dB/(cm·MHz)).
//!
//! **Attenuation** (the sources and the tests holding the values to them:
//! `src/published_acoustics.rs`, `docs/imaging-sources.md`): muscle 0.7,
//! across the fibres as the transverse section sees it, within 0.55
//! (bovine muscle, 4 MHz) to 0.96 (Diagnostics 13(5):855, 2023, table 4);
//! fat 0.63, skin 0.35, blood 0.15 and fascia 1.57 (connective tissue),
//! the values of that table; cortical bone 15, its "bone" (Sensors
//! 23(13):5942, 2023, gives 1–10 for cortical bone). Vessel walls 0.8
//! have no source.
//!
//! **Backscatter** (echo relative to muscle): estimates that reproduce the
//! B-mode appearance described in clinical texts, not measured levels —
//! dermis hyperechoic, fat hypoechoic with echogenic septa, fascia bright,
//! muscle mid-grey with echogenic perimysium, blood anechoic, bone cortex
//! very bright with a shadow behind it (e.g. Rumack, "Diagnostic
//! Ultrasound", 5th ed., ch. 23; Lee et al. 2004, "Sonography of lower limb
//! muscle injury", AJR 182:341). No published backscatter coefficient of
//! human subcutaneous fat relative to muscle at 5–10 MHz was found.

/// A tissue class of the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Tissue {
    /// Coupling gel above the skin (no echo, no attenuation).
    Gel,
    /// Epidermis and dermis.
    Skin,
    /// Subcutaneous fat.
    Fat,
    /// Deep or intermuscular fascia.
    Fascia,
    /// Skeletal muscle.
    Muscle,
    /// Wall of the femoral vein.
    VeinWall,
    /// Lumen of the femoral vein (blood or thrombus, by vein state).
    VeinLumen,
    /// Wall of the femoral artery.
    ArteryWall,
    /// Lumen of the femoral artery (blood).
    ArteryLumen,
    /// Lumen of a patent vessel other than the studied vein (blood).
    Blood,
    /// Thrombus or fibrous content inside a vein's lumen (issue 13); its
    /// echo and attenuation are the vein's condition's
    /// ([`crate::VeinCondition`]); the values here are the acute defaults.
    Thrombus,
    /// Wall of a vein other than the studied one.
    VesselWall,
    /// Cortex of a lymph node (hypoechoic).
    NodeCortex,
    /// Fatty hilum of a lymph node (echogenic).
    NodeHilum,
    /// Femoral cortex.
    Cortex,
    /// Femoral marrow cavity (behind the cortex: never reached by the beam).
    Marrow,
}

/// Acoustic properties of one tissue class.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Acoustics {
    /// Mean backscattered intensity relative to muscle (dB); `None`: no scatterers.
    pub echo_db: Option<f64>,
    /// One-way attenuation slope (dB/(cm·MHz)).
    pub attenuation: f64,
}

impl Tissue {
    /// Properties of the classes that do not depend on the vein state
    /// (vein wall and lumen are set by [`crate::VeinStateParams`]).
    pub fn acoustics(self) -> Acoustics {
        let (echo, attenuation) = match self {
            Tissue::Gel => (None, 0.0),
            Tissue::Skin => (Some(8.0), 0.35),
            Tissue::Fat => (Some(-9.0), 0.63),
            Tissue::Fascia => (Some(12.0), 1.57),
            Tissue::Muscle => (Some(0.0), 0.7),
            Tissue::VeinWall => (Some(4.0), 0.8),
            Tissue::VeinLumen => (Some(-50.0), 0.15),
            Tissue::ArteryWall => (Some(6.0), 0.8),
            Tissue::ArteryLumen => (Some(-50.0), 0.15),
            Tissue::Blood => (Some(-50.0), 0.15),
            Tissue::Thrombus => (Some(-24.0), 0.3),
            Tissue::VesselWall => (Some(4.0), 0.8),
            // A normal node: a hypoechoic cortex (about 15 dB under muscle)
            // around an echogenic fatty hilum (brighter than muscle); e.g.
            // Ying & Ahuja 2003, "Sonography of neck lymph nodes", Clin
            // Radiol 58 — the same appearance as inguinal nodes.
            Tissue::NodeCortex => (Some(-15.0), 0.6),
            Tissue::NodeHilum => (Some(6.0), 0.6),
            // The bone–soft-tissue interface reflects ≈ 64 % of the incident
            // amplitude (published impedances give 0.55–0.69:
            // `published_acoustics`), far above tissue backscatter; the
            // cortex's attenuation confines its echo to the first
            // ≈ 0.27 mm (−6 dB), so the layer is set +35 dB (an estimate: the scale
            // on which the specular lines are set) to show as the
            // saturated white line of scans (only where it faces the beam:
            // `scatterers::specular_gain`).
            Tissue::Cortex => (Some(35.0), 15.0),
            // Never reached by the beam (no echo): its slope only has to
            // keep it dark.
            Tissue::Marrow => (None, 20.0),
        };
        Acoustics {
            echo_db: echo,
            attenuation,
        }
    }
}
