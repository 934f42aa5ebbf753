//! The two-process deployment of the paper's Fig. 1 (physics on one host,
//! haptics on the host with the device): `echothigh physics-server` and
//! `echothigh haptic-client`, over UDP with a session token.

use super::run::{default_out, load_scenario, write_run, ModeArg};
use crate::live::CouplingMode;
use crate::runtime::client::{run_client, ClientEnd, LoopParts};
use crate::runtime::deploy::{scripted_device, summarize, RunOutput};
use crate::runtime::haptic_side::haptic_side_for;
use crate::runtime::physics_loop::{physics_loop, Clock, PhysicsEnd};
use crate::runtime::physics_side::PhysicsSide;
use crate::runtime::trace::write_physics;
use anyhow::{bail, Context, Result};
use echothigh_transport::{connect, ListenConfig, SessionToken, TokenSource, UdpServer};
use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
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
    /// Write the physics trace here (CSV).
    #[arg(long)]
    pub trace: Option<PathBuf>,
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
}

/// Runs the physics server until its client leaves or goes silent.
pub fn server(args: ServerArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), None, None)?;
    let (token, source) = SessionToken::resolve_or_generate(args.token.as_deref())?;
    let listener = UdpServer::bind(&ListenConfig {
        addr: args.listen,
        allow_remote: args.allow_remote,
    })?;
    let addr = listener.local_addr()?;
    let mut physics = PhysicsSide::new(&scenario)?;
    // stdout may be a pipe its reader has closed: never panic on it.
    let mut out = std::io::stdout();
    let _ = writeln!(out, "physics server listening on {addr}");
    if source == TokenSource::Generated {
        let _ = writeln!(
            out,
            "session token: {token}   (give it to the client: --token {token})"
        );
    }
    let _ = out.flush();
    let clock = Clock::start();
    let rate = scenario.coupling.physics_rate;
    let mut link = listener
        .accept(
            token.0,
            scenario.link_faults().1,
            rate,
            wait_duration(args.accept_timeout),
            clock.now(),
        )
        .context("waiting for the haptic client")?;
    tracing::info!("haptic client connected");
    let mut records = Vec::with_capacity(((3600.0 * rate) as usize).min(1 << 20));
    let stop = AtomicBool::new(false);
    let report = physics_loop(
        &mut physics,
        &mut link,
        clock,
        &stop,
        rate,
        args.peer_timeout,
        &mut records,
    )?;
    if let Some(p) = &args.trace {
        write_physics(p, &records)?;
    }
    let _ = writeln!(
        std::io::stdout(),
        "physics server: {} steps at {:.1} Hz",
        report.steps,
        report.rate
    );
    match report.end {
        PhysicsEnd::PeerClosed | PhysicsEnd::Stopped => Ok(()),
        PhysicsEnd::PeerSilent => bail!(
            "the haptic client went silent for more than {} s",
            args.peer_timeout
        ),
    }
}

/// Runs the haptic client for the scenario's exam.
pub fn client(args: ClientArgs) -> Result<()> {
    let scenario = load_scenario(args.scenario.as_deref(), args.mode, args.duration)?;
    let c = &scenario.coupling;
    if c.mode == CouplingMode::Direct {
        bail!("coupling.mode = direct needs the physics in-process: use `echothigh run --mode direct`");
    }
    let Some((token, _)) = SessionToken::from_arg_or_env(args.token.as_deref())? else {
        bail!("no session token: pass --token (printed by the server) or set ECHOTHIGH_TOKEN");
    };
    let clock = Clock::start();
    let (link, welcome) = connect(
        args.connect,
        token.0,
        scenario.link_faults().0,
        wait_duration(args.connect_timeout),
        clock.now(),
    )
    .with_context(|| format!("connecting to the physics server at {}", args.connect))?;
    tracing::info!(
        "connected to {}, physics at {} Hz",
        args.connect,
        welcome.physics_rate
    );
    let device = scripted_device(&scenario)?;
    let (sink, source) = haptic_side_for(c.mode, &scenario)?;
    let parts = LoopParts {
        device,
        source,
        scale: scenario.device.force_scale(),
        direct_physics: None,
    };
    let report = run_client(
        Some(Box::new(link)),
        sink,
        parts,
        &scenario.haptics.runner,
        scenario.run.duration,
        c.peer_timeout,
    )?;
    let summary = summarize(
        &scenario,
        "processes",
        &report.ticks,
        &[],
        report.timing.missed_deadlines,
        scenario.run.duration,
        report.physics_rate,
        report.faults,
        report.link.duplicate + report.link.stale + report.link.malformed,
        0,
    );
    let out = RunOutput {
        ticks: report.ticks,
        steps: Vec::new(),
        summary,
        peer_lost: report.end == ClientEnd::PeerLost,
    };
    let dir = args.out.clone().unwrap_or_else(|| default_out("client"));
    write_run(&dir, &scenario, &out)?;
    println!("haptic client: run written to {}", dir.display());
    if let Some(t) = report.lost_at {
        bail!(
            "the physics server at {} went silent at t = {t:.3} s: force faded to zero, client stopped (data written to {})",
            args.connect,
            dir.display()
        );
    }
    Ok(())
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

/// The wait as a `Duration`: `inf` (or any wait past `Duration::MAX`, ~585
/// billion years) is `Duration::MAX`, which the handshakes compare against
/// the elapsed time and never add to an instant.
pub fn wait_duration(seconds: f64) -> Duration {
    Duration::try_from_secs_f64(seconds).unwrap_or(Duration::MAX)
}
