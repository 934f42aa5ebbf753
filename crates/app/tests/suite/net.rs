//! The two-process deployment over loopback UDP (issue 5): a physics server
//! and a haptic client started as child processes run part of the exam; if
//! the server is killed mid-run the client fades its force out and stops
//! with a clear message, keeping the data it recorded.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_echothigh");
const TOKEN: &str = "00000000c0ffee01";

struct Server {
    child: Child,
    addr: String,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start_server() -> Server {
    let mut child = Command::new(BIN)
        .args([
            "--log",
            "warn",
            "physics-server",
            "--listen",
            "127.0.0.1:0",
            "--token",
            TOKEN,
            "--accept-timeout",
            "30",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("starting the physics server");
    let stdout = child.stdout.take().unwrap();
    let mut line = String::new();
    BufReader::new(stdout).read_line(&mut line).unwrap();
    let addr = line.trim().rsplit(' ').next().unwrap().to_string();
    assert!(
        line.contains("listening"),
        "unexpected server output: {line}"
    );
    Server { child, addr }
}

fn column(csv: &Path, name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

/// The `haptic-client` command for `server`, running `seconds` of the exam
/// and writing its run directory to `out`.
fn client(server: &Server, seconds: f64, out: &Path) -> Command {
    let mut c = Command::new(BIN);
    c.args(["--log", "warn", "haptic-client", "--connect", &server.addr])
        .args(["--token", TOKEN, "--duration", &seconds.to_string()])
        .arg("--out")
        .arg(out);
    c
}

#[test]
fn client_and_server_run_the_exam_over_udp() {
    let server = start_server();
    let out = std::env::temp_dir().join(format!("echothigh-net-ok-{}", std::process::id()));
    let status = client(&server, 2.0, &out).status().unwrap();
    assert!(status.success(), "client failed: {status}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["deployment"], "processes");
    let ticks = summary["ticks"].as_u64().unwrap();
    assert!((1900..=2001).contains(&ticks), "ticks {ticks}");
    let f = column(&out.join("haptic.csv"), "force");
    let peak = f.iter().copied().fold(0.0, f64::max);
    assert!(f.iter().all(|x| x.is_finite()));
    assert!(peak > 3.0 && peak <= 20.0 + 1e-9, "peak force {peak}");
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn killing_the_server_fades_the_client_force() {
    let mut server = start_server();
    let out = std::env::temp_dir().join(format!("echothigh-net-kill-{}", std::process::id()));
    let client = client(&server, 6.0, &out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Kill the server while the hand presses (the press starts at ~0.4 s).
    std::thread::sleep(Duration::from_millis(1500));
    server.child.kill().unwrap();
    let output = client.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success(),
        "the client should report the lost server"
    );
    assert!(stderr.contains("went silent"), "unclear message: {stderr}");
    let t = column(&out.join("haptic.csv"), "t");
    let f = column(&out.join("haptic.csv"), "force");
    assert!(t.last().unwrap() < &5.0, "the client did not stop early");
    assert!(f.iter().all(|x| x.is_finite()));
    assert_eq!(*f.last().unwrap(), 0.0, "the force was not faded out");
    std::fs::remove_dir_all(&out).ok();
}
