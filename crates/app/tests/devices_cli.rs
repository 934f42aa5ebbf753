//! `echothigh devices --json` on a machine without any device SDK: each
//! backend is reported absent with its reason naming the library and the
//! environment variable, and the command exits 0.

use std::process::Command;

#[test]
fn devices_json_reports_every_backend_absent_with_its_reason() {
    let out = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(["devices", "--json"])
        .env("ECHOTHIGH_HD_LIB", "/nonexistent/libHD.so")
        .env("ECHOTHIGH_DHD_LIB", "/nonexistent/libdhd.so")
        .output()
        .expect("run echothigh");
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    let reports = reports.as_array().expect("an array");
    assert_eq!(reports.len(), 2);
    for (r, (name, var, lib)) in reports.iter().zip([
        ("openhaptics", "ECHOTHIGH_HD_LIB", "/nonexistent/libHD.so"),
        (
            "forcedimension",
            "ECHOTHIGH_DHD_LIB",
            "/nonexistent/libdhd.so",
        ),
    ]) {
        assert_eq!(r["backend"], name);
        assert_eq!(r["found"], false);
        assert_eq!(r["library"], lib);
        assert_eq!(r["env_var"], var);
        assert_eq!(r["devices"].as_array().map(Vec::len), Some(0));
        let reason = r["reason"].as_str().expect("a reason");
        assert!(reason.contains(lib) && reason.contains(var), "{reason}");
    }
}
