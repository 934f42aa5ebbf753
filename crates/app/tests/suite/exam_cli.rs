//! `echothigh exam --script --case [--json]` (issue 14): the JSON carries
//! the score's fields and per call the site, the call and the truth; a bad
//! script exits non-zero naming the key.

use std::process::Command;

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(args)
        .output()
        .expect("run echothigh");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn scenario(name: &str) -> String {
    format!("{}/../../scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Two-point on the isolated FV thrombus: both calls (CFV, popliteal)
/// normal and right, full coverage of the protocol's two bins, every press
/// adequate (the 10 N presses coapt both veins), and the missed FV
/// segment (170–230 mm) in the score.
#[test]
fn json_has_the_score_and_the_calls() {
    let script = scenario("exam-two-point.toml");
    let (ok, out, err) = run(&[
        "exam",
        "--script",
        &script,
        "--case",
        "isolated-fv-mid-acute",
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["coverage"], 1.0);
    assert_eq!(v["calls_correct"], 2);
    assert_eq!(v["calls_total"], 2);
    assert_eq!(v["pressure_adequate"], 1.0);
    let calls = v["calls"].as_array().unwrap();
    let sites: Vec<&str> = calls.iter().map(|c| c["site"].as_str().unwrap()).collect();
    assert_eq!(sites, ["cfv", "popliteal"]);
    for c in calls {
        assert_eq!(c["call"], "normal");
        assert_eq!(c["truth"], "normal");
    }
    let missed = v["score"]["missed"].as_array().unwrap();
    assert_eq!(missed.len(), 1);
    assert_eq!(missed[0]["vein"], "fv");
    assert_eq!(missed[0]["truth"], "acute_dvt");
}

/// A bad script names the key; an unknown case names the argument.
#[test]
fn bad_scripts_and_cases_are_refused_naming_what() {
    let dir = std::env::temp_dir().join(format!("echothigh-exam-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "protocol = \"two-point\"\n[press]\nmax_force = 90.0\n",
    )
    .unwrap();
    let bad = bad.to_str().unwrap();
    let (ok, _, err) = run(&["exam", "--script", bad, "--case", "normal-average"]);
    assert!(!ok);
    assert!(
        err.contains("press.max_force") && err.contains("bad.toml"),
        "{err}"
    );
    let typo = dir.join("typo.toml");
    std::fs::write(&typo, "protocol = \"two-point\"\nskipp = [\"cfv\"]\n").unwrap();
    let (ok, _, err) = run(&[
        "exam",
        "--script",
        typo.to_str().unwrap(),
        "--case",
        "normal-average",
    ]);
    assert!(!ok);
    assert!(err.contains("skipp"), "{err}");
    let script = scenario("exam-two-point.toml");
    let (ok, _, err) = run(&["exam", "--script", &script, "--case", "no-such-case"]);
    assert!(!ok);
    assert!(
        err.contains("--case") && err.contains("no-such-case"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
