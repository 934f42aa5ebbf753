//! `echothigh bench link`: the physics–haptics exchange. Loopback round-trip
//! latency (median, p99) over UDP and over the in-process link, and the
//! physics and haptic rates `echothigh run` achieves in each deployment.

use crate::cmd::run::load_scenario;
use anyhow::{Context, Result};
use echothigh_runtime::deploy::{run_threads, summarize};
use echothigh_runtime::recorder::RecordSink;
use echothigh_transport::{
    connect, in_process_pair, measure_round_trips, EchoResponder, FaultConfig, ListenConfig,
    RoundTripReport, SessionToken, UdpServer,
};
use serde_json::json;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

/// Arguments of `echothigh bench link`.
#[derive(clap::Args, Debug)]
#[command(after_help = "Example:\n  echothigh bench link --json --out link.json")]
pub struct Args {
    /// Print JSON on stdout (the table goes to stderr either way).
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON report here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Round trips per transport.
    #[arg(long, default_value_t = 2000)]
    pub count: usize,
    /// Duration of each deployment run (s).
    #[arg(long, default_value_t = 3.0)]
    pub seconds: f64,
}

fn rtt_json(r: &Option<RoundTripReport>) -> serde_json::Value {
    match r {
        Some(r) => json!({"count": r.count, "min_us": r.min * 1e6, "median_us": r.median * 1e6,
                          "p99_us": r.p99 * 1e6, "max_us": r.max * 1e6}),
        None => serde_json::Value::Null,
    }
}

/// Runs the benchmark.
pub fn run(args: Args) -> Result<()> {
    let timeout = Duration::from_secs(1);
    // In-process link.
    let (mut a, b) = in_process_pair(1, FaultConfig::default(), FaultConfig::default());
    let echo = EchoResponder::spawn(b);
    let in_process = measure_round_trips(&mut a, 100, args.count, timeout)?;
    echo.stop()?;
    // UDP over loopback.
    let server = UdpServer::bind(&ListenConfig {
        addr: "127.0.0.1:0".parse()?,
        allow_remote: false,
    })?;
    let addr = server.local_addr()?;
    let token = SessionToken::generate();
    let accept = std::thread::spawn(move || {
        server.accept(
            &token,
            FaultConfig::default(),
            100.0,
            Duration::from_secs(5),
            0.0,
        )
    });
    let (mut client, _) = connect(
        addr,
        &token,
        FaultConfig::default(),
        Duration::from_secs(5),
        0.0,
    )?;
    let server_end = accept
        .join()
        .map_err(|_| anyhow::anyhow!("accept thread panicked"))??;
    let echo = EchoResponder::spawn(server_end);
    let udp = measure_round_trips(&mut client, 100, args.count, timeout)?;
    echo.stop()?;

    // Achieved rates of `run`, in threads and in two processes.
    let scenario = load_scenario(None, None, Some(args.seconds))?;
    let c = &scenario.coupling;
    let rows = |rate: f64| (args.seconds * rate * 1.5) as usize + 16;
    let out = run_threads(
        &scenario,
        Arc::new(AtomicBool::new(false)),
        RecordSink::memory(rows(c.haptic_rate)),
        RecordSink::memory(rows(c.physics_rate)),
    )
    .context("threads deployment")?;
    let threads = summarize(
        &scenario, "threads", &out.ticks, &out.steps, &out.stats, out.end,
    );
    let processes = run_processes(args.seconds)?;
    let report = json!({
        "round_trip": {"in_process": rtt_json(&in_process), "udp_loopback": rtt_json(&udp)},
        "run": {
            "threads": {"physics_rate_hz": threads.physics_rate, "haptic_rate_hz": threads.haptic_rate,
                        "missed_deadlines": threads.missed_deadlines, "seconds": args.seconds},
            "processes": processes,
        },
        "machine": {"cores": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)},
    });
    let text = serde_json::to_string_pretty(&report)?;
    eprintln!("{text}");
    if args.json {
        println!("{text}");
    }
    if let Some(p) = &args.out {
        std::fs::write(p, text + "\n").with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// Runs `physics-server` and `haptic-client` as two child processes of this
/// binary and reads the client's summary.
fn run_processes(seconds: f64) -> Result<serde_json::Value> {
    let exe = std::env::current_exe().context("locating the echothigh binary")?;
    let token = "00000000be4c0001";
    let mut server = Command::new(&exe)
        .args([
            "--log",
            "warn",
            "physics-server",
            "--listen",
            "127.0.0.1:0",
            "--token",
            token,
        ])
        .stdout(Stdio::piped())
        .spawn()
        .context("starting physics-server")?;
    let mut line = String::new();
    BufReader::new(server.stdout.take().context("server stdout")?).read_line(&mut line)?;
    let addr = line
        .trim()
        .rsplit(' ')
        .next()
        .unwrap_or_default()
        .to_string();
    let dir = std::env::temp_dir().join(format!("echothigh-bench-link-{}", std::process::id()));
    let status = Command::new(&exe)
        .args([
            "--log",
            "warn",
            "haptic-client",
            "--connect",
            &addr,
            "--token",
            token,
            "--duration",
        ])
        .arg(seconds.to_string())
        .arg("--out")
        .arg(&dir)
        .status()
        .context("running haptic-client")?;
    let _ = server.wait();
    anyhow::ensure!(status.success(), "haptic-client failed: {status}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json"))?)?;
    std::fs::remove_dir_all(&dir).ok();
    Ok(
        json!({"haptic_rate_hz": summary["haptic_rate"], "missed_deadlines": summary["missed_deadlines"],
              "physics_rate_hz": summary["physics_rate"], "seconds": seconds}),
    )
}
