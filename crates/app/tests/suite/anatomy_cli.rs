//! `echothigh anatomy`: the JSON shape, the sites, and clear errors with a
//! non-zero exit on bad input (issue 12).

use std::process::Command;

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .arg("anatomy")
        .args(args)
        .output()
        .expect("run echothigh");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ids(v: &serde_json::Value) -> Vec<String> {
    v["structures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["id"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn json_has_exactly_the_documented_shape_at_every_site() {
    for site in [
        "cfv",
        "sfj",
        "fv-proximal",
        "fv-mid",
        "fv-distal",
        "popliteal",
    ] {
        let (ok, stdout, stderr) = run(&["--site", site, "--json"]);
        assert!(ok, "{site}: {stderr}");
        let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
        let top: Vec<&String> = v.as_object().unwrap().keys().collect();
        assert_eq!(top, ["s_mm", "structures"], "{site}");
        assert!(v["s_mm"].as_f64().unwrap() > 0.0);
        let mut last_depth = f64::NEG_INFINITY;
        for x in v["structures"].as_array().unwrap() {
            let mut keys: Vec<&String> = x.as_object().unwrap().keys().collect();
            keys.sort();
            assert_eq!(
                keys,
                ["depth_mm", "id", "kind", "lateral_mm", "radii_mm"],
                "{site}"
            );
            let r = x["radii_mm"].as_array().unwrap();
            assert_eq!(r.len(), 2);
            assert!(r.iter().all(|a| a.as_f64().unwrap() > 0.0));
            // Sorted by depth.
            let d = x["depth_mm"].as_f64().unwrap();
            assert!(d >= last_depth);
            last_depth = d;
        }
    }
    // The site's vein is centred (lateral 0) and the popliteal vessels are
    // present only at the popliteal site.
    let (_, mid, _) = run(&["--site", "fv-mid", "--json"]);
    let v: serde_json::Value = serde_json::from_str(mid.trim()).unwrap();
    let fv = v["structures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["id"] == "fv")
        .unwrap();
    assert!(fv["lateral_mm"].as_f64().unwrap().abs() < 1e-6);
    assert!(!ids(&v).contains(&"pv".to_string()));
    let (_, pop, _) = run(&["--site", "popliteal", "--json"]);
    let v: serde_json::Value = serde_json::from_str(pop.trim()).unwrap();
    assert!(ids(&v).contains(&"pv".to_string()) && ids(&v).contains(&"pa".to_string()));
}

#[test]
fn at_and_angle_and_variants() {
    let dir = std::env::temp_dir().join(format!("echothigh-anatomy-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("dup.toml");
    std::fs::write(
        &file,
        "preset = \"average-female\"\nduplicated_fv = true\nlymph_node = true\n",
    )
    .unwrap();
    let (ok, stdout, stderr) = run(&["--patient", file.to_str().unwrap(), "--at", "185", "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert!((v["s_mm"].as_f64().unwrap() - 185.0).abs() < 1e-9);
    assert!(ids(&v).contains(&"fv2".to_string()), "{stdout}");
    let (ok, _, stderr) = run(&["--at", "200", "--angle", "30", "--json"]);
    assert!(ok, "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_exits_non_zero_naming_it() {
    let (ok, _, stderr) = run(&["--at", "1000", "--json"]);
    assert!(!ok && stderr.contains("--at"), "{stderr}");
    let (ok, _, stderr) = run(&["--site", "ankle", "--json"]);
    assert!(!ok && stderr.contains("ankle"), "{stderr}");
    let (ok, _, stderr) = run(&["--patient", "giant", "--site", "cfv"]);
    assert!(!ok && stderr.contains("giant"), "{stderr}");
    let dir = std::env::temp_dir().join(format!("echothigh-anatomy-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (text, key) in [
        ("fat_thicknes_distal = 0.01\n", "fat_thicknes_distal"),
        ("fat_thickness_distal = -0.01\n", "fat_thickness_distal"),
        ("muscle_depth_scale = 3.0\n", "muscle_depth_scale"),
    ] {
        let f = dir.join("bad.toml");
        std::fs::write(&f, text).unwrap();
        let (ok, _, stderr) = run(&["--patient", f.to_str().unwrap(), "--site", "cfv", "--json"]);
        assert!(!ok && stderr.contains(key), "{text}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
    // Neither --at nor --site: clap refuses.
    let (ok, _, _) = run(&["--json"]);
    assert!(!ok);
}
