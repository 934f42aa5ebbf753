//! `[doppler]` of a case file (issue 17), optional: what the Doppler flow
//! model needs beyond the thrombus segments of the leg.
//!
//! ```toml
//! [doppler]
//! proximal_obstruction = true   # iliac vein obstruction above the groin
//! ```
//!
//! Absent, every key takes its default (no obstruction), so the case
//! files written before it load unchanged.

use serde::{Deserialize, Serialize};

/// The `[doppler]` table of a case file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DopplerSpec {
    /// An obstruction of the iliac veins (above the inguinal ligament, off
    /// the modelled leg): the CFV signal is continuous, not phasic, and
    /// does not respond to Valsalva. Default false.
    pub proximal_obstruction: bool,
}

impl DopplerSpec {
    /// Whether every key has its default (then the table is not written).
    pub fn is_default(&self) -> bool {
        *self == DopplerSpec::default()
    }
}

#[cfg(test)]
mod tests {
    use crate::CaseFile;

    const BASE: &str = r#"
name = "t"
title = "t"
[patient]
preset = "lean-male"
[vignette]
age = 40
symptoms = "swelling"
wells = 1
[truth]
diagnosis = "normal"
"#;

    /// A file without `[doppler]` loads with no obstruction and writes no
    /// `[doppler]` table (old files round-trip unchanged); one with it
    /// keeps the flag through a round trip; an unknown key is refused by name.
    #[test]
    fn doppler_table_is_optional_and_round_trips() {
        let f = CaseFile::from_toml_str(BASE).unwrap();
        assert!(!f.doppler.proximal_obstruction);
        assert!(!f.to_toml_string().contains("[doppler]"));
        let with = format!("{BASE}[doppler]\nproximal_obstruction = true\n");
        let f = CaseFile::from_toml_str(&with).unwrap();
        assert!(f.doppler.proximal_obstruction);
        let again = CaseFile::from_toml_str(&f.to_toml_string()).unwrap();
        assert!(again.doppler.proximal_obstruction);
        let bad = format!("{BASE}[doppler]\nproximal = true\n");
        let e = CaseFile::from_toml_str(&bad).unwrap_err().to_string();
        assert!(e.contains("proximal"), "{e}");
    }
}
