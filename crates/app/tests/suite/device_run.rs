//! `--device` on the real binary (issue 15): a missing vendor library is
//! refused before any file is made, naming the library and the variable
//! that overrides its path; with the emulated HD (Touch) and DHD (omega.6)
//! libraries — stand-ins exporting the vendors' C functions, no hardware on
//! these machines — `run` drives the device through the one haptic tick:
//! a stylus calibrated 10 mm inside the thigh is pushed back out.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_echothigh");

/// The emulator cdylib cargo built for this test (a dev-dependency): next
/// to the test executable or in a parent directory up to `target`.
fn emulator() -> PathBuf {
    let name = format!(
        "{}echothigh_device_emu{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    );
    let exe = std::env::current_exe().unwrap();
    let mut dir = exe.parent().map(Path::to_path_buf);
    while let Some(d) = dir {
        if d.join(&name).is_file() {
            return d.join(&name);
        }
        if d.file_name().is_some_and(|n| n == "target") {
            break;
        }
        dir = d.parent().map(Path::to_path_buf);
    }
    panic!("{name} not found above {exe:?}: build echothigh-device-emu");
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("echothigh-device-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

#[test]
fn a_missing_library_is_named_before_any_file_is_made() {
    for (device, var) in [
        ("openhaptics", "ECHOTHIGH_HD_LIB"),
        ("forcedimension", "ECHOTHIGH_DHD_LIB"),
    ] {
        let out = out_dir(&format!("missing-{device}"));
        let o = Command::new(BIN)
            .args(["run", "--device", device, "--duration", "1", "--out"])
            .arg(&out)
            .env(var, "/nonexistent/libvendor.so")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{device}: exit 0");
        assert!(
            err.contains(var) && err.contains("/nonexistent/libvendor.so"),
            "{device}: the message names neither the variable nor the file: {err}"
        );
        assert!(!out.exists(), "{device}: a run directory was made");
    }
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
fn an_emulated_device_pressed_into_the_thigh_is_pushed_out() {
    let lib = emulator();
    // Peak forces of the emulated models (devices-hw's limits table: Touch
    // 3.3 N, omega.6 12 N).
    for (device, var, peak) in [
        ("openhaptics", "ECHOTHIGH_HD_LIB", 3.3),
        ("forcedimension", "ECHOTHIGH_DHD_LIB", 12.0),
    ] {
        let out = out_dir(&format!("emu-{device}"));
        std::fs::create_dir_all(&out).unwrap();
        // The stylus's home placed at y = 62 mm in the leg frame: 10 mm
        // inside the default thigh, whose top is at semi_axis_y = 72 mm.
        let hw = out.join("hardware.toml");
        std::fs::write(&hw, "[calibration]\ntranslation = [0.0, 0.062, 0.0]\n").unwrap();
        let run = out.join("run");
        let o = Command::new(BIN)
            .args([
                "--log",
                "warn",
                "run",
                "--device",
                device,
                "--duration",
                "2",
            ])
            .arg("--hardware")
            .arg(&hw)
            .arg("--out")
            .arg(&run)
            .env(var, &lib)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{device}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = std::fs::read_to_string(run.join("haptic.csv")).unwrap();
        let y = column(&text, "device_y");
        let fy = column(&text, "force_y");
        let dev: Vec<f64> = ["device_force_x", "device_force_y", "device_force_z"]
            .iter()
            .map(|c| column(&text, c))
            .fold(vec![0.0; y.len()], |acc, c| {
                acc.iter().zip(&c).map(|(a, b)| a + b * b).collect()
            })
            .into_iter()
            .map(f64::sqrt)
            .collect();
        assert!(y.len() >= 1900, "{device}: {} ticks in 2 s", y.len());
        assert!((y[0] - 0.062).abs() < 1e-6, "{device}: starts at {}", y[0]);
        // Pushed out: the tissue force points out of the thigh (+y) on
        // every tick (never pulls the stylus in), and was felt.
        assert!(
            fy.iter().all(|&f| f >= -1e-9),
            "{device}: a force pulled into the tissue"
        );
        assert!(fy.iter().any(|&f| f > 1.0), "{device}: no force felt");
        // Out of the tissue at the end: above 70 mm (the surface is at 72 mm;
        // the emulated arm, pushed out, coasts 2 mm past it — measured
        // 74.1 mm — and 2 mm below it is the most a penalty contact at
        // rest would leave it in).
        let last = *y.last().unwrap();
        assert!(
            last > 0.070,
            "{device}: still {:.1} mm in",
            (0.072 - last) * 1e3
        );
        // Within the device's limits on every tick.
        let worst = dev.iter().copied().fold(0.0, f64::max);
        assert!(worst <= peak + 1e-9, "{device}: {worst} N > {peak} N peak");
        std::fs::remove_dir_all(&out).ok();
    }
}

/// `devices calibrate` with nobody touching the emulated stylus: the
/// landmark waited for is named, and no file is written (the capture
/// itself is tested in-process against the emulator, where the test can
/// move the stylus: `crates/devices-hw/tests/calibrate.rs`).
#[test]
fn calibrate_without_a_touch_names_the_landmark_and_writes_nothing() {
    let out = out_dir("calibrate").with_extension("toml");
    let o = Command::new(BIN)
        .args([
            "devices",
            "calibrate",
            "--device",
            "openhaptics",
            "--timeout",
            "0.5",
            "--out",
        ])
        .arg(&out)
        .env("ECHOTHIGH_HD_LIB", emulator())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "exit 0: {err}");
    assert!(
        err.contains("(1/4) touch the top of the thigh at mid-thigh"),
        "{err}"
    );
    assert!(
        err.contains("no touch of \"the top of the thigh at mid-thigh\""),
        "{err}"
    );
    assert!(!out.exists(), "a file was written");
}
