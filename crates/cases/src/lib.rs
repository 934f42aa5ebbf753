//! Cases of echothigh (issue 13): a patient, its variants, thrombus
//! segments on named veins, a clinical vignette and the ground truth, in
//! one TOML file ([`CaseFile`]); the shipped library ([`library::LIBRARY`],
//! embedded from `cases/` at the repository's root); and the generator of
//! new cases from documented distributions ([`generate::Generator`]).
//!
//! The crate does no I/O: the app reads and writes the files.
//!
//! ```
//! let case = echothigh_cases::builtin("isolated-fv-mid-acute").unwrap();
//! let fv = case.ground_truth().into_iter().find(|v| v.vein == "fv").unwrap();
//! assert_eq!(fv.pieces.iter().filter(|p| p.kind == "acute_occlusive").count(), 1);
//! ```
#![warn(missing_docs)]

pub mod case;
pub mod doppler_spec;
pub mod error;
pub mod generate;
pub mod library;

pub use case::{implied_diagnosis, Case, CaseFile, Diagnosis, TruthSpec, Vignette};
pub use doppler_spec::DopplerSpec;
pub use error::CaseError;
pub use generate::{Draw, Generator, Pattern, PRACTICE, REALISTIC};

/// The names of the shipped cases, in the library's order.
pub fn names() -> impl Iterator<Item = &'static str> {
    library::LIBRARY.iter().map(|(n, _)| *n)
}

/// Loads and validates the shipped case `name`.
pub fn builtin(name: &str) -> Result<Case, CaseError> {
    let (_, text) = library::LIBRARY
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| CaseError::Unknown(name.to_string()))?;
    CaseFile::from_toml_str(text)?.load()
}

/// Parses and validates a case file's text.
pub fn from_toml_str(text: &str) -> Result<Case, CaseError> {
    CaseFile::from_toml_str(text)?.load()
}
