//! Published acoustic properties of the thigh's tissues, and the tests that
//! hold the image's levels to them (issue 21; the table of every level and
//! its source is `docs/imaging-sources.md`).
//!
//! Sources (each range below is the span of the values they give):
//! - **[T3]** Table 3 of "Mech. Mater. 44 (2012) 174–188"
//!   (doi:10.1016/j.mechmat.2011.08.007, PMC3233242), densities and speeds
//!   of sound compiled from Goldman & Richards 1954, Goss et al. 1978, 1980,
//!   Mast 2000 and others: fat 950 kg/m³, 1468–1488 m/s; muscle 1050 kg/m³,
//!   1517–1600 m/s; tendon 1130 kg/m³, 1654–1852 m/s; cortical bone
//!   1800–2200 kg/m³, 3200–4000 m/s.
//! - **[B25]** Appendix A of "Experimental validation of time-explicit
//!   ultrasound propagation models …", Bioengineering 12(9):946 (2025),
//!   measured ex vivo: adipose 927 kg/m³, 1461.8 m/s; skeletal muscle
//!   1058 kg/m³, 1562.2 m/s across the fibres (1598.7 along); tendon
//!   1121 kg/m³, 1827.4 m/s; ligament 1101 kg/m³, 1663.7 m/s; cortical bone
//!   1862 kg/m³, 3194 m/s.
//! - **[S23]** Table A2 of Sensors 23(13):5942 (2023, PMC10346919):
//!   attenuation fat 0.8, muscle 1.2, cortical bone 1–10 dB/(cm·MHz).
//! - **[D23]** Table 4 of Diagnostics 13(5):855 (2023,
//!   doi:10.3390/diagnostics13050855), attenuation at 1 MHz (dB/cm): blood
//!   0.15, skin 0.35, adipose 0.63, skeletal muscle 0.96 across the fibres
//!   (1.40 along), connective tissue 1.57, bone 15.
//! - **[BM]** "Attenuation of ultrasound in post rigor bovine skeletal
//!   muscle", Ultrasonics (1–7 MHz): 0.55 dB/(cm·MHz) across the fibres,
//!   1.3 along, at 4 MHz and 20 °C.
//!
//! Amplitude reflection coefficient at normal incidence between media of
//! acoustic impedances `Z₁ < Z₂` (kg/(m²·s)): `R = (Z₂ − Z₁)/(Z₂ + Z₁)`
//! (Szabo 2014, "Diagnostic Ultrasound Imaging: Inside Out", ch. 3).

use crate::reverberation::{ReverbConfig, BONE_REFLECTION};
use crate::specular::Interface;
use crate::tissue::Tissue;

/// Published span of a tissue's density (kg/m³) and speed of sound (m/s).
struct Published {
    density: (f64, f64),
    speed: (f64, f64),
}

impl Published {
    /// Span of the acoustic impedance `ρ c` (kg/(m²·s)).
    fn impedance(&self) -> (f64, f64) {
        (self.density.0 * self.speed.0, self.density.1 * self.speed.1)
    }
}

/// Subcutaneous fat: [T3] and [B25].
const FAT: Published = Published {
    density: (927.0, 950.0),
    speed: (1461.0, 1488.0),
};
/// Skeletal muscle: [T3] and [B25] (across and along the fibres).
const MUSCLE: Published = Published {
    density: (1050.0, 1058.0),
    speed: (1517.0, 1600.0),
};
/// Dense collagenous tissue (fascia, adventitia, septa): tendon and
/// ligament of [T3] and [B25].
const COLLAGEN: Published = Published {
    density: (1101.0, 1130.0),
    speed: (1654.0, 1852.0),
};
/// Cortical bone: [T3] and [B25].
const CORTICAL_BONE: Published = Published {
    density: (1800.0, 2200.0),
    speed: (3194.0, 4000.0),
};

/// Span of the amplitude reflection coefficient between `soft` and the
/// harder `hard` (the module's formula at the spans' opposite corners).
fn reflection(soft: &Published, hard: &Published) -> (f64, f64) {
    let (s, h) = (soft.impedance(), hard.impedance());
    assert!(h.0 > s.1, "the spans overlap: R would reach 0");
    ((h.0 - s.1) / (h.0 + s.1), (h.1 - s.0) / (h.1 + s.0))
}

/// Level (dB re muscle speckle) of a specular interface of reflection `r`
/// on the model's scale: the cortex's echo ([`Tissue::Cortex`]) stands for
/// reflection [`BONE_REFLECTION`], and echoes scale as `R`.
fn level_db(r: f64) -> f64 {
    let cortex = Tissue::Cortex.acoustics().echo_db.unwrap_or(0.0);
    cortex + 20.0 * (r / BONE_REFLECTION).log10()
}

#[test]
fn the_bone_reflection_lies_in_the_published_range() {
    // Muscle on cortical bone, [T3] and [B25]: R from 0.545 to 0.693.
    // No tolerance: the published spread is the range.
    let (lo, hi) = reflection(&MUSCLE, &CORTICAL_BONE);
    assert!(
        (lo..=hi).contains(&BONE_REFLECTION),
        "{BONE_REFLECTION} not in {lo:.3}–{hi:.3}"
    );
}

#[test]
fn the_soft_tissue_reflection_lies_in_the_published_range() {
    // The soft-tissue interfaces of the reverberation (fascia, septa,
    // adventitia against fat) lie between fat on muscle (the weakest,
    // R ≥ 0.060) and fat on dense collagen (the strongest, R ≤ 0.214).
    let weakest = reflection(&FAT, &MUSCLE).0;
    let strongest = reflection(&FAT, &COLLAGEN).1;
    let r = ReverbConfig::default().interface_reflection;
    assert!(
        (weakest..=strongest).contains(&r),
        "{r} not in {weakest:.3}–{strongest:.3}"
    );
}

#[test]
fn the_specular_levels_follow_the_published_reflections() {
    // A fascia, a vein's wall and an artery's adventitia are collagen
    // sheets against fat or muscle: on the cortex's scale, R from 0.060 to
    // 0.214 puts their lines between +14.4 and +25.5 dB re muscle. The
    // lumen–intima line is an estimate (no published impedance of the
    // intima was found), checked only to be the weaker of the double line.
    let lo = level_db(reflection(&FAT, &MUSCLE).0);
    let hi = level_db(reflection(&FAT, &COLLAGEN).1);
    for kind in [
        Interface::Fascia,
        Interface::VeinWall,
        Interface::Adventitia,
    ] {
        let l = kind.level_db();
        assert!(
            (lo..=hi).contains(&l),
            "{kind:?}: {l} not in {lo:.1}–{hi:.1}"
        );
    }
    assert!(Interface::Intima.level_db() < Interface::Adventitia.level_db());
}

#[test]
fn the_attenuation_slopes_lie_in_the_published_ranges() {
    // dB/(cm·MHz), one way. Muscle across the fibres (the transverse
    // section): [BM] 0.55 to [D23] 0.96. Fat: [D23] 0.63 to [S23] 0.8.
    // Blood, skin, fascia (connective tissue): the single values of [D23].
    // Cortical bone: [S23] 1–10 to [D23] 15.
    let cases = [
        (Tissue::Muscle, 0.55, 0.96),
        (Tissue::Fat, 0.63, 0.8),
        (Tissue::Blood, 0.15, 0.15),
        (Tissue::ArteryLumen, 0.15, 0.15),
        (Tissue::Skin, 0.35, 0.35),
        (Tissue::Fascia, 1.57, 1.57),
        (Tissue::Cortex, 1.0, 15.0),
    ];
    for (t, lo, hi) in cases {
        let a = t.acoustics().attenuation;
        assert!((lo..=hi).contains(&a), "{t:?}: {a} not in {lo}–{hi}");
    }
}
