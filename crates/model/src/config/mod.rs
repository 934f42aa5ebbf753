//! Configuration of the physical model: the `[thigh]`, `[tissue]` and
//! `[integrator]` sections of a scenario file.
//!
//! Every struct is `serde` (de)serializable with `deny_unknown_fields` and
//! defaults for every field, so each can be embedded as a field of a larger
//! scenario struct. [`ModelConfig`] bundles the three and checks the
//! constraints that span sections (the normal springs' asymptote must be
//! shorter than their rest length).

mod geometry;
mod integrator;
mod tissue;
mod window;

pub use geometry::ThighGeometry;
pub use integrator::IntegratorParams;
pub use tissue::TissueParams;
pub use window::WindowParams;

use serde::{Deserialize, Serialize};

/// An invalid configuration: names the offending key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// A value is out of its allowed range (message names the key and the value).
    #[error("{key} {message}")]
    Invalid {
        /// Dotted key, e.g. `tissue.areal_density`.
        key: String,
        /// What is wrong, e.g. `must be > 0, got -1`.
        message: String,
    },
}

impl ConfigError {
    /// An [`ConfigError::Invalid`] for `key`.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigError::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// Joins a prefix and a field name into a dotted key (`""` + `a` = `a`).
pub(crate) fn key(prefix: &str, field: &str) -> String {
    if prefix.is_empty() {
        field.to_string()
    } else {
        format!("{prefix}.{field}")
    }
}

/// Deserializes a fixed-size array of exactly `N` numbers. serde's own
/// `[f64; N]` reads the first `N` elements and, with the TOML decoder,
/// silently drops any more (`femur_offset = [0, -0.01, 99]` was accepted);
/// here a sequence of another length is an error naming its length.
pub(crate) fn exact_array<'de, D, const N: usize>(d: D) -> Result<[f64; N], D::Error>
where
    D: serde::Deserializer<'de>,
{
    use serde::de::Error;
    let v = <Vec<f64> as Deserialize>::deserialize(d)?;
    let len = v.len();
    v.try_into()
        .map_err(|_| D::Error::invalid_length(len, &format!("exactly {N} numbers").as_str()))
}

/// Checks `lo <= value <= hi` (NaN fails), stating the unit and the reason
/// for the range in the message, e.g. `thigh.length must be in [0.1, 1] m (a
/// human thigh segment), got 1e308`.
pub(crate) fn range(
    prefix: &str,
    field: &str,
    value: f64,
    (lo, hi): (f64, f64),
    unit: &str,
    why: &str,
) -> Result<(), ConfigError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key(prefix, field),
            format!(
                "must be in [{lo}, {hi}]{}{unit} ({why}), got {value:?}",
                sp(unit)
            ),
        ))
    }
}

/// A space before a non-empty unit.
fn sp(unit: &str) -> &'static str {
    if unit.is_empty() {
        ""
    } else {
        " "
    }
}

/// Checks `lo <= value <= hi` for an integer count, with the reason.
pub(crate) fn count_range(
    prefix: &str,
    field: &str,
    value: u64,
    (lo, hi): (u64, u64),
    why: &str,
) -> Result<(), ConfigError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key(prefix, field),
            format!("must be in [{lo}, {hi}] ({why}), got {value}"),
        ))
    }
}

/// Checks `lo <= value <= hi` (NaN fails).
pub(crate) fn in_range(
    prefix: &str,
    field: &str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<(), ConfigError> {
    if value >= lo && value <= hi {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key(prefix, field),
            format!("must be in [{lo}, {hi}], got {value:?}"),
        ))
    }
}

/// The physical model's whole configuration: `[thigh]`, `[tissue]`,
/// `[integrator]`. Serde types and validation only: the scenario loader
/// (`echothigh_runtime::scenario`) is the one place that parses TOML.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelConfig {
    /// Geometry and mesh resolution.
    pub thigh: ThighGeometry,
    /// Masses, springs and dampers.
    pub tissue: TissueParams,
    /// Implicit Euler, Newton and PCG settings.
    pub integrator: IntegratorParams,
}

impl ModelConfig {
    /// Validates every section (keys `{prefix}.thigh.*`, ...) and the
    /// cross-section constraint `tissue.normal_b / tissue.normal_a <
    /// thigh.tissue_thickness` (the asymptote of the normal springs must be
    /// reachable only by compressing less than their rest length).
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let thigh = key(prefix, "thigh");
        let tissue = key(prefix, "tissue");
        self.thigh.validate(&thigh)?;
        self.tissue.validate(&tissue)?;
        self.integrator.validate(&key(prefix, "integrator"))?;
        check_asymptote(&self.thigh, &self.tissue, &tissue)
    }
}

/// Checks that the normal springs' asymptote `b/a` (m) is shorter than their
/// rest length `thigh.tissue_thickness`; the error names `{tissue_prefix}.normal_b`.
pub fn check_asymptote(
    thigh: &ThighGeometry,
    tissue: &TissueParams,
    tissue_prefix: &str,
) -> Result<(), ConfigError> {
    let asymptote = tissue.normal_b / tissue.normal_a;
    if asymptote < thigh.tissue_thickness {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key(tissue_prefix, "normal_b"),
            format!(
                "gives an asymptote normal_b/normal_a = {asymptote} m that must be < \
                 thigh.tissue_thickness = {} m (the normal spring's rest length)",
                thigh.tissue_thickness
            ),
        ))
    }
}
