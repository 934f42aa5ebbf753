//! Decoding `[[exam.phases]]` so that an error names the phase and the field.
//!
//! `PhaseConfig` is an internally tagged enum (`kind = "press"`); serde
//! buffers such a table before choosing the variant, and a wrong type inside
//! it then comes out as "invalid type: string, expected f64" with neither
//! the phase nor the field named (the TOML decoder pointed at the first
//! phase). Here each phase is read as a plain table, its fields are checked
//! for shape (a number, or exactly three numbers for `point` and
//! `direction`), and only then decoded; every error reads
//! `exam.phases[i].field: ...`.

use super::PhaseConfig;
use serde::de::Error;
use serde::{Deserialize, Deserializer};

/// The fields that hold a point or a direction (three numbers); every other
/// field but `kind` holds one number.
const VECTOR_FIELDS: [&str; 2] = ["point", "direction"];

/// The type name of a TOML value, for error messages.
fn type_name(v: &toml::Value) -> &'static str {
    v.type_str()
}

fn is_number(v: &toml::Value) -> bool {
    matches!(v, toml::Value::Integer(_) | toml::Value::Float(_))
}

/// Checks the shape of one field; the message names neither phase nor key.
fn check_shape(field: &str, v: &toml::Value) -> Result<(), String> {
    if VECTOR_FIELDS.contains(&field) {
        match v {
            toml::Value::Array(a) if a.len() == 3 && a.iter().all(is_number) => Ok(()),
            toml::Value::Array(a) if a.iter().all(is_number) => {
                Err(format!("expected exactly 3 numbers, found {}", a.len()))
            }
            _ => Err(format!(
                "expected an array of 3 numbers, found {}",
                type_name(v)
            )),
        }
    } else if is_number(v) {
        Ok(())
    } else {
        Err(format!("expected a number, found {}", type_name(v)))
    }
}

/// Decodes phase `i` from its table; errors are prefixed
/// `exam.phases[i]` (with `.field` when one field is at fault).
pub(super) fn phase_from_table(i: usize, table: toml::Table) -> Result<PhaseConfig, String> {
    let at = format!("exam.phases[{i}]");
    match table.get("kind") {
        None => {
            return Err(format!(
                "{at}: missing `kind` (approach, press, hold, slide, release)"
            ))
        }
        Some(toml::Value::String(_)) => {}
        Some(v) => {
            return Err(format!(
                "{at}.kind: expected a string, found {}",
                type_name(v)
            ))
        }
    }
    for (field, v) in table.iter().filter(|(k, _)| k.as_str() != "kind") {
        check_shape(field, v).map_err(|m| format!("{at}.{field}: {m}"))?;
    }
    // Shapes are right: what is left is a missing, unknown or misplaced
    // field, or an unknown kind, and serde's messages name those.
    toml::Value::Table(table)
        .try_into::<PhaseConfig>()
        .map_err(|e| format!("{at}: {}", e.to_string().trim()))
}

/// `deserialize_with` of `ExamConfig::phases`.
pub(super) fn deserialize_phases<'de, D>(d: D) -> Result<Vec<PhaseConfig>, D::Error>
where
    D: Deserializer<'de>,
{
    let tables = <Vec<toml::Table> as Deserialize>::deserialize(d)?;
    if tables.len() > super::config::MAX_PHASES {
        return Err(D::Error::custom(format!(
            "exam.phases: {} phases, at most {} are accepted",
            tables.len(),
            super::config::MAX_PHASES
        )));
    }
    tables
        .into_iter()
        .enumerate()
        .map(|(i, t)| phase_from_table(i, t).map_err(D::Error::custom))
        .collect()
}
