//! The two-process deployment of the paper's Fig. 1 (physics on one host,
//! haptics on the host with the device): `echothigh physics-server` and
//! `echothigh haptic-client`, over UDP with a session token.

use super::run::{
    default_out, expected_rows, finish_run, load_scenario, mode_name, write_scenario, ModeArg,
};
use anyhow::{bail, Context, Result};
use echothigh_runtime::client::{run_client, ClientConfig, LoopParts};
use echothigh_runtime::deploy::{client_end, scripted_device, RunOutput, RunStats};
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::physics_loop::{physics_loop, Clock, PhysicsEnd};
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::recorder::{RecordSink, Recording, Streams};
use echothigh_runtime::signals::stop_on_signals;
use echothigh_transport::{
    connect, Link, LinkError, ListenConfig, SessionToken, TokenSource, UdpServer,
};
use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Duration;

/// Arguments of `echothigh physics-server`.
#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:\n  echothigh physics-server\n  \
echothigh physics-server --listen 127.0.0.1:7878 --token 00000000000000aa\n  \
echothigh physics-server --listen 0.0.0.0:7878 --allow-remote")]
pub struct ServerArgs {
    /// Address to listen on (UDP). Loopback unless `--allow-remote`.
    #[arg(long, default_value = "127.0.0.1:7878")]
    pub listen: SocketAddr,
    /// Accept a non-loopback listen address.
    #[arg(long)]
    pub allow_remote: bool,
    /// Session token (16 hex digits); else $ECHOTHIGH_TOKEN; else generated and printed.
    #[arg(long)]
    pub token: Option<String>,
    /// Scenario TOML (default: the built-in one).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// How long to wait for the client (s): a number >= 0, or `inf` to wait
    /// forever.
    #[arg(long, default_value_t = 60.0, value_parser = parse_wait)]
    pub accept_timeout: f64,
    /// Silence of the client after which the server stops (s), in [0.01, 60].
    #[arg(long, default_value_t = 2.0, value_parser = parse_peer_timeout)]
    pub peer_timeout: f64,
    /// Stream the physics trace into this directory (`physics.csv`, flushed
    /// as it goes; every client's session is appended).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Serve one client and exit (by default the server takes a new client
    /// when one leaves, until SIGINT or SIGTERM, or until no client comes
    /// within the accept timeout).
    #[arg(long)]
    pub once: bool,
}

/// Arguments of `echothigh haptic-client`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  echothigh haptic-client --connect 127.0.0.1:7878 --token 00000000000000aa\n  \
ECHOTHIGH_TOKEN=00000000000000aa echothigh haptic-client --connect 127.0.0.1:7878 --mode hold"
)]
pub struct ClientArgs {
    /// Physics server address.
    #[arg(long)]
    pub connect: SocketAddr,
    /// Session token (16 hex digits); else $ECHOTHIGH_TOKEN.
    #[arg(long)]
    pub token: Option<String>,
    /// Scenario TOML (default: the built-in one); its `[coupling]`, `[link]`,
    /// `[haptics]`, `[device]`, `[hand]`, `[exam]` and `[run]` apply here.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Override the coupling mode (`buffer` or `hold`; `direct` needs the physics in-process).
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Override the run duration (s).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Output directory (default: runs/client-<unix time>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Handshake timeout (s): a number >= 0, or `inf` to wait forever.
    #[arg(long, default_value_t = 5.0, value_parser = parse_wait)]
    pub connect_timeout: f64,
    /// The device the haptic loop drives.
    #[command(flatten)]
    pub device: super::device_arg::DeviceArgs,
}

/// Runs the physics server: serves one haptic client after another (a new
/// client can connect when the previous one has left or gone silent) until
/// SIGINT or SIGTERM, or after the first with `--once`.
pub fn server(args: ServerArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), None, None)?;
    let (token, source) = SessionToken::resolve_or_generate(args.token.as_deref())?;
    let accept_timeout = timeout_arg("--accept-timeout", args.accept_timeout)?;
    let peer_timeout = positive_arg("--peer-timeout", args.peer_timeout)?;
    let stop = stop_on_signals()?;
    let mut recording = match &args.trace {
        Some(dir) => {
            let rows = (scenario.coupling.physics_rate * 3600.0) as u64;
            let (rec, _, steps) = Recording::create(
                dir,
                "physics",
                Streams {
                    ticks: false,
                    steps: true,
                },
                rows,
                stop.clone(),
            )?;
            Some((rec, steps))
        }
        None => None,
    };
    let mut listen = args.listen;
    let mut first = true;
    let mut served = 0u32;
    let mut result = Ok(());
    // This thread runs the physics loop: real-time where permitted.
    echothigh_runtime::physics_loop::request_physics_priority(
        scenario.haptics.runner.realtime_priority,
    );
    'sessions: while !stop.load(Ordering::Relaxed) {
        let mut physics = PhysicsSide::new(&scenario)?;
        let clock = Clock::start();
        let rate = scenario.coupling.physics_rate;
        // Wait for a client in slices of a second, so that a signal is seen
        // while waiting (the client repeats its Hello until answered).
        let waited = std::time::Instant::now();
        let mut link = loop {
            if stop.load(Ordering::Relaxed) {
                break 'sessions;
            }
            let listener = UdpServer::bind(&ListenConfig {
                addr: listen,
                allow_remote: args.allow_remote,
            })?;
            listen = listener.local_addr()?;
            if first {
                // stdout may be a pipe its reader has closed: never panic on it.
                let mut out = std::io::stdout();
                let _ = writeln!(out, "physics server listening on {listen}");
                if source == TokenSource::Generated {
                    let _ = writeln!(
                        out,
                        "session token: {token}   (give it to the client: --token {token})"
                    );
                }
                let _ = out.flush();
                first = false;
            }
            let left = accept_timeout.saturating_sub(waited.elapsed());
            if left.is_zero() {
                if served > 0 {
                    // Clients came and went; none for the accept timeout.
                    break 'sessions;
                }
                result = Err(anyhow::anyhow!(
                    "waiting for the haptic client: no client within {} s",
                    accept_timeout.as_secs_f64()
                ));
                break 'sessions;
            }
            let slice = left.min(Duration::from_secs(1));
            match listener.accept(&token, scenario.link_faults().1, rate, slice, clock.now()) {
                Ok(l) => break l,
                Err(LinkError::AcceptTimeout { .. }) => continue,
                Err(e) => {
                    result = Err(anyhow::Error::new(e).context("waiting for the haptic client"));
                    break 'sessions;
                }
            }
        };
        served += 1;
        tracing::info!("haptic client connected");
        let mut discard = RecordSink::Discard;
        let steps = recording.as_mut().map_or(&mut discard, |(_, s)| s);
        let report = physics_loop(
            &mut physics,
            &mut link,
            clock,
            &stop,
            rate,
            peer_timeout,
            steps,
        );
        let report = match report {
            Ok(r) => r,
            Err(e) => {
                result = Err(e);
                break;
            }
        };
        let _ = writeln!(
            std::io::stdout(),
            "physics server: {} steps at {:.1} Hz",
            report.steps,
            report.rate
        );
        match report.end {
            PhysicsEnd::PeerClosed | PhysicsEnd::Stopped => {}
            PhysicsEnd::PeerSilent => tracing::warn!(
                "the haptic client went silent for more than {peer_timeout} s: session ended"
            ),
        }
        if args.once {
            if report.end == PhysicsEnd::PeerSilent {
                result = Err(anyhow::anyhow!(
                    "the haptic client went silent for more than {peer_timeout} s"
                ));
            }
            break;
        }
    }
    if let Some((rec, _)) = recording {
        let dir = rec.dir().to_path_buf();
        rec.finish()?;
        // stdout may be a pipe its reader has closed: never panic on it.
        let _ = writeln!(
            std::io::stdout(),
            "physics trace written to {}",
            dir.join("physics.csv").display()
        );
    }
    result
}

/// A timeout argument (s): `inf` waits forever; NaN and negative values are
/// refused naming the flag.
fn timeout_arg(flag: &str, seconds: f64) -> Result<Duration> {
    if seconds == f64::INFINITY {
        return Ok(Duration::MAX);
    }
    if !(seconds.is_finite() && seconds >= 0.0) {
        bail!("{flag} must be a number of seconds ≥ 0 (or inf), got {seconds}");
    }
    Duration::try_from_secs_f64(seconds).with_context(|| format!("{flag} = {seconds} s"))
}

/// The peer timeout (s), in [0.01, 60]: above a physics period, and below
/// the 60 s of silence the transport's sequence bound allows for
/// (`echothigh_transport::MAX_SEQ_JUMP`).
fn positive_arg(flag: &str, seconds: f64) -> Result<f64> {
    if !(seconds.is_finite() && (0.01..=60.0).contains(&seconds)) {
        bail!("{flag} must be in [0.01, 60] s, got {seconds}");
    }
    Ok(seconds)
}

/// Runs the haptic client: connects, runs the exam, streams its run
/// directory as it goes.
pub fn client(args: ClientArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), args.mode, args.duration)?;
    let c = &scenario.coupling;
    if c.mode == CouplingMode::Direct {
        bail!("coupling.mode = direct needs the physics in-process: use `echothigh run --mode direct`");
    }
    let Some((token, _)) = SessionToken::from_arg_or_env(args.token.as_deref())? else {
        bail!("no session token: pass --token (printed by the server) or set ECHOTHIGH_TOKEN");
    };
    let connect_timeout = timeout_arg("--connect-timeout", args.connect_timeout)?;
    // The device first: a missing driver is said before any file is made.
    let real = args.device.open(scenario.device.kind)?;
    let dir = args.out.clone().unwrap_or_else(|| default_out("client"));
    let stop = stop_on_signals()?;
    // The directory, its free space and its files before connecting.
    let (recording, ticks, _) = Recording::create(
        &dir,
        &mode_name(&scenario),
        Streams {
            ticks: true,
            steps: false,
        },
        expected_rows(&scenario),
        stop.clone(),
    )?;
    write_scenario(&dir, &scenario)?;
    let clock = Clock::start();
    let connected = connect(
        args.connect,
        &token,
        scenario.link_faults().0,
        connect_timeout,
        clock.now(),
    )
    .with_context(|| format!("connecting to the physics server at {}", args.connect));
    let (link, welcome) = match connected {
        Ok(c) => c,
        Err(e) => {
            let _ = recording.finish();
            return Err(e);
        }
    };
    tracing::info!(
        "connected to {}, physics at {} Hz",
        args.connect,
        welcome.physics_rate
    );
    let (sink, source) = haptic_side_for(c.mode, &scenario)?;
    let scale = scenario.device().force_scale();
    let config = ClientConfig {
        loop_config: &scenario.haptics.runner,
        duration: scenario.run.duration,
        peer_timeout: c.peer_timeout,
        stop,
        orientation: scenario.probe_orientation()?,
    };
    let link: Box<dyn Link> = Box::new(link);
    let report = match real {
        Some(device) => {
            let parts = LoopParts {
                device,
                source,
                scale,
                direct_physics: None,
            };
            run_client(Some(link), sink, parts, config, ticks)
        }
        None => {
            let parts = LoopParts {
                device: scripted_device(&scenario)?,
                source,
                scale,
                direct_physics: None,
            };
            run_client(Some(link), sink, parts, config, ticks)
        }
    };
    let recorded = recording.finish();
    let report = report?;
    let recorded = recorded?;
    let out = RunOutput {
        ticks: Vec::new(),
        steps: Vec::new(),
        stats: RunStats {
            missed_deadlines: report.timing.missed_deadlines,
            physics_rate: report.physics_rate,
            faults: report.faults,
            link_dropped: report.link.rejected(),
            dropped_records: report.dropped,
            loop_timing: report.timing,
        },
        end: client_end(report.end),
    };
    if let Some(t) = report.lost_at {
        // Say "faded to zero" only if the last force written was zero.
        let last = recorded.ticks.last().map_or(0.0, |r| {
            (r.force[0].powi(2) + r.force[1].powi(2) + r.force[2].powi(2)).sqrt()
        });
        let faded = if last == 0.0 {
            "force faded to zero".to_string()
        } else {
            format!("force {last:.2} N when the loop stopped, then released to zero")
        };
        finish_run(&dir, &scenario, "processes", &recorded.ticks, &[], &out).ok();
        bail!(
            "the physics server at {} went silent at t = {t:.3} s: {faded}, client stopped (data written to {})",
            args.connect,
            dir.display()
        );
    }
    finish_run(&dir, &scenario, "processes", &recorded.ticks, &[], &out)
}

/// Parses a wait in seconds for `--accept-timeout` / `--connect-timeout`: a
/// number >= 0, or `inf` (also `infinity`) for "wait forever". NaN and
/// negative numbers are refused (they made `Duration::from_secs_f64` panic).
pub fn parse_wait(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds (or `inf`)"))?;
    if v.is_nan() || v < 0.0 {
        return Err(format!(
            "must be >= 0 s or `inf` (wait forever), got {text}"
        ));
    }
    Ok(v)
}

/// Parses `--peer-timeout`: seconds in [0.01, 60], the range of
/// `coupling.peer_timeout` (a silence shorter than 10 ms is one missed
/// datagram; longer than a minute the device would hold a stale force).
pub fn parse_peer_timeout(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(0.01..=60.0).contains(&v) {
        return Err(format!("must be in [0.01, 60] s, got {text}"));
    }
    Ok(v)
}
