//! `echothigh cases` and `--case` (issue 13): the JSON ground truth covers
//! each vein once in mm, the generator's files are the same for a seed, and
//! bad input exits non-zero with a message naming what is wrong.

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

#[test]
fn show_json_lists_each_vein_once_in_mm() {
    let (ok, out, err) = run(&["cases", "show", "isolated-fv-mid-acute", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["diagnosis"], "acute_dvt");
    let truth = v["truth"].as_array().unwrap();
    let veins: Vec<&str> = truth.iter().map(|x| x["vein"].as_str().unwrap()).collect();
    assert_eq!(veins.len(), 5, "{veins:?}"); // cfv fv pv gsv dfv (no fv2 on this leg)
    let fv = truth.iter().find(|x| x["vein"] == "fv").unwrap()["segments"]
        .as_array()
        .unwrap();
    // The case file's segment is 0.17–0.23 m: 170–230 mm.
    let acute = fv.iter().find(|s| s["kind"] == "acute_occlusive").unwrap();
    assert!((acute["s_start_mm"].as_f64().unwrap() - 170.0).abs() < 1e-9);
    assert!((acute["s_end_mm"].as_f64().unwrap() - 230.0).abs() < 1e-9);
    for w in fv.windows(2) {
        assert_eq!(w[0]["s_end_mm"], w[1]["s_start_mm"]);
    }
    let (ok, out, _) = run(&["cases", "list", "--json"]);
    assert!(ok);
    let list: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert!(list.as_array().unwrap().len() >= 24);
}

#[test]
fn generate_is_deterministic_and_cases_load_back() {
    let base = std::env::temp_dir().join(format!("echothigh-cases-{}", std::process::id()));
    let dirs = [base.join("a"), base.join("b")];
    for d in &dirs {
        let (ok, _, err) = run(&[
            "cases",
            "generate",
            "--count",
            "12",
            "--prevalence",
            "0.5",
            "--seed",
            "9",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
    }
    for i in 1..=12 {
        let name = format!("generated-{i:05}.toml");
        let a = std::fs::read_to_string(dirs[0].join(&name)).unwrap();
        let b = std::fs::read_to_string(dirs[1].join(&name)).unwrap();
        assert_eq!(a, b, "{name} differs between two runs with one seed");
        let path = dirs[0].join(&name);
        let (ok, _, err) = run(&["cases", "show", path.to_str().unwrap()]);
        assert!(ok, "{name}: {err}");
    }
    std::fs::remove_dir_all(&base).ok();
}

#[test]
fn bad_input_names_what_is_wrong() {
    let (ok, _, err) = run(&["cases", "show", "no-such-case"]);
    assert!(!ok && err.contains("no-such-case"), "{err}");
    let (ok, _, err) = run(&[
        "cases",
        "generate",
        "--count",
        "3",
        "--prevalence",
        "1.5",
        "--out",
        "/tmp/x",
    ]);
    assert!(!ok && err.contains("--prevalence"), "{err}");
    let dir = std::env::temp_dir().join(format!("echothigh-badcase-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    let text = "name = \"bad\"\ntitle = \"t\"\n[patient]\npreset = \"lean-male\"\n[vignette]\nage = 50\nsymptoms = \"s\"\nwells = 1\n[[thrombus]]\nvein = \"fv\"\ns_start = 0.15\ns_end = 0.20\nkind = \"clot\"\n[truth]\ndiagnosis = \"acute_dvt\"\n";
    std::fs::write(&path, text).unwrap();
    let (ok, _, err) = run(&[
        "anatomy",
        "--case",
        path.to_str().unwrap(),
        "--site",
        "fv-mid",
    ]);
    assert!(!ok && err.contains("thrombus[0].kind"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn anatomy_with_a_case_gives_the_state_of_each_vein() {
    let (ok, out, err) = run(&[
        "anatomy",
        "--case",
        "isolated-fv-mid-acute",
        "--at",
        "200",
        "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let fv = v["structures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["id"] == "fv")
        .unwrap();
    assert_eq!(fv["state"]["fill"], 1.0);
    let gsv = v["structures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["id"] == "gsv")
        .unwrap();
    assert_eq!(gsv["state"]["fill"], 0.0);
}

/// `echothigh cases list | head` (issue 13): a reader that has gone (the
/// pipe's read end closed before the first write, so that every write
/// meets EPIPE whatever the timing) ends the listing quietly: exit 0, no
/// panic on stderr. Before the fix `println!` panicked ("failed printing to
/// stdout: Broken pipe", exit 101). Also for `show`, text and JSON.
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    for args in [
        &["cases", "list"][..],
        &["cases", "list", "--json"],
        &["cases", "show", "fv-chronic"],
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_echothigh"))
            .args(args)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .expect("run echothigh");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {:?}, {err}", out.status);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}
