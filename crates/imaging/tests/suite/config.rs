//! The `[imaging]` section: TOML round trip, unknown keys and bad values
//! are named.

use echothigh_imaging::*;

#[test]
fn defaults_validate_and_round_trip() {
    let cfg = ImagingConfig::default();
    cfg.validate("imaging").unwrap();
    let text = toml::to_string(&cfg).unwrap();
    let back: ImagingConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, cfg);
    let partial: ImagingConfig =
        toml::from_str("columns = 128\n[anatomy]\nvein_diameter = 0.009\n").unwrap();
    assert_eq!(partial.columns, 128);
    assert_eq!(partial.anatomy.vein_diameter, 0.009);
    assert_eq!(partial.rows, 864);
}

#[test]
fn unknown_keys_are_rejected() {
    let e = toml::from_str::<ImagingConfig>("colums = 128\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("colums"), "{e}");
    let e = toml::from_str::<ImagingConfig>("[anatomy.healthy]\ndiameter_factor = 1.0\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("missing field") || e.contains("wall_thickness"),
        "{e}"
    );
    let v: VeinState = toml::from_str::<toml::Table>("s = \"acute\"").unwrap()["s"]
        .clone()
        .try_into()
        .unwrap();
    assert_eq!(v, VeinState::Acute);
    assert!("Chronic".parse::<VeinState>().is_ok());
    assert!("old"
        .parse::<VeinState>()
        .unwrap_err()
        .to_string()
        .contains("old"));
}

#[test]
fn bad_values_name_their_key() {
    let cases: Vec<(ImagingConfig, &str)> = vec![
        (
            ImagingConfig {
                columns: 2,
                ..Default::default()
            },
            "imaging.columns",
        ),
        (
            ImagingConfig {
                depth: f64::NAN,
                ..Default::default()
            },
            "imaging.depth",
        ),
        (
            ImagingConfig {
                beam: BeamConfig {
                    transmit_focus: -0.02,
                    ..Default::default()
                },
                ..Default::default()
            },
            "imaging.beam.transmit_focus",
        ),
        (
            ImagingConfig {
                dynamic_range: 300.0,
                ..Default::default()
            },
            "imaging.dynamic_range",
        ),
        (
            ImagingConfig {
                scatterer_density: 1e12,
                ..Default::default()
            },
            "imaging.scatterer_density",
        ),
        (
            {
                let mut c = ImagingConfig::default();
                c.anatomy.vein_depth = 0.005;
                c
            },
            "imaging.anatomy.vein_depth",
        ),
        (
            {
                let mut c = ImagingConfig::default();
                c.anatomy.acute.collapse_full = 0.0;
                c
            },
            "imaging.anatomy.acute.collapse_full",
        ),
        (
            {
                let mut c = ImagingConfig::default();
                c.anatomy.healthy.min_lumen_ratio = 1.5;
                c
            },
            "imaging.anatomy.healthy.min_lumen_ratio",
        ),
    ];
    for (cfg, key) in cases {
        let e = cfg.validate("imaging").unwrap_err().to_string();
        assert!(e.contains(&format!("`{key}`")), "{key}: {e}");
        assert!(Renderer::new(&cfg, VeinState::Healthy).is_err());
    }
    // Per-frame input errors are typed, not panics.
    let mut r = Renderer::new(
        &ImagingConfig {
            columns: 64,
            rows: 160,
            ..Default::default()
        },
        VeinState::Healthy,
    )
    .unwrap();
    let d = SectionDeformation::rest(0.04);
    let mut out = vec![0u8; 10];
    let input = FrameInput {
        deformation: &d,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    };
    assert!(r
        .render_into(&input, &mut out)
        .unwrap_err()
        .to_string()
        .contains("out"));
    let bad = FrameInput {
        deformation: &d,
        probe_pressure: f64::NAN,
        time: 0.0,
        lateral_offset: 0.0,
    };
    assert!(r
        .render(&bad)
        .unwrap_err()
        .to_string()
        .contains("probe_pressure"));
}
