//! A repeatable fuzz/property harness for the scenario loader (issue 20):
//! arbitrary text, arbitrary bytes and random mutations of the default
//! scenario never panic, and every refusal names a line (TOML syntax and
//! type errors) or a key (validation errors).
//!
//! The case count is `SCENARIO_FUZZ_CASES` (default 256 per test), so a
//! later run can go deeper: `SCENARIO_FUZZ_CASES=100000 cargo test -p
//! echothigh-runtime --release --test suite scenario_fuzz::`.

use echothigh_runtime::scenario::{Scenario, MAX_SCENARIO_BYTES};
use proptest::prelude::*;

fn cases() -> u32 {
    std::env::var("SCENARIO_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

/// Sections of a scenario: a validation error names `section.key`.
const SECTIONS: [&str; 14] = [
    "thigh",
    "tissue",
    "integrator",
    "probe",
    "contact",
    "haptics",
    "device",
    "hand",
    "exam",
    "coupling",
    "link",
    "imaging",
    "patient",
    "run",
];

/// A refusal is useful only if it says where: a line (parse errors) or a key.
fn names_a_line_or_key(msg: &str) -> bool {
    msg.contains("line ")
        || SECTIONS
            .iter()
            .any(|s| msg.contains(&format!("{s}.")) || msg.contains(&format!("`{s}`")))
        || msg.contains("unknown field")
}

fn check(text: &str) -> Result<(), TestCaseError> {
    if let Err(e) = Scenario::from_toml_str(text, "(fuzz)") {
        let msg = format!("{e:#}");
        prop_assert!(
            names_a_line_or_key(&msg),
            "an error that names no line or key: {msg}\ninput: {text:?}"
        );
    }
    Ok(())
}

/// The default scenario written out, the seed of the mutations.
fn seed_text() -> String {
    toml::to_string(&Scenario::default()).expect("the default scenario serializes")
}

/// Tokens that stress the decoder where a number is expected.
const TOKENS: [&str; 14] = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-300",
    "0",
    "-1",
    "\"x\"",
    "[]",
    "[1, 2, 3, 4]",
    "true",
    "{}",
    "18446744073709551616",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,400}") {
        check(&text)?;
    }

    #[test]
    fn arbitrary_bytes_through_a_file_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let dir = std::env::temp_dir().join(format!("echothigh-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("s.toml");
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = Scenario::load(Some(&path)) {
            let msg = format!("{e:#}");
            prop_assert!(
                msg.contains("s.toml") && (names_a_line_or_key(&msg) || msg.contains("UTF-8")),
                "{msg}"
            );
        }
    }

    /// Replace one value of the default scenario by a hostile token, or cut,
    /// duplicate or delete a line: the loader refuses or accepts, never panics.
    #[test]
    fn mutated_default_scenario_never_panics(
        line in any::<prop::sample::Index>(),
        token in 0..TOKENS.len(),
        op in 0..4u8,
    ) {
        let seed = seed_text();
        let mut lines: Vec<String> = seed.lines().map(str::to_string).collect();
        let at = line.index(lines.len());
        match op {
            0 => {
                if let Some(eq) = lines[at].find(" = ") {
                    lines[at] = format!("{}{}", &lines[at][..eq + 3], TOKENS[token]);
                }
            }
            1 => { lines.remove(at); }
            2 => { let l = lines[at].clone(); lines.insert(at, l); }
            _ => { let l = &lines[at]; lines[at] = l[..l.len() / 2].to_string(); }
        }
        check(&lines.join("\n"))?;
    }
}

/// `--scenario /dev/zero` read without bound; it is now refused after 1 MiB.
#[test]
fn an_endless_input_is_refused_after_the_size_bound() {
    let e = Scenario::load(Some(std::path::Path::new("/dev/zero"))).unwrap_err();
    let msg = format!("{e:#}");
    assert!(
        msg.contains("/dev/zero") && msg.contains(&MAX_SCENARIO_BYTES.to_string()),
        "{msg}"
    );
}

/// Fixed-size arrays take exactly their size (issue 20: extra elements were
/// dropped silently), in every crate's section.
#[test]
fn arrays_with_extra_or_missing_elements_are_refused() {
    for text in [
        "[thigh]\nfemur_offset = [0, -0.01, 99]\n",
        "[thigh]\nfemur_offset = [0, -0.01, 99, \"junk\", true]\n",
        "[thigh]\nfemur_offset = [0]\n",
        "[tissue]\ngravity = [0, 0, 0, 0]\n",
        "[exam]\nstart = [0, 0.092, -0.01, 5]\n",
        "[exam]\npress_direction = [0, -1]\n",
    ] {
        let e = Scenario::from_toml_str(text, "(test)").unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("line "), "{text}: {msg}");
        assert!(
            msg.contains("exactly") || msg.contains("invalid type"),
            "{text}: {msg}"
        );
    }
}
