//! `--device` on `view` and on the viewer's `exam` (issue 15), on this
//! machine, which has no OpenHaptics: both exit non-zero before serving,
//! naming the library looked for and the variable that overrides its path.

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_echothigh");

fn refused(args: &[&str]) {
    let o = Command::new(BIN)
        .args(args)
        .env_remove("ECHOTHIGH_HD_LIB")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "{args:?}: exit 0");
    assert!(
        err.contains("libHD") && err.contains("ECHOTHIGH_HD_LIB"),
        "{args:?}: the message names neither the library nor the variable: {err}"
    );
    assert!(
        !out.contains("echothigh viewer:"),
        "{args:?}: it served: {out}"
    );
}

#[test]
fn view_with_a_missing_library_names_it_and_the_variable() {
    refused(&["view", "--device", "openhaptics", "--port", "0"]);
}

#[test]
fn exam_with_a_missing_library_names_it_and_the_variable() {
    let db = std::env::temp_dir().join(format!("echothigh-view-device-{}.db", std::process::id()));
    let url = format!("sqlite://{}", db.display());
    refused(&[
        "exam",
        "--trainee",
        "ada",
        "--device",
        "openhaptics",
        "--port",
        "0",
        "--db",
        &url,
    ]);
    assert!(
        !db.exists(),
        "the records database was made before the device failed"
    );
}
