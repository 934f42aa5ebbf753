//! `echothigh view`: the trainee's web viewer (issue 8). Starts the live
//! simulation in-process (buffer mode by default) and a local web server that
//! serves the embedded page and streams the state over a WebSocket: the 3D
//! thigh deforming under the probe, the device and proxy markers, the force
//! (rendered and physics, paper Fig. 4), the echographic image, the status,
//! and an exam mode whose answer stays on the server.
//!
//! Loopback only unless `--allow-remote`: the page drives the simulator.

mod assets;
mod display_fit;
mod exam;
pub mod exam_status;
#[cfg(test)]
mod fake;
#[cfg(test)]
mod fake_doppler;
mod flow_frames;
mod frames;
mod idle;
mod image_link;
mod image_pace;
pub mod protocol;
mod records_pages;
mod server;
#[cfg(test)]
mod tests;

use anyhow::{bail, Context, Result};
use echothigh_runtime::live::LiveControl;
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;
use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

pub use exam::sink::{CaseLog, DbSink, MemorySink, RecordSink};
pub use exam::{ExamPlan, ExamSession, OpenAttempt, ResumePoint};
pub use server::ServerConfig;

/// Arguments of `echothigh view`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scenario TOML (defaults built in when absent).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// A case (issue 13): a shipped case's name (`echothigh cases list`) or
    /// a case TOML file; the leg becomes its patient's and its veins carry
    /// its thrombus segments. The caller loads it ([`run`]'s `case`).
    #[arg(long, value_name = "NAME|FILE")]
    pub case: Option<String>,
    /// TCP port; 0 picks a free one (the URL printed says which).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Address to bind; only loopback unless `--allow-remote`.
    #[arg(long, default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    pub bind: IpAddr,
    /// Allow binding a non-loopback address (anyone who reaches it drives the simulator).
    #[arg(long)]
    pub allow_remote: bool,
    /// Rate at which the page receives the state (Hz, 1..=120).
    #[arg(long, default_value_t = 40.0)]
    pub rate: f64,
    /// Close a connection from which nothing arrived for this long (s,
    /// 1..=3600); open pages answer the server's pings, so only dead or
    /// idle clients are closed.
    #[arg(long, default_value_t = idle::DEFAULT_IDLE_TIMEOUT.as_secs_f64())]
    pub idle_timeout: f64,
}

/// Refuses a non-loopback `bind` unless `allow_remote`.
pub fn check_bind(bind: IpAddr, allow_remote: bool) -> Result<()> {
    if !bind.is_loopback() && !allow_remote {
        bail!("--bind {bind} is not a loopback address; pass --allow-remote to serve other hosts");
    }
    Ok(())
}

/// Checks the state push rate (Hz).
pub fn check_rate(rate: f64) -> Result<()> {
    if !(rate.is_finite() && (1.0..=120.0).contains(&rate)) {
        bail!("--rate {rate} is out of range [1, 120] Hz");
    }
    Ok(())
}

/// Checks the idle timeout (s).
pub fn check_idle_timeout(seconds: f64) -> Result<std::time::Duration> {
    if !(seconds.is_finite() && (1.0..=3600.0).contains(&seconds)) {
        bail!("--idle-timeout {seconds} is out of range [1, 3600] s");
    }
    Ok(std::time::Duration::from_secs_f64(seconds))
}

/// The URL a browser opens for a server bound at `addr`.
pub fn url(addr: SocketAddr) -> String {
    format!("http://{addr}/")
}

/// Runs the viewer until Ctrl-C: starts the live system (`runtime::live_system`)
/// from the scenario on `case` (the one `args.case` names, loaded by the
/// caller), serves it, and stops its threads on the way out. Its exam mode
/// is anonymous practice over the built-in case library.
pub fn run(args: Args, case: Option<echothigh_cases::Case>) -> Result<()> {
    let plan = exam::ExamPlan::practice(rand::random())?;
    let session = exam::ExamSession::new(plan, Box::new(exam::sink::MemorySink::default()), true);
    run_with(args, case, session)
}

/// [`run`] with `session` as its exam session (the `exam` command passes a
/// trainee's plan and a database sink).
pub fn run_with(
    args: Args,
    case: Option<echothigh_cases::Case>,
    session: ExamSession,
) -> Result<()> {
    run_with_device(args, case, session, None)
}

/// [`run_with`] with `device` (issue 15, `--device NAME`), when given,
/// driving the probe instead of the page
/// ([`LiveSystem::start_with_device`]): the page shows its clutch, its
/// force and its workspace, and its probe controls are refused.
pub fn run_with_device(
    args: Args,
    case: Option<echothigh_cases::Case>,
    session: ExamSession,
    device: Option<echothigh_runtime::live_device::LiveDevice>,
) -> Result<()> {
    check_bind(args.bind, args.allow_remote)?;
    check_rate(args.rate)?;
    let idle_timeout = check_idle_timeout(args.idle_timeout)?;
    let scenario = Scenario::load(args.scenario.as_deref())?;
    let system = LiveSystem::start_with_device(scenario, case.as_ref(), device)
        .context("starting the live simulation")?;
    let control: Arc<dyn LiveControl> = system.clone();
    let config = ServerConfig {
        state_rate: args.rate,
        allow_remote: args.allow_remote,
        idle_timeout,
        home_case: case,
    };
    let addr = SocketAddr::new(args.bind, args.port);
    let served = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the web server's async runtime")
        .and_then(|rt| rt.block_on(serve(control, addr, config, session, shutdown_signal())));
    let stopped = system.shutdown().context("stopping the live simulation");
    served.and(stopped)
}

/// Resolves on Ctrl-C (or if the signal cannot be installed, never).
async fn shutdown_signal() {
    if tokio::signal::ctrl_c().await.is_err() {
        std::future::pending::<()>().await;
    }
}

/// Binds `addr`, prints the URL on stdout, and serves until `shutdown` resolves.
pub async fn serve(
    control: Arc<dyn LiveControl>,
    addr: SocketAddr,
    config: ServerConfig,
    session: ExamSession,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<()> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("binding {addr}"))?;
    let local = listener.local_addr().context("reading the bound address")?;
    let mut stdout = std::io::stdout();
    writeln!(stdout, "echothigh viewer: {}", url(local))?;
    stdout.flush()?;
    tracing::info!(url = %url(local), "viewer serving");
    serve_on(listener, control, config, session, shutdown).await
}

/// Serves on an already bound `listener` until `shutdown` resolves, with
/// the exam observer thread sampling the live state for `session`; the
/// observer is stopped and joined, and the session's records closed, on the
/// way out.
pub async fn serve_on(
    listener: tokio::net::TcpListener,
    control: Arc<dyn LiveControl>,
    config: ServerConfig,
    session: ExamSession,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<()> {
    let idle_timeout = config.idle_timeout;
    let state = Arc::new(server::AppState::new(control, session, config));
    let observer =
        exam::ExamObserver::spawn(state.clone()).context("starting the exam observer")?;
    let listener = idle::IdleListener::new(listener, idle_timeout);
    let served = axum::serve(listener, server::router(state.clone()))
        .with_graceful_shutdown(shutdown)
        .await
        .context("serving the viewer");
    observer.stop();
    state.end_exam();
    served
}
