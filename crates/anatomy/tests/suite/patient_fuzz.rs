//! A repeatable fuzz/property harness for the patient loader (issue 20):
//! arbitrary text never panics it; a preset with any key set to any number
//! (NaN, ±∞, negative, 0, huge, plausible) is either refused with an error
//! naming that key, or gives an anatomy whose sections along the whole leg
//! are finite; the same for the built anatomy and its sections.
//!
//! Cases per property: `PATIENT_FUZZ_CASES` (default 256), so a later run
//! can go deeper: `PATIENT_FUZZ_CASES=20000 cargo test -p
//! echothigh-anatomy --release --test suite patient_fuzz::`.

use echothigh_anatomy::{Anatomy, Patient, ProbePose, PRESETS};
use proptest::prelude::*;

fn cases() -> u32 {
    std::env::var("PATIENT_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

/// The numeric keys of a patient file (those of the preset's table).
const NUMERIC_KEYS: [&str; 21] = [
    "knee_s",
    "length",
    "circumference_groin",
    "circumference_mid",
    "circumference_distal",
    "circumference_knee",
    "ap_ratio",
    "skin_thickness",
    "fat_thickness_proximal",
    "fat_thickness_distal",
    "muscle_depth_scale",
    "femur_obliquity_deg",
    "cfv_diameter",
    "fv_diameter_mid",
    "gsv_diameter_sfj",
    "gsv_diameter_thigh",
    "vein_artery_ratio_groin",
    "vein_artery_ratio_below",
    "stiffness_scale",
    // Booleans given a number are a type error naming the key too.
    "tense_muscle",
    "lymph_node",
];

fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("0.0".to_string()),
        Just("1e308".to_string()),
        Just("-1e-3".to_string()),
        (-2.0f64..2.0).prop_map(|v| format!("{v:e}")),
        (0.0f64..1.0).prop_map(|v| format!("{v:e}")),
        (1e-6f64..1e3).prop_map(|v| format!("{v:e}")),
        "\"[a-z]{0,6}\"".prop_map(|s| s),
    ]
}

/// Sections every 10 mm along the leg, at three angles: each number finite.
fn sections_are_finite(a: &Anatomy) -> Result<(), String> {
    let n = (a.length() / 0.01).floor() as usize;
    for i in 0..=n {
        let s = (i as f64 * 0.01).min(a.length());
        for theta in [-0.8, 0.0, 0.8] {
            let Ok(sec) = a.section(&ProbePose::transverse(s, theta)) else {
                continue; // a refusal is an answer; a panic or a NaN is not
            };
            if !sec.skin_depth.is_finite() {
                return Err(format!("skin depth {} at s = {s}", sec.skin_depth));
            }
            for st in &sec.structures {
                let e = format!("{:?}", st.ellipse);
                if e.contains("NaN") || e.contains("inf") || !st.s.is_finite() {
                    return Err(format!("{:?} at s = {s}: {e}", st.id));
                }
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,300}") {
        if let Ok(p) = Patient::from_toml_str(&text) {
            if let Ok(a) = Anatomy::new(p) {
                prop_assert!(sections_are_finite(&a).is_ok());
            }
        }
    }

    #[test]
    fn any_value_of_any_key_is_refused_by_name_or_gives_a_finite_leg(
        preset in prop::sample::select(PRESETS.to_vec()),
        key in prop::sample::select(NUMERIC_KEYS.to_vec()),
        v in value(),
    ) {
        let text = format!("preset = \"{preset}\"\n{key} = {v}\n");
        match Patient::from_toml_str(&text) {
            Err(e) => prop_assert!(
                e.to_string().contains(key),
                "{text}: the error does not name {key}: {e}"
            ),
            Ok(p) => match Anatomy::new(p) {
                // A leg the value makes impossible names what places it.
                Err(e) => prop_assert!(!e.to_string().is_empty()),
                Ok(a) => {
                    let r = sections_are_finite(&a);
                    prop_assert!(r.is_ok(), "{text}: {}", r.unwrap_err());
                }
            },
        }
    }
}
