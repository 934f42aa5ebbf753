//! The shipped library (issue 13): every case loads and validates, its
//! ground truth covers every vein of its leg exactly once, the names the
//! issue requires are there, and bad files name the key at fault.

use echothigh_cases::{builtin, from_toml_str, names, CaseError, Diagnosis};

const REQUIRED: [&str; 8] = [
    "normal-average",
    "normal-obese",
    "isolated-fv-mid-acute",
    "cfv-occlusive-acute",
    "popliteal-acute",
    "cfv-free-floating",
    "fv-non-occlusive",
    "fv-chronic",
];

#[test]
fn every_shipped_case_loads_and_covers_each_vein_once() {
    let all: Vec<&str> = names().collect();
    assert!(all.len() >= 24, "{} cases", all.len());
    for r in REQUIRED {
        assert!(all.contains(&r), "missing {r}");
    }
    let mut seen = std::collections::HashSet::new();
    for name in all {
        assert!(seen.insert(name), "duplicate {name}");
        let case = builtin(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(case.name(), name, "file name and `name` differ");
        let truth = case.ground_truth();
        let mut veins: Vec<&str> = truth.iter().map(|v| v.vein).collect();
        veins.sort();
        let before = veins.len();
        veins.dedup();
        assert_eq!(before, veins.len(), "{name}: a vein listed twice");
        // Every vein of the leg is listed (the deep line, GSV, profunda, fv2 if duplicated).
        let expect = case
            .anatomy
            .tubes()
            .iter()
            .filter(|t| t.kind().as_str().ends_with("_vein"))
            .count();
        assert_eq!(veins.len(), expect, "{name}");
        for v in &truth {
            let tube = case
                .anatomy
                .tubes()
                .iter()
                .find(|t| t.id().as_str() == v.vein)
                .unwrap();
            let (lo, hi) = tube.s_range();
            assert_eq!(v.pieces[0].s_start, lo, "{name} {}", v.vein);
            assert_eq!(v.pieces.last().unwrap().s_end, hi, "{name} {}", v.vein);
            for w in v.pieces.windows(2) {
                assert_eq!(
                    w[0].s_end, w[1].s_start,
                    "{name} {}: gap or overlap",
                    v.vein
                );
            }
            assert!(
                v.pieces.iter().all(|p| p.s_end > p.s_start),
                "{name} {}",
                v.vein
            );
        }
        // Normal cases have only normal pieces, and the others at least one thrombosed piece.
        let thrombosed = truth
            .iter()
            .flat_map(|v| &v.pieces)
            .filter(|p| p.kind != "normal")
            .count();
        assert_eq!(
            thrombosed == 0,
            case.file.truth.diagnosis == Diagnosis::Normal,
            "{name}"
        );
    }
}

fn with(base: &str, from: &str, to: &str) -> String {
    assert!(base.contains(from), "test fixture lacks {from}");
    base.replacen(from, to, 1)
}

fn key_of(e: CaseError) -> String {
    match e {
        CaseError::Key { key, .. } => key,
        CaseError::Thrombus(echothigh_anatomy::AnatomyError::Thrombus { key, .. }) => key,
        CaseError::Patient(a) => a.to_string(),
        CaseError::Parse(m) => m,
        other => other.to_string(),
    }
}

#[test]
fn bad_case_files_name_the_key() {
    let base = echothigh_cases::library::LIBRARY
        .iter()
        .find(|(n, _)| *n == "isolated-fv-mid-acute")
        .unwrap()
        .1;
    assert!(from_toml_str(base).is_ok());
    let overlap = with(
        base,
        "[truth]",
        "[[thrombus]]\nvein = \"fv\"\ns_start = 0.2\ns_end = 0.25\nkind = \"chronic\"\n\n[truth]",
    );
    let bad: Vec<(String, &str)> = vec![
        (overlap, "thrombus[1].s_start"),
        (
            with(base, "s_end = 0.23", "s_end = 0.30"),
            "thrombus[0].s_end",
        ),
        (
            with(base, "vein = \"fv\"", "vein = \"sfv\""),
            "thrombus[0].vein",
        ),
        (
            with(base, "kind = \"acute_occlusive\"", "kind = \"subacute\""),
            "thrombus[0].kind",
        ),
        (
            with(base, "s_start = 0.17", "s_start = nan"),
            "thrombus[0].s_start",
        ),
        (with(base, "wells = 2", "wells = 12"), "vignette.wells"),
        (
            with(base, "diagnosis = \"acute_dvt\"", "diagnosis = \"normal\""),
            "truth.diagnosis",
        ),
        (
            with(
                base,
                "preset = \"lean-male\"",
                "preset = \"lean-male\"\nknee_s = 0.9",
            ),
            "patient.knee_s",
        ),
    ];
    for (text, key) in bad {
        let e = from_toml_str(&text)
            .err()
            .unwrap_or_else(|| panic!("accepted a file with a bad {key}"));
        let msg = e.to_string();
        assert!(key_of(e).contains(key), "expected {key} in: {msg}");
        assert!(msg.contains(key), "message must name {key}: {msg}");
    }
    // An unknown key and an unknown diagnosis: the TOML parser names them.
    let Err(e) = from_toml_str(&with(base, "wells = 2", "wells = 2\nwell = 3")) else {
        panic!("unknown key accepted")
    };
    assert!(e.to_string().contains("well"), "{e}");
    let Err(e) = from_toml_str(&with(
        base,
        "diagnosis = \"acute_dvt\"",
        "diagnosis = \"dvt\"",
    )) else {
        panic!("unknown diagnosis accepted")
    };
    assert!(
        e.to_string().contains("diagnosis") || e.to_string().contains("dvt"),
        "{e}"
    );
}
