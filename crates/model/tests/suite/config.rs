//! Configuration: defaults, TOML parsing, and errors that name the key.

use echothigh_model::{ConfigError, ModelConfig, ThighModel};
use serde::Deserialize;

/// Why a document was refused: it does not decode (serde), or a value is
/// out of range (validation).
#[derive(Debug)]
enum ParseError {
    Decode(String),
    Invalid(ConfigError),
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParseError::Decode(m) => f.write_str(m),
            ParseError::Invalid(e) => write!(f, "{e}"),
        }
    }
}

/// Decodes and validates a `[thigh]`/`[tissue]`/`[integrator]` document as
/// the scenario loader does (the model crate parses no TOML itself).
fn from_toml(text: &str) -> Result<ModelConfig, ParseError> {
    let c: ModelConfig = toml::from_str(text).map_err(|e| ParseError::Decode(e.to_string()))?;
    c.validate("").map_err(ParseError::Invalid)?;
    Ok(c)
}

fn key_of(text: &str) -> String {
    match from_toml(text) {
        Err(ParseError::Invalid(ConfigError::Invalid { key, .. })) => key,
        other => panic!("expected an Invalid error for {text:?}, got {other:?}"),
    }
}

#[test]
fn defaults_are_valid_and_plausible() {
    let c = ModelConfig::default();
    c.validate("").unwrap();
    assert_eq!(from_toml("").unwrap(), c);
    let m = ThighModel::new(&c).unwrap();
    assert_eq!(m.node_count(), 48 * 21);
    // Circumference of the default ellipse ≈ 0.48 m; mass ≈ areal density × area.
    let area: f64 = m.mesh().areas().iter().sum();
    assert!((area / c.thigh.length - 0.48).abs() < 0.01, "{area}");
    let mass: f64 = m.masses().iter().sum();
    assert!((mass - area * c.tissue.areal_density).abs() < 1e-12);
    assert!(c.tissue.asymptote() < c.thigh.tissue_thickness);
}

#[test]
fn parses_partial_sections() {
    let c = from_toml(
        "[thigh]\nn_theta = 32\nhold_ends = false\n[tissue]\nnormal_b = 1.0e-6\n\
         [integrator]\nlambda = 0.5\npreconditioner = \"none\"\n",
    )
    .unwrap();
    assert_eq!(c.thigh.n_theta, 32);
    assert!(!c.thigh.hold_ends);
    assert_eq!(c.tissue.normal_b, 1.0e-6);
    assert_eq!(c.integrator.lambda, 0.5);
    assert_eq!(c.thigh.n_z, 21); // default kept
}

#[test]
fn invalid_values_name_their_key() {
    assert_eq!(
        key_of("[tissue]\nareal_density = -1.0"),
        "tissue.areal_density"
    );
    assert_eq!(key_of("[integrator]\nlambda = 1.5"), "integrator.lambda");
    assert_eq!(key_of("[integrator]\nlambda = -0.1"), "integrator.lambda");
    assert_eq!(key_of("[tissue]\nnormal_a = nan"), "tissue.normal_a");
    assert_eq!(key_of("[thigh]\nlength = inf"), "thigh.length");
    assert_eq!(key_of("[thigh]\nn_z = 2"), "thigh.n_z");
    assert_eq!(
        key_of("[integrator]\nasymptote_margin = 1.0"),
        "integrator.asymptote_margin"
    );
    assert_eq!(
        key_of("[integrator]\ncg_max_iterations = 0"),
        "integrator.cg_max_iterations"
    );
    assert_eq!(
        key_of("[tissue]\ngravity = [0.0, nan, 0.0]"),
        "tissue.gravity[1]"
    );
    // Asymptote b/a = 0.05 m beyond the 0.04 m rest length.
    assert_eq!(
        key_of("[tissue]\nnormal_a = 2.0e-5\nnormal_b = 1.0e-6"),
        "tissue.normal_b"
    );
    // Anchors inside the femur.
    assert_eq!(
        key_of("[thigh]\ntissue_thickness = 0.065"),
        "thigh.tissue_thickness"
    );
    // Message format.
    let e = from_toml("[tissue]\nareal_density = -1.0").unwrap_err();
    assert_eq!(
        e.to_string(),
        "tissue.areal_density must be in [1, 200] kg/m² (soft tissue ~1000 kg/m³ over 1 mm \
         to 0.2 m), got -1.0"
    );
}

#[test]
fn unknown_keys_and_wrong_types_are_rejected_with_their_name() {
    let e = from_toml("[tissue]\nnode_mas = 1.0").unwrap_err();
    assert!(matches!(e, ParseError::Decode(_)));
    assert!(e.to_string().contains("node_mas"), "{e}");
    let e = from_toml("[thigh]\nn_theta = -3").unwrap_err();
    assert!(e.to_string().contains("n_theta"), "{e}");
    let e = from_toml("[solver]\nx = 1").unwrap_err();
    assert!(e.to_string().contains("solver"), "{e}");
}

#[test]
fn sections_embed_in_a_larger_scenario_with_a_prefix() {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Scenario {
        #[serde(default)]
        model: ModelConfig,
        #[serde(default)]
        tissue: echothigh_model::TissueParams,
    }
    let s: Scenario = toml::from_str("[model.integrator]\nlambda = 2.0\n[tissue]\n").unwrap();
    let e = s.model.validate("model").unwrap_err();
    assert_eq!(
        e.to_string().split(' ').next(),
        Some("model.integrator.lambda")
    );
    s.tissue.validate("tissue").unwrap();
}

#[test]
fn round_trips_through_toml() {
    let c = ModelConfig::default();
    let text = toml::to_string(&c).unwrap();
    assert_eq!(from_toml(&text).unwrap(), c);
}

/// Regression (issue 20): values that passed the sign checks but no
/// physical range (a 1e308 m thigh, λ below ½ where the scheme is unstable,
/// 1e9 Newton iterations) are refused naming the key, the range, its unit
/// and its reason.
#[test]
fn physically_absurd_values_are_refused_with_range_unit_and_reason() {
    let e = from_toml("[thigh]\nlength = 1e308").unwrap_err();
    assert_eq!(
        e.to_string(),
        "thigh.length must be in [0.1, 1] m (a human thigh segment), got 1e308"
    );
    let e = from_toml("[integrator]\nlambda = 0.49").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("integrator.lambda must be in [0.5, 1]"),
        "{e}"
    );
    assert!(e.to_string().contains("unconditionally stable"), "{e}");
    let e = from_toml("[integrator]\nnewton_max_iterations = 1000000000").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("integrator.newton_max_iterations must be in [1, 100]"),
        "{e}"
    );
    let e = from_toml("[thigh]\nfemur_offset = [0.0, -0.01, 99.0]").unwrap_err();
    assert!(e.to_string().contains("exactly 2 numbers"), "{e}");
    assert!(from_toml("[integrator]\nlambda = 0.5").is_ok());
}
