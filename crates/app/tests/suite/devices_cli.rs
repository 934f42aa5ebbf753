//! `echothigh devices --json` on a machine without any device SDK or
//! service: each backend is reported absent with its reason naming the
//! library (or the service's address) and the environment variable, and the
//! command exits 0.

use std::process::Command;

#[test]
fn devices_json_reports_every_backend_absent_with_its_reason() {
    // A loopback port where nothing listens (just freed).
    let dead = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        format!("ws://{}", l.local_addr().unwrap())
    };
    let out = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(["devices", "--json"])
        .env("ECHOTHIGH_HD_LIB", "/nonexistent/libHD.so")
        .env("ECHOTHIGH_DHD_LIB", "/nonexistent/libdhd.so")
        .env("ECHOTHIGH_HAPLY_URL", &dead)
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
    assert_eq!(reports.len(), 3);
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
    // Haply: the client is built in (`found`), the service does not answer.
    let h = &reports[2];
    assert_eq!(h["backend"], "haply");
    assert_eq!(h["found"], true);
    assert_eq!(h["service_reachable"], false);
    assert_eq!(h["library"], dead.as_str());
    assert_eq!(h["env_var"], "ECHOTHIGH_HAPLY_URL");
    assert_eq!(h["devices"].as_array().map(Vec::len), Some(0));
    let reason = h["reason"].as_str().expect("a reason");
    assert!(
        reason.contains(&dead) && reason.contains("ECHOTHIGH_HAPLY_URL"),
        "{reason}"
    );
}
