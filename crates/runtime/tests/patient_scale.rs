//! The force scale on a patient's leg (issue 12): `Scenario::device` lowers
//! `[device] force_scale` just enough that the device's peak force stands
//! for the patient's exam force, keeps it where the device already covers
//! it, and leaves it alone when `scale_to_patient = false` or on the paper's
//! elliptic cylinder. The forces each patient's exam needs are measured in
//! `coaptation_along_leg.rs`; this checks the rule that uses them.

use echothigh_anatomy::{Patient, PRESETS};
use echothigh_runtime::scenario::Scenario;

/// The built-in scenario on `preset`'s leg.
fn on(preset: &str) -> Scenario {
    let mut s = Scenario::builtin().unwrap();
    s.set_patient(&Patient::preset(preset).unwrap()).unwrap();
    s
}

#[test]
fn each_leg_is_rendered_up_to_its_exam_force_and_no_further() {
    for preset in PRESETS {
        let s = on(preset);
        let exam = Patient::preset(preset).unwrap().exam_force;
        let d = s.device();
        // The default 6 N device at 0.3 renders 20 N, below every preset's
        // exam force (35–49 N): the scale is lowered to exactly cover it.
        assert!(exam > s.device.max_force / s.device.force_scale, "{preset}");
        let renderable = d.max_force / d.force_scale;
        assert!(
            (renderable - exam).abs() < 1e-9,
            "{preset}: renders {renderable} N for an exam force of {exam} N"
        );
        // What the loops derive from it follows: the stiffness cap in
        // tissue units is the device's over the lowered scale.
        assert!((d.tissue_max_stiffness() - d.max_stiffness / d.force_scale).abs() < 1e-9);
        // Nothing else of the device changes.
        assert_eq!(
            echothigh_device::DeviceConfig {
                force_scale: s.device.force_scale,
                ..d
            },
            s.device
        );
    }
}

#[test]
fn a_device_that_covers_the_leg_keeps_its_scale() {
    let mut s = on("obese");
    // 30 N at 0.3 stands for 100 N of tissue force, beyond the obese 49 N.
    s.device.max_force = 30.0;
    assert_eq!(s.device().force_scale, 0.3);
}

#[test]
fn the_papers_experiment_and_the_cylinder_keep_the_configured_scale() {
    let fig4 = Scenario::from_toml_str(
        include_str!("../../../scenarios/fig4.toml"),
        "scenarios/fig4.toml",
    )
    .unwrap();
    assert!(!fig4.device.scale_to_patient);
    assert_eq!(fig4.device().force_scale, 0.3);
    let cylinder = Scenario::from_toml_str("[thigh]\npatient = \"\"\n", "cylinder").unwrap();
    assert!(cylinder.leg_patient().is_none());
    assert_eq!(cylinder.device().force_scale, 0.3);
}

#[test]
fn a_patient_file_with_a_bad_exam_force_is_refused_naming_it() {
    for bad in [
        "exam_force = 0.0",
        "exam_force = -5.0",
        "exam_force = 200.0",
        "exam_force = nan",
    ] {
        let e = Patient::from_toml_str(bad).unwrap_err().to_string();
        assert!(e.contains("exam_force"), "{bad}: {e}");
    }
}
