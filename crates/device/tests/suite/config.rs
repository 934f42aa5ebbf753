//! Configuration parsing and validation: every error names its key.

use echothigh_device::{
    ConfigError, DeviceConfig, ExamConfig, ExamScript, HandConfig, PhaseConfig, SimulatedDevice,
    SimulatedHand, Vec3,
};

fn key_of(e: &ConfigError) -> &str {
    let ConfigError::Invalid { key, .. } = e;
    key
}

/// Decodes `[exam]` from a scenario document as the scenario loader does
/// (serde; other sections are the other crates') and validates it: the
/// device crate parses no TOML itself.
fn exam_from_toml(text: &str) -> Result<ExamConfig, String> {
    #[derive(serde::Deserialize)]
    struct Doc {
        #[serde(default)]
        exam: ExamConfig,
    }
    let doc: Doc = toml::from_str(text).map_err(|e| e.to_string())?;
    doc.exam.validate("exam").map_err(|e| e.to_string())?;
    Ok(doc.exam)
}

#[test]
fn defaults_are_valid() {
    DeviceConfig::default().validate("device").unwrap();
    HandConfig::default().validate("hand").unwrap();
    ExamConfig::default().validate("exam").unwrap();
}

/// The device displays `scale × k_tissue`: its 1000 N/m limit at scale
/// 0.3 allows 3333 N/m of tissue stiffness.
#[test]
fn tissue_stiffness_limit_is_the_device_limit_over_the_scale() {
    let d = DeviceConfig::default();
    assert!((d.tissue_max_stiffness() - 1000.0 / 0.3).abs() < 1e-9);
    let firm = DeviceConfig {
        force_scale: 1.0,
        ..d
    };
    assert_eq!(firm.tissue_max_stiffness(), 1000.0);
}

#[test]
fn device_and_hand_errors_name_the_key() {
    let cases: [(DeviceConfig, &str); 5] = [
        (
            DeviceConfig {
                mass: 0.0,
                ..Default::default()
            },
            "device.mass",
        ),
        (
            DeviceConfig {
                viscous_friction: -1.0,
                ..Default::default()
            },
            "device.viscous_friction",
        ),
        (
            DeviceConfig {
                max_force: f64::NAN,
                ..Default::default()
            },
            "device.max_force",
        ),
        (
            DeviceConfig {
                substep_rate: 5000.0,
                ..Default::default()
            },
            "device.substep_rate",
        ),
        (
            DeviceConfig {
                force_scale: 0.0,
                ..Default::default()
            },
            "device.force_scale",
        ),
    ];
    for (cfg, key) in cases {
        let e = SimulatedDevice::new(cfg, Vec3::zeros()).unwrap_err();
        assert_eq!(key_of(&e), key);
        assert!(e.to_string().contains(key));
    }
    let e = SimulatedHand::new(
        HandConfig {
            stiffness: -300.0,
            ..Default::default()
        },
        Vec3::zeros(),
    )
    .unwrap_err();
    assert_eq!(key_of(&e), "hand.stiffness");
}

#[test]
fn exam_toml_round_trip_and_partial_override() {
    let text = r#"
        [device]
        mass = 0.1

        [exam]
        repeat = 3
        start = [0.0, 0.1, 0.1]

        [[exam.phases]]
        kind = "approach"
        point = [0.0, 0.08, 0.1]
        speed = 0.02

        [[exam.phases]]
        kind = "press"
        rate = 0.01
        target_force = 12.0
        max_depth = 0.02

        [[exam.phases]]
        kind = "release"
        speed = 0.05
        clearance = 0.0
    "#;
    let cfg = exam_from_toml(text).unwrap();
    assert_eq!(cfg.repeat, 3);
    assert_eq!(cfg.skin_point, ExamConfig::default().skin_point);
    assert_eq!(cfg.phases.len(), 3);
    assert_eq!(
        cfg.phases[1],
        PhaseConfig::Press {
            rate: 0.01,
            target_force: 12.0,
            max_depth: 0.02
        }
    );
    // Serialize and parse back.
    let mut doc = toml::Table::new();
    doc.insert("exam".into(), toml::Value::try_from(&cfg).unwrap());
    let back = toml::to_string(&doc).unwrap();
    let again = exam_from_toml(&back).unwrap_or_else(|e| panic!("{e}\n{back}"));
    assert_eq!(again, cfg);
    // No [exam] at all: the default script.
    assert_eq!(
        exam_from_toml("[hand]\nmass = 1.0\n").unwrap(),
        ExamConfig::default()
    );
    assert!(ExamScript::new(exam_from_toml(text).unwrap()).is_ok());
}

fn parse_err(text: &str) -> String {
    exam_from_toml(text).unwrap_err()
}

#[test]
fn exam_parse_errors_name_the_key() {
    let e = parse_err("[exam]\nrepet = 2\n");
    assert!(e.contains("repet"), "{e}");
    let e = parse_err("[exam]\n[[exam.phases]]\nkind = \"hold\"\nduration = 1.0\nspeed = 2.0\n");
    assert!(e.contains("speed"), "{e}");
    let e =
        parse_err("[exam]\n[[exam.phases]]\nkind = \"press\"\nrate = 0.01\ntarget_force = 5.0\n");
    assert!(e.contains("max_depth"), "{e}");
    let e = parse_err("[exam]\n[[exam.phases]]\nkind = \"jump\"\n");
    assert!(e.contains("jump"), "{e}");
    let e = parse_err("[exam]\nrepeat = \"two\"\n");
    assert!(e.contains("repeat") || e.contains("two"), "{e}");
}

#[test]
fn exam_validation_errors_name_the_key() {
    let with = |f: &dyn Fn(&mut ExamConfig)| {
        let mut c = ExamConfig::default();
        f(&mut c);
        ExamScript::new(c).unwrap_err()
    };
    assert_eq!(key_of(&with(&|c| c.repeat = 0)), "exam.repeat");
    assert_eq!(key_of(&with(&|c| c.phases.clear())), "exam.phases");
    assert_eq!(
        key_of(&with(&|c| c.press_direction = [0.0; 3])),
        "exam.press_direction"
    );
    assert_eq!(
        key_of(&with(&|c| c.start[1] = f64::INFINITY)),
        "exam.start[1]"
    );
    assert_eq!(
        key_of(&with(&|c| c.phases[0] = PhaseConfig::Approach {
            point: [0.0, 0.06, 0.15],
            speed: 0.05
        })),
        "exam.phases[0].point"
    );
    assert_eq!(
        key_of(&with(&|c| c.phases[1] = PhaseConfig::Press {
            rate: 0.01,
            target_force: -1.0,
            max_depth: 0.02
        })),
        "exam.phases[1].target_force"
    );
    assert_eq!(
        key_of(&with(
            &|c| c.phases[2] = PhaseConfig::Hold { duration: f64::NAN }
        )),
        "exam.phases[2].duration"
    );
    assert_eq!(
        key_of(&with(&|c| c.phases[3] = PhaseConfig::Slide {
            direction: [0.0, 1.0, 0.0],
            distance: 0.02,
            speed: 0.01
        })),
        "exam.phases[3].direction"
    );
    assert_eq!(
        key_of(&with(&|c| c.phases[5] = PhaseConfig::Release {
            speed: 0.0,
            clearance: 0.005
        })),
        "exam.phases[5].speed"
    );
    let e = exam_from_toml("[exam]\nrepeat = 0\n").unwrap_err();
    assert!(e.to_string().contains("exam.repeat"), "{e}");
}

/// The phase decoder's errors (`exam.phases[i].field`), moved from the
/// crate's unit tests when the crate stopped parsing TOML itself.
mod phases {

    fn err(text: &str) -> String {
        super::exam_from_toml(text).unwrap_err()
    }

    const HEAD: &str = "[exam]\nrepeat = 1\n";
    const PHASE0: &str = "[[exam.phases]]\nkind = \"hold\"\nduration = 1.0\n";

    /// Regression (issue 20): an error inside the fourth phase named
    /// neither the phase nor the field.
    #[test]
    fn a_wrong_type_in_phase_3_names_phase_and_field() {
        let text = format!(
            "{HEAD}{PHASE0}{PHASE0}{PHASE0}[[exam.phases]]\nkind = \"release\"\n\
             speed = \"fast\"\nclearance = 0.005\n"
        );
        let e = err(&text);
        assert!(e.contains("exam.phases[3].speed"), "{e}");
        assert!(e.contains("expected a number, found string"), "{e}");
    }

    #[test]
    fn missing_unknown_and_extra_elements_are_named() {
        let e = err(&format!("{HEAD}{PHASE0}[[exam.phases]]\nkind = \"hold\"\n"));
        assert!(
            e.contains("exam.phases[1]") && e.contains("duration"),
            "{e}"
        );
        let e = err(&format!(
            "{HEAD}[[exam.phases]]\nkind = \"hold\"\nduration = 1\nsped = 2\n"
        ));
        assert!(e.contains("exam.phases[0]") && e.contains("sped"), "{e}");
        let e = err(&format!(
            "{HEAD}[[exam.phases]]\nkind = \"slide\"\ndirection = [0, 0, 1, 5]\n\
             distance = 0.01\nspeed = 0.01\n"
        ));
        assert!(
            e.contains("exam.phases[0].direction: expected exactly 3 numbers, found 4"),
            "{e}"
        );
        let e = err(&format!("{HEAD}[[exam.phases]]\nkind = \"jump\"\n"));
        assert!(e.contains("exam.phases[0]") && e.contains("jump"), "{e}");
        let e = err("[exam]\nstart = [0.0, 0.09, 0.0, 99.0]\n");
        assert!(e.contains("start") || e.contains("3 numbers"), "{e}");
    }

    /// A value out of its documented range is refused naming the phase.
    #[test]
    fn out_of_range_phase_values_are_refused_by_key() {
        let e = err(&format!(
            "{HEAD}[[exam.phases]]\nkind = \"hold\"\nduration = 1e308\n"
        ));
        assert!(e.contains("exam.phases[0].duration"), "{e}");
        let e = err(&format!(
            "{HEAD}[[exam.phases]]\nkind = \"press\"\nrate = 0.04\ntarget_force = 1e9\n\
             max_depth = 0.02\n"
        ));
        assert!(e.contains("exam.phases[0].target_force"), "{e}");
    }
}
