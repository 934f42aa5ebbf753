//! Typed errors of the anatomy crate. Every variant names the key, vessel or
//! query argument at fault, so that a user can fix a patient file or a
//! command line from the message alone.

use thiserror::Error;

/// What went wrong when building or querying the anatomy.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AnatomyError {
    /// The patient TOML does not parse (syntax, unknown key, wrong type);
    /// the message is the TOML parser's, which names the key and line.
    #[error("patient file: {0}")]
    Parse(String),
    /// A patient key has a value outside its documented range.
    #[error("patient.{key} = {value}: {reason}")]
    InvalidValue {
        /// The offending key, e.g. `fat_thickness_distal`.
        key: &'static str,
        /// The value found.
        value: f64,
        /// What the key must satisfy.
        reason: &'static str,
    },
    /// An unknown preset name (`preset = …` in a file, or `--patient`).
    #[error("unknown patient preset `{0}` (known: lean-male, average-female, obese)")]
    UnknownPreset(String),
    /// A vessel (or landmark) would leave the leg or cross the femur with
    /// this patient's dimensions; `keys` are the patient keys that place it.
    #[error("patient: `{structure}` at s = {s:.3} m {problem} (set by patient.{keys})")]
    StructureOutside {
        /// Structure id (`fv`, `gsv`, …).
        structure: &'static str,
        /// Position along the leg (m below the inguinal ligament).
        s: f64,
        /// `lies outside the leg` or `crosses the femur`.
        problem: &'static str,
        /// The keys that set this structure's position.
        keys: &'static str,
    },
    /// A query position along the leg outside `[0, length]`.
    #[error("{what} = {value:.4} m is outside the leg (s must lie in [0, {length:.3}] m)")]
    OutsideLeg {
        /// The argument's name (`s`, `--at`, …).
        what: &'static str,
        /// The value given (m).
        value: f64,
        /// The leg's length (m).
        length: f64,
    },
    /// A query argument that is not finite or out of its range.
    #[error("{what} = {value}: {reason}")]
    BadQuery {
        /// The argument's name (`theta`, `tilt`, `spin`, …).
        what: &'static str,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// An unknown exam site name.
    #[error("unknown site `{0}` (known: cfv, sfj, fv-proximal, fv-mid, fv-distal, popliteal)")]
    UnknownSite(String),
    /// A thrombus segment of a case is invalid; `key` names the entry and
    /// field (`thrombus[2].s_end`).
    #[error("{key} {reason}")]
    Thrombus {
        /// The key at fault, e.g. `thrombus[0].vein`.
        key: String,
        /// What is wrong and what it must satisfy.
        reason: String,
    },
}
