//! `echothigh image --patient P (--at S [--angle A] | --site NAME)` (issue
//! 12): the image's vein comes from the 3D leg's section there, the same
//! one `echothigh anatomy --json` reports, and bad input is refused with a
//! message naming it.

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
fn bad_position_or_site_is_named() {
    let png = std::env::temp_dir().join("echothigh-image-site-bad.png");
    let png = png.to_str().unwrap();
    let (ok, _, err) = run(&[
        "image",
        "--patient",
        "lean-male",
        "--at",
        "900",
        "--out",
        png,
    ]);
    assert!(
        !ok && err.contains("--at") && err.contains("outside the leg"),
        "{err}"
    );
    let (ok, _, err) = run(&["image", "--site", "knee", "--out", png]);
    assert!(
        !ok && err.contains("--site") && err.contains("unknown site `knee`"),
        "{err}"
    );
    let (ok, _, err) = run(&["image", "--patient", "skinny", "--at", "100", "--out", png]);
    assert!(!ok && err.contains("--patient `skinny`"), "{err}");
    let (ok, _, err) = run(&["image", "--site", "fv-mid", "--at", "100", "--out", png]);
    assert!(!ok && err.contains("either --site or --at"), "{err}");
}

#[test]
fn image_vein_follows_the_anatomy_section() {
    for site in ["cfv", "fv-mid"] {
        let png = std::env::temp_dir().join(format!("echothigh-image-site-{site}.png"));
        let (ok, out, err) = run(&["image", "--site", site, "--out", png.to_str().unwrap()]);
        assert!(ok, "{site}: {err}");
        let (ok, json, err) = run(&["anatomy", "--site", site, "--json"]);
        assert!(ok, "{err}");
        let v: serde_json::Value = serde_json::from_str(json.trim()).unwrap();
        let vein = if site == "cfv" { "cfv" } else { "fv" };
        let x = v["structures"]
            .as_array()
            .unwrap()
            .iter()
            .find(|x| x["id"] == vein)
            .unwrap();
        let depth = x["depth_mm"].as_f64().unwrap();
        let [a, b] = [0, 1].map(|i| x["radii_mm"][i].as_f64().unwrap());
        // The image line prints the depth and the area-equivalent diameter
        // 2√(ab) to 0.1 mm: they agree to its rounding (0.05 mm).
        let line = out.lines().find(|l| l.starts_with("patient")).unwrap();
        let expect_depth = format!("{vein} {depth:.1} mm deep");
        let expect_wide = format!("{:.1} mm wide", 2.0 * (a * b).sqrt());
        assert!(
            line.contains(&expect_depth) && line.contains(&expect_wide),
            "{line} vs {expect_depth}, {expect_wide}"
        );
        assert!(png.exists());
    }
}
