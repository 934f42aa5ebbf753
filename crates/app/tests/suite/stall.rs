//! SIGSTOP of either process in contact (issue 20, item 2), on the real
//! binaries: `physics-server` and `haptic-client` on loopback, the client's
//! scripted exam sliding along the thigh at ~10 N, one process stopped for
//! 0.05, 0.15, 0.35, 1 or 3 s, then continued; repeated with two busy
//! processes competing for the two cores.
//!
//! Both sides get a 5 s peer timeout so that the 3 s stall is recovered
//! from (the demanding case: the force comes back), not ended.
//!
//! Asserted on the client's `haptic.csv`, around the stall:
//! - no kick: the force never changes by more than 0.5 N in one tick,
//!   twice the largest change of the undisturbed exam (0.24 N per tick in
//!   issue 20; 0.240–0.252 N measured here on undisturbed runs, quiet and
//!   loaded). Released or ramped in, the force moves by at most
//!   `max_force / fade_time · 1 ms = 0.2 N`; tracking, by at most the
//!   renderer's rate limit, 500 N/s = 0.5 N per tick. The failures
//!   reported in issue 20 were 2.0 N per tick (0.15 s stall) and 16 N in
//!   one tick (0.35 s); with the former 2000 N/s limit this test measured
//!   1.87 N (quiet) and 1.99 N (loaded) in one tick after a 0.35 s stall,
//!   when the first models after the stall moved the proxy by 1.6 mm.
//! - no more force than the tissue justifies: the force after the stall
//!   exceeds the force before it by at most what the buffer model's
//!   stiffness gives for the extra depth the hand sank while the force was
//!   released, `k · Δd`, plus one 0.5 N tick. `k` is the pre-stall
//!   stiffness `F / |proxy − device|` times 2: the model grows stiffer with
//!   depth (in the default press of `echothigh run`, from 700 N/m at 3 N
//!   to 1 150 N/m at 9 N, ×1.6 over 8 mm of indentation), and the hand
//!   sinks by up to ~7 mm after a stall (measured: 58.5 → 51.5 mm after a
//!   0.35 s client stop).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_echothigh");
const TOKEN: &str = "00000000000000cd";
const STALLS: [f64; 5] = [0.05, 0.15, 0.35, 1.0, 3.0];
/// Largest force change in one tick (N), see the module docs.
const TICK_BOUND: f64 = 0.5;
/// `haptic.csv` writes forces to 1e-5 N: a difference of two printed
/// values is off by at most 1e-5 N.
const CSV_PRECISION: f64 = 1e-5;

struct Guard(Vec<Child>);

impl Drop for Guard {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("echothigh-stall-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn kill(pid: u32, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill {sig} {pid}");
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Side {
    Server,
    Client,
}

struct Row {
    t: f64,
    force: f64,
    device_y: f64,
    proxy_y: f64,
    model_age: f64,
}

fn rows(csv: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (t, f, dy, py, age) = (
        col("t"),
        col("force"),
        col("device_y"),
        col("proxy_y"),
        col("model_age"),
    );
    lines
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            Row {
                t: v[t],
                force: v[f],
                device_y: v[dy],
                proxy_y: v[py],
                model_age: v[age],
            }
        })
        .collect()
}

/// Loop time of the last complete row of a streamed trace (s; 0 if none).
fn last_time(csv: &Path) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap_or_default();
    let whole = &text[..text.rfind('\n').unwrap_or(0)];
    whole
        .lines()
        .last()
        .and_then(|l| l.split(',').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or(0.0)
}

/// Loop time (s) the stall starts at: sliding in contact.
const STALL_AT: f64 = 2.5;

/// One run: stops `side` for `stall` s once the client's loop is past
/// [`STALL_AT`].
fn run(side: Side, stall: f64, work: &Path) -> Vec<Row> {
    let scenario = work.join("scenario.toml");
    std::fs::write(&scenario, "[coupling]\npeer_timeout = 5.0\n").unwrap();
    let out = work.join(format!("{side:?}-{stall}"));
    std::fs::remove_dir_all(&out).ok();
    let mut server = Command::new(BIN)
        .args([
            "--log",
            "error",
            "physics-server",
            "--listen",
            "127.0.0.1:0",
        ])
        .args(["--token", TOKEN, "--peer-timeout", "5", "--once"])
        .args(["--accept-timeout", "60"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(server.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line.trim().rsplit(' ').next().unwrap().to_string();
    let client = Command::new(BIN)
        .args(["--log", "error", "haptic-client", "--connect", &addr])
        .args(["--token", TOKEN, "--duration", "7", "--scenario"])
        .arg(&scenario)
        .arg("--out")
        .arg(&out)
        .stderr(Stdio::null())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut guard = Guard(vec![server, client]);
    // Stop once the client's loop is 2.5 s into the exam (sliding in
    // contact, 2.0–4.05 s of the default script), read from its streamed
    // trace (flushed every 0.25 s), whatever the start-up took.
    let csv = out.join("haptic.csv");
    let t0 = std::time::Instant::now();
    while last_time(&csv) < STALL_AT {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the client never got to {STALL_AT} s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let victim = guard.0[if side == Side::Server { 0 } else { 1 }].id();
    kill(victim, "-STOP");
    std::thread::sleep(Duration::from_secs_f64(stall));
    kill(victim, "-CONT");
    let status = guard.0[1].wait().unwrap();
    assert!(status.success(), "{side:?} {stall} s: client exit {status}");
    let r = rows(&out.join("haptic.csv"));
    std::fs::remove_dir_all(&out).ok();
    r
}

/// Index of the first tick after the stall: the largest gap between ticks
/// (the client stopped) or the oldest model (the server stopped), looked
/// for where the stall can be: from [`STALL_AT`] to 1.5 s past it (the
/// flush period, the polling and a loaded machine's scheduling delays),
/// plus the stall.
fn stall_end(rows: &[Row], side: Side, stall: f64) -> usize {
    let near = |i: &usize| (STALL_AT..STALL_AT + 1.5 + stall).contains(&rows[*i].t);
    match side {
        Side::Client => (1..rows.len())
            .filter(near)
            .max_by(|&a, &b| {
                let g = |i: usize| rows[i].t - rows[i - 1].t;
                g(a).total_cmp(&g(b))
            })
            .unwrap(),
        Side::Server => (0..rows.len())
            .filter(near)
            .max_by(|&a, &b| rows[a].model_age.total_cmp(&rows[b].model_age))
            .unwrap(),
    }
}

fn check(side: Side, stall: f64, rows: &[Row]) {
    let what = format!("{side:?} stopped {stall} s");
    // No kick anywhere in the run.
    for w in rows.windows(2) {
        let d = (w[1].force - w[0].force).abs();
        assert!(
            d <= TICK_BOUND + CSV_PRECISION,
            "{what}: the force changed by {d:.3} N in one tick at t = {:.3} s ({:.2} -> {:.2} N)",
            w[1].t,
            w[0].force,
            w[1].force
        );
    }
    // A server stall shorter than the stale age (0.1 s) leaves the model in
    // use: nothing is released, the hand does not sink, and the stall is
    // not told apart from the link's jitter in the trace; the bound above
    // is the whole promise there.
    if side == Side::Server && stall < 0.1 {
        return;
    }
    let end = stall_end(rows, side, stall);
    let t_end = rows[end].t;
    let t_start = match side {
        Side::Client => rows[end - 1].t,
        Side::Server => t_end - rows[end].model_age,
    };
    assert!(
        t_end - t_start > 0.8 * stall.min(1.0) - 0.01,
        "{what}: the stall is not visible in the trace (found {:.3} s)",
        t_end - t_start
    );
    // The reference: the force and the buffer model's stiffness in the
    // second before the stall (on a loaded machine the physics may already
    // have been late then, so the last tick well in contact is taken).
    let before: Vec<&Row> = rows
        .iter()
        .filter(|r| r.t >= t_start - 1.0 && r.t < t_start)
        .collect();
    let f0 = before.iter().map(|r| r.force).fold(0.0, f64::max);
    let last = before
        .iter()
        .rev()
        .find(|r| r.force > 5.0)
        .unwrap_or_else(|| panic!("{what}: not in contact in the second before {t_start:.3} s"));
    let k = last.force / (last.proxy_y - last.device_y).abs();
    let mut deepest = last.device_y;
    for r in rows.iter().filter(|r| r.t >= t_start && r.t <= t_end + 1.5) {
        // The thigh's surface is below the probe: deeper is lower y.
        deepest = deepest.min(r.device_y);
        let sink = (last.device_y - deepest).max(0.0);
        let margin = 2.0 * k * sink + TICK_BOUND + CSV_PRECISION;
        assert!(
            r.force <= f0 + margin,
            "{what}: {:.2} N at t = {:.3} s exceeds {f0:.2} N before the stall \
             + {margin:.2} N (sank {:.1} mm, k {k:.0} N/m)",
            r.force,
            r.t,
            sink * 1e3
        );
    }
}

/// The two tests take turns: each needs the machine to itself (or its own
/// load).
static MACHINE: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn stalls(load: bool, which: &[f64]) {
    let _turn = MACHINE.lock().unwrap_or_else(|e| e.into_inner());
    let work = dir(if load { "load" } else { "quiet" });
    let mut spinners = Guard(Vec::new());
    if load {
        for _ in 0..2 {
            spinners.0.push(
                Command::new("sh")
                    .args(["-c", "while :; do :; done"])
                    .spawn()
                    .unwrap(),
            );
        }
    }
    for side in [Side::Server, Side::Client] {
        for &s in which {
            let rows = run(side, s, &work);
            check(side, s, &rows);
        }
    }
    drop(spinners);
    std::fs::remove_dir_all(&work).ok();
}

#[test]
fn sigstop_of_either_side_in_contact_never_kicks() {
    stalls(false, &STALLS);
}

#[test]
fn sigstop_under_cpu_load_never_kicks() {
    stalls(true, &[0.15, 0.35, 1.0]);
}
