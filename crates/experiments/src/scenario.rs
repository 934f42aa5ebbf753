//! The default scenario of the experiments, `scenarios/fig4.toml`, embedded
//! in the binary (its comments document the physical plausibility of every
//! choice, with sources).

use anyhow::Result;
use echothigh_runtime::scenario::Scenario;
use std::path::Path;

/// The text of `scenarios/fig4.toml`.
pub const FIG4_TOML: &str = include_str!("../../../scenarios/fig4.toml");

/// The embedded default fig4 scenario, parsed and validated.
pub fn default_fig4() -> Result<Scenario> {
    Scenario::from_toml_str(FIG4_TOML, "scenarios/fig4.toml (embedded)")
}

/// The scenario of `path`, or the embedded fig4 scenario when `None`.
pub fn load_fig4(path: Option<&Path>) -> Result<Scenario> {
    match path {
        None => default_fig4(),
        Some(p) => Scenario::load(Some(p)),
    }
}
