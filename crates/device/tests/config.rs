//! Configuration parsing and validation: every error names its key.

use echothigh_device::{
    ConfigError, DeviceConfig, ExamConfig, ExamScript, HandConfig, PhaseConfig, SimulatedDevice,
    SimulatedHand, Vec3,
};

fn key_of(e: &ConfigError) -> &str {
    match e {
        ConfigError::Invalid { key, .. } => key,
        ConfigError::Parse { .. } => panic!("expected a validation error, got {e}"),
    }
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
    let cfg = ExamConfig::from_toml_str(text).unwrap();
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
    let again = ExamConfig::from_toml_str(&back).unwrap_or_else(|e| panic!("{e}\n{back}"));
    assert_eq!(again, cfg);
    // No [exam] at all: the default script.
    assert_eq!(
        ExamConfig::from_toml_str("[hand]\nmass = 1.0\n").unwrap(),
        ExamConfig::default()
    );
    assert!(ExamScript::from_toml_str(text).is_ok());
}

fn parse_err(text: &str) -> String {
    ExamConfig::from_toml_str(text).unwrap_err().to_string()
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
    let e = ExamConfig::from_toml_str("[exam]\nrepeat = 0\n").unwrap_err();
    assert!(e.to_string().contains("exam.repeat"), "{e}");
}
