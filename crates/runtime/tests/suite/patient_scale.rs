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
        // exam force (35–50 N): the scale is lowered to exactly cover it.
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
    // 30 N at 0.3 stands for 100 N of tissue force, beyond the obese 50 N.
    s.device.max_force = 30.0;
    assert_eq!(s.device().force_scale, 0.3);
}

#[test]
fn the_papers_experiment_and_the_cylinder_keep_the_configured_scale() {
    let fig4 = Scenario::from_toml_str(
        include_str!("../../../../scenarios/fig4.toml"),
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

/// A real device's own peak force sets the scale (issue 12): a Touch's
/// 3.3 N is scaled to stand for the lean leg's 36 N exam force; an
/// omega.6's 12 N at the configured 0.3 already renders 40 N and keeps
/// it; a peak that is not a positive, finite force is refused, naming it.
#[test]
fn a_real_devices_peak_sets_the_scale() {
    for peak in [3.3, 12.0] {
        let mut s = on("lean-male");
        s.set_device_peak(peak).unwrap();
        let d = s.device();
        assert_eq!(d.max_force, peak);
        let exam = Patient::preset("lean-male").unwrap().exam_force;
        let want = s.device.force_scale.min(peak / exam);
        assert!(
            (d.force_scale - want).abs() < 1e-12,
            "{peak} N: {}",
            d.force_scale
        );
        assert!(d.max_force / d.force_scale >= exam - 1e-9, "{peak} N");
    }
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut s = on("lean-male");
        let e = s.set_device_peak(bad).unwrap_err().to_string();
        assert!(e.contains("peak force"), "{e}");
    }
}
