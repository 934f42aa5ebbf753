//! The Haply backend on the real binary (issue 15), against the emulated
//! Inverse Service (`echothigh_device_emu::inverse`, in this test's process,
//! on a loopback port; no hardware on these machines): `devices --json`
//! reports it, an unreachable service is refused before any file is made,
//! and a scenario whose `[device] kind = "haply"` drives the emulated
//! Inverse3 through the one haptic tick.
#![cfg(feature = "haply")]

use echothigh_device_emu::inverse::InverseService;
use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_echothigh");

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("echothigh-haply-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

/// Columns of `haptic.csv` by name.
fn column(text: &str, name: &str) -> Vec<f64> {
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = head.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(i).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn devices_json_reports_a_reachable_service_and_its_inverse3() {
    let emu = InverseService::start().unwrap();
    let out = Command::new(BIN)
        .args(["devices", "--json"])
        .env("ECHOTHIGH_HD_LIB", "/nonexistent/libHD.so")
        .env("ECHOTHIGH_DHD_LIB", "/nonexistent/libdhd.so")
        .env("ECHOTHIGH_HAPLY_URL", emu.url())
        .output()
        .unwrap();
    assert!(out.status.success());
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let h = &reports[2];
    assert_eq!(h["backend"], "haply");
    assert_eq!(h["service_reachable"], true, "{h}");
    assert_eq!(h["library"], emu.url().as_str());
    let d = &h["devices"][0];
    assert!(d["model"].as_str().unwrap().starts_with("inverse3"), "{d}");
    assert_eq!(d["orientation_sensed"], true);
    // The probe opened the device at zero force and left none behind.
    assert_eq!(emu.max_applied_force(), 0.0);
    assert_eq!(emu.closed_with_force(), 0);
}

#[test]
fn an_unreachable_service_is_named_before_any_file_is_made() {
    let dead = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        format!("ws://{}", l.local_addr().unwrap())
    };
    let out = out_dir("unreachable");
    let o = Command::new(BIN)
        .args(["run", "--device", "haply", "--duration", "1", "--out"])
        .arg(&out)
        .env("ECHOTHIGH_HAPLY_URL", &dead)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "exit 0");
    assert!(
        err.contains(&dead) && err.contains("ECHOTHIGH_HAPLY_URL"),
        "the message names neither the address nor the variable: {err}"
    );
    assert!(!out.exists(), "a run directory was made");
}

#[test]
fn the_scenario_selects_the_haply_device_and_the_thigh_pushes_it_out() {
    let emu = InverseService::start().unwrap();
    let out = out_dir("scenario");
    std::fs::create_dir_all(&out).unwrap();
    let scenario = out.join("scenario.toml");
    std::fs::write(&scenario, "[device]\nkind = \"haply\"\n").unwrap();
    // The cursor's home placed at y = 62 mm in the leg frame: 10 mm inside
    // the default thigh, whose top is at semi_axis_y = 72 mm.
    let hw = out.join("hardware.toml");
    std::fs::write(
        &hw,
        format!(
            "[calibration]\ntranslation = [0.0, 0.062, 0.0]\n[haply]\nurl = \"{}\"\n",
            emu.url()
        ),
    )
    .unwrap();
    let run = out.join("run");
    let o = Command::new(BIN)
        .args(["--log", "warn", "run", "--duration", "2"])
        .arg("--scenario")
        .arg(&scenario)
        .arg("--hardware")
        .arg(&hw)
        .arg("--out")
        .arg(&run)
        .env_remove("ECHOTHIGH_HAPLY_URL")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(run.join("haptic.csv")).unwrap();
    let y = column(&text, "device_y");
    let fy = column(&text, "force_y");
    assert!(y.len() >= 1900, "{} ticks in 2 s", y.len());
    // The wire carries f32: 0.062 m to within 4e-9 m.
    assert!((y[0] - 0.062).abs() < 1e-6, "starts at {}", y[0]);
    assert!(
        fy.iter().all(|&f| f >= -1e-9),
        "a force pulled into the tissue"
    );
    assert!(fy.iter().any(|&f| f > 1.0), "no force felt");
    // Out of the tissue at the end, as the HD and DHD runs (device_run.rs).
    let last = *y.last().unwrap();
    assert!(last > 0.070, "still {:.1} mm in", (0.072 - last) * 1e3);
    // Within the limits an unlisted model gets (the Touch's 3.3 N peak), as
    // the service saw them (f32 components: ≤ 6e-8 relative).
    let max = emu.max_applied_force();
    assert!(max > 0.0 && max <= 3.3 * (1.0 + 6e-8), "{max} N");
    // The run ended by zeroing the force before closing the session.
    assert_eq!(emu.last_force().0, [0.0; 3]);
    assert_eq!(emu.closed_with_force(), 0);
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn bench_haptics_times_the_tick_through_the_emulated_service() {
    let emu = InverseService::start().unwrap();
    let o = Command::new(BIN)
        .args([
            "bench",
            "haptics",
            "--device",
            "haply",
            "--device-ticks",
            "300",
        ])
        .env("ECHOTHIGH_HAPLY_URL", emu.url())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let results = report["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for (r, name) in results.iter().zip(["simulated", "haply"]) {
        assert_eq!(r["device"], name);
        assert_eq!(r["ticks"], 300);
        // Order statistics of one sample: median ≤ p99 ≤ p99.9, times ≥ 0
        // (wall clock and the thread's CPU clock alike).
        for key in ["tick_compute", "tick_thread_cpu"] {
            let c = &r[key];
            let (m, p99, p999) = (
                c["median_us"].as_f64().unwrap(),
                c["p99_us"].as_f64().unwrap(),
                c["p999_us"].as_f64().unwrap(),
            );
            assert!(0.0 <= m && m <= p99 && p99 <= p999, "{key}: {c}");
        }
    }
    // The benchmark's device left no force behind.
    assert_eq!(emu.closed_with_force(), 0);
}
