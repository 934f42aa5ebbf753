//! The viewer's web server: the embedded page and the `/ws` WebSocket.
//!
//! One task per connection pushes the live state at [`ServerConfig::state_rate`]
//! (JSON scalars, the surface nodes that moved and — when a new one exists —
//! the echographic image as a PNG or a PNG of its change, see
//! [`super::frames`]), with flow control: a new state only when the page has
//! acknowledged all but [`CREDIT`] − 1 of those sent, within a byte budget
//! ([`super::frames::BYTES_PER_SECOND`]), always the latest (never a
//! backlog). Commands run off the async executor. The exam session is shared by all connections and
//! lives only here, so the hidden vein state never reaches the page before it
//! is answered.

use super::assets;
use super::display_fit::DisplayFit;
use super::exam::ExamSession;
use super::frames::{ByteBudget, WireState, BURST_BYTES, BYTES_PER_SECOND};
use super::image_link::{ImageLinks, LinkEvent};
use super::image_pace::ImagePace;
use super::protocol::{
    decode_client, ClientMessage, Envelope, FrameHeader, FrameKind, ServerMessage, ViewState,
    ViewerCommand, CREDIT, PROTOCOL_VERSION,
};
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::{header, HeaderMap, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use echothigh_runtime::live::{LiveCommand, LiveControl, LiveSnapshot};
use echothigh_runtime::live_doppler::DopplerMode;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

/// Server settings.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Rate at which each connection receives the state (Hz, 1..=120).
    pub state_rate: f64,
    /// Accept any `Host` (the server was bound to a non-loopback address on
    /// purpose, `--allow-remote`); otherwise only loopback host names.
    pub allow_remote: bool,
    /// A connection (HTTP or WebSocket) from which nothing was read for this
    /// long is closed ([`super::idle`]); pages are pinged every third of it.
    pub idle_timeout: Duration,
    /// The case whose leg the server started with (`view --case`; `None`:
    /// the scenario's own leg). Leaving the exam puts it back.
    pub home_case: Option<echothigh_cases::Case>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            state_rate: 40.0,
            allow_remote: false,
            idle_timeout: super::idle::DEFAULT_IDLE_TIMEOUT,
            home_case: None,
        }
    }
}

/// What every connection shares.
pub struct AppState {
    control: Arc<dyn LiveControl>,
    exam: Mutex<ExamSession>,
    config: ServerConfig,
    /// The connection that drives the probe (the first one; `None` once it
    /// closed), and the last connection number given.
    owner: Mutex<(Option<u64>, u64)>,
    /// Grows when the live mesh changes (a case's leg loaded): each
    /// connection then sends a new `hello` with the mesh.
    mesh_epoch: std::sync::atomic::AtomicU64,
    /// Whether the live leg is an exam case's (loaded by `exam_start`), to
    /// be replaced by the home case's when the trainee leaves the exam.
    exam_leg: std::sync::atomic::AtomicBool,
    /// The image sockets offered to the connections' workers.
    image_links: ImageLinks,
}

impl AppState {
    /// Wraps the live system; `exam` holds the trainee's session.
    /// A server's state over `control`, with the exam session `exam`. A
    /// resumed session's case under way is loaded into the live system at
    /// once (its leg, its thrombi); if it cannot be, the case is dropped
    /// unscored (its records stay) and the page is told why.
    pub fn new(control: Arc<dyn LiveControl>, mut exam: ExamSession, config: ServerConfig) -> Self {
        let mut exam_leg = false;
        if let Some(case) = exam.open_case().cloned() {
            match control.set_case(Some(&case)) {
                Ok(()) => exam_leg = true,
                Err(e) => {
                    exam.abandon();
                    exam.report(format!("could not load the resumed case: {e}"));
                }
            }
        }
        Self {
            control,
            exam: Mutex::new(exam),
            config,
            owner: Mutex::new((None, 0)),
            mesh_epoch: std::sync::atomic::AtomicU64::new(0),
            exam_leg: std::sync::atomic::AtomicBool::new(exam_leg),
            image_links: ImageLinks::default(),
        }
    }

    /// A new connection's number; it drives the probe if nobody does.
    fn join(&self) -> u64 {
        let mut o = self.owner.lock().unwrap_or_else(|e| e.into_inner());
        o.1 += 1;
        let id = o.1;
        o.0.get_or_insert(id);
        id
    }

    /// Whether connection `id` drives the probe; `claim` makes it the
    /// driver if nobody is.
    fn drives(&self, id: u64, claim: bool) -> bool {
        let mut o = self.owner.lock().unwrap_or_else(|e| e.into_inner());
        if claim && o.0.is_none() {
            o.0 = Some(id);
        }
        o.0 == Some(id)
    }

    /// Connection `id` closed: if it drove, nobody drives until a tab asks.
    fn leave(&self, id: u64) {
        let mut o = self.owner.lock().unwrap_or_else(|e| e.into_inner());
        if o.0 == Some(id) {
            o.0 = None;
        }
    }

    /// The server is stopping: an open case stays unfinished in the
    /// records, and the session stays open for the next server to resume
    /// unless it is over ([`ExamSession::suspend`]).
    pub(crate) fn end_exam(&self) {
        self.exam().suspend();
    }

    /// Copies the live state into `out`.
    pub(crate) fn snapshot_into(&self, out: &mut LiveSnapshot) {
        self.control.snapshot(out);
    }

    /// The exam session (a poisoned lock is recovered: the session is plain data).
    fn exam(&self) -> MutexGuard<'_, ExamSession> {
        self.exam.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Applies one decoded page message; `Err` is the text sent back to the page.
    fn apply(&self, msg: ClientMessage) -> Result<(), String> {
        match msg {
            ClientMessage::Live(LiveCommand::SetVein { .. }) if self.exam().is_open() => Err(
                "the vein is the case's during an exam: finish the case or leave the exam first"
                    .into(),
            ),
            // A real device drives the probe (issue 15): the page only watches it.
            ClientMessage::Live(
                LiveCommand::Probe { .. } | LiveCommand::Lift | LiveCommand::PlayExam,
            ) if self.control.driving_device().is_some() => {
                let name = self.control.driving_device().unwrap_or_default();
                Err(echothigh_runtime::live_system::device_drives_message(&name))
            }
            ClientMessage::Live(cmd @ LiveCommand::Probe { .. }) => {
                self.control.command(cmd)?;
                self.exam().trainee_pressed();
                Ok(())
            }
            ClientMessage::Live(cmd) => self.control.command(cmd),
            ClientMessage::Doppler(cmd) => self.control.doppler(cmd),
            ClientMessage::Viewer(ViewerCommand::ExamStart) => {
                // The exam lock is not held across the case's loading (a
                // rebuild of the physics): the other connections' pushes
                // and the observer read the exam status meanwhile.
                let case = self.exam().start().map_err(|e| e.to_string())?.clone();
                if let Err(e) = self.control.set_case(Some(&case)) {
                    self.exam().abandon();
                    return Err(format!("could not load the exam's case: {e}"));
                }
                self.exam_leg
                    .store(true, std::sync::atomic::Ordering::Release);
                // The patient's leg has its own rest shape.
                self.mesh_epoch
                    .fetch_add(1, std::sync::atomic::Ordering::AcqRel);
                Ok(())
            }
            ClientMessage::Viewer(ViewerCommand::ExamCall { site, finding }) => {
                self.exam().call(&site, finding).map_err(|e| e.to_string())
            }
            ClientMessage::Viewer(ViewerCommand::ExamDoppler {
                site,
                flow,
                augments,
            }) => self
                .exam()
                .call_doppler(&site, echothigh_exam::DopplerFinding { flow, augments })
                .map_err(|e| e.to_string()),
            ClientMessage::Viewer(ViewerCommand::ExamFinish) => {
                self.exam().finish().map_err(|e| e.to_string())
            }
            ClientMessage::Viewer(ViewerCommand::ExamStop) => {
                self.exam().stop();
                // Back to the leg the server started with, whose vein the
                // page's vein control sets again.
                if self
                    .exam_leg
                    .swap(false, std::sync::atomic::Ordering::AcqRel)
                {
                    self.control
                        .set_case(self.config.home_case.as_ref())
                        .map_err(|e| format!("could not restore the practice leg: {e}"))?;
                    self.mesh_epoch
                        .fetch_add(1, std::sync::atomic::Ordering::AcqRel);
                }
                Ok(())
            }
            // Flow control and ownership, handled by the connection itself.
            ClientMessage::Viewer(
                ViewerCommand::Ack { .. }
                | ViewerCommand::ImageAck
                | ViewerCommand::ImageSize { .. }
                | ViewerCommand::TakeControl,
            ) => Ok(()),
        }
    }

    /// Builds the state message from `snap`; the exam status goes with it
    /// only when it changed since `exam_rev` (the connection's last one).
    fn view_state(&self, snap: &LiveSnapshot, exam_rev: &mut Option<u64>) -> ViewState {
        let exam = self.exam();
        let vein = (!exam.is_open()).then(|| self.control.vein());
        let status = exam.status();
        let changed = *exam_rev != Some(status.rev);
        *exam_rev = Some(status.rev);
        ViewState::from_snapshot(snap, vein, changed.then(|| status.clone()))
    }

    /// Feeds the exam session one sample of `snap` taken at `now` (the
    /// exam observer's tick): nothing while no case is open or the trainee
    /// has not moved the probe, or before the imaging thread's first
    /// reading of the section.
    pub(crate) fn observe_exam(&self, snap: &LiveSnapshot, now: std::time::Instant) {
        let mut exam = self.exam();
        let Some(t) = exam.case_time(now) else {
            return;
        };
        let Some(sample) = super::exam::sample(&snap.status, t) else {
            return;
        };
        if let Err(e) = exam.observe(&sample) {
            tracing::warn!("exam sample: {e}");
            exam.report(e.to_string());
        }
    }
}

/// The routes: `/ws` and the embedded files.
pub fn router(state: Arc<AppState>) -> Router {
    Router::new()
        .route("/ws", get(ws_upgrade))
        .route("/ws/image", get(image_upgrade))
        .route("/records", get(instructor_page))
        .route("/records/{name}", get(trainee_page))
        .fallback(get(serve_asset))
        .with_state(state)
}

/// Whether the request's `Host` names this machine's loopback
/// (`localhost`, `127.0.0.0/8`, `[::1]`, with any port). A page on another
/// site that a DNS-rebinding attack points at 127.0.0.1 still sends its own
/// host name, so checking `Origin` against `Host` alone lets it through
/// (issue 20, item 8); requiring a loopback `Host` does not.
pub fn loopback_host(headers: &HeaderMap) -> bool {
    let Some(host) = headers.get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return false;
    };
    let name = if let Some(rest) = host.strip_prefix('[') {
        // [v6]:port
        match rest.split_once(']') {
            Some((v6, _)) => {
                return v6
                    .parse::<std::net::Ipv6Addr>()
                    .is_ok_and(|a| a.is_loopback())
            }
            None => return false,
        }
    } else {
        host.rsplit_once(':').map_or(host, |(n, port)| {
            if port.chars().all(|c| c.is_ascii_digit()) {
                n
            } else {
                host
            }
        })
    };
    name.eq_ignore_ascii_case("localhost")
        || name
            .parse::<std::net::Ipv4Addr>()
            .is_ok_and(|a| a.is_loopback())
}

/// Refuses a request whose `Host` is not loopback, unless remote access was
/// allowed.
fn host_refused(app: &AppState, headers: &HeaderMap) -> Option<Response> {
    (!app.config.allow_remote && !loopback_host(headers)).then(|| {
        (
            StatusCode::FORBIDDEN,
            "refused: Host is not a loopback name (start with --allow-remote to serve other names)",
        )
            .into_response()
    })
}

/// Serves an embedded file, or 404.
async fn serve_asset(uri: Uri, headers: HeaderMap, State(app): State<Arc<AppState>>) -> Response {
    if let Some(r) = host_refused(&app, &headers) {
        return r;
    }
    match assets::lookup(uri.path()) {
        Some(a) => (
            [
                (header::CONTENT_TYPE, a.content_type),
                (header::CACHE_CONTROL, "no-cache"),
                (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
            ],
            a.body,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "not found").into_response(),
    }
}

/// `/records`: the instructor's page (every trainee), read-only.
async fn instructor_page(headers: HeaderMap, State(app): State<Arc<AppState>>) -> Response {
    records_page(&app, &headers, |store| {
        let t = store.trainees()?;
        Ok(super::records_pages::instructor(&t, store.name()))
    })
    .await
}

/// `/records/{name}`: one trainee's history, read-only.
async fn trainee_page(
    axum::extract::Path(name): axum::extract::Path<String>,
    headers: HeaderMap,
    State(app): State<Arc<AppState>>,
) -> Response {
    records_page(&app, &headers, move |store| {
        let h = store.history(&name)?;
        Ok(super::records_pages::trainee(&h, store.name()))
    })
    .await
}

/// Renders a record page from the exam session's database, off the async
/// executor (the store's calls block); 404 when the session records
/// nothing (practice), 500 with the database's message on an error.
async fn records_page(
    app: &Arc<AppState>,
    headers: &HeaderMap,
    render: impl FnOnce(&echothigh_records::BlockingStore) -> Result<String, echothigh_records::RecordsError>
        + Send
        + 'static,
) -> Response {
    if let Some(r) = host_refused(app, headers) {
        return r;
    }
    let Some(store) = app.exam().store() else {
        return (
            StatusCode::NOT_FOUND,
            "this viewer records nothing (practice); start it with `echothigh exam --trainee NAME` to keep records",
        )
            .into_response();
    };
    let html = tokio::task::spawn_blocking(move || render(&store)).await;
    match html {
        Ok(Ok(page)) => (
            [
                (header::CONTENT_TYPE, "text/html; charset=utf-8"),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            page,
        )
            .into_response(),
        Ok(Err(e)) => (
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the records database: {e}"),
        )
            .into_response(),
        Err(e) => (
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the record page failed: {e}"),
        )
            .into_response(),
    }
}

/// Whether a browser's `Origin` is this server (blocks other web sites from
/// driving the simulator through the trainee's browser). Clients that send
/// no `Origin` (not browsers) are allowed.
pub fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
    match (origin.to_str().ok(), host) {
        (Some(origin), Some(host)) => {
            origin
                .strip_prefix("http://")
                .or_else(|| origin.strip_prefix("https://"))
                == Some(host)
        }
        _ => false,
    }
}

/// Why a WebSocket upgrade is refused, if it is: a host name that is not
/// this machine's loopback ([`host_refused`]), or another site's page
/// ([`same_origin`]).
fn socket_refused(app: &AppState, headers: &HeaderMap) -> Option<Response> {
    if let Some(r) = host_refused(app, headers) {
        return Some(r);
    }
    (!same_origin(headers))
        .then(|| (StatusCode::FORBIDDEN, "cross-origin WebSocket refused").into_response())
}

async fn ws_upgrade(
    ws: WebSocketUpgrade,
    headers: HeaderMap,
    State(app): State<Arc<AppState>>,
) -> Response {
    if let Some(r) = socket_refused(&app, &headers) {
        return r;
    }
    ws.max_message_size(64 * 1024)
        .on_upgrade(move |socket| session(socket, app))
}

/// The image socket of a connection's worker ([`super::image_link`]):
/// `?token=` the hex token of that connection's `hello`; refused (404)
/// when no open connection offers it, and with the checks of `/ws`.
async fn image_upgrade(
    ws: WebSocketUpgrade,
    headers: HeaderMap,
    Query(query): Query<std::collections::HashMap<String, String>>,
    State(app): State<Arc<AppState>>,
) -> Response {
    if let Some(r) = socket_refused(&app, &headers) {
        return r;
    }
    let token = query
        .get("token")
        .and_then(|t| u64::from_str_radix(t, 16).ok());
    let Some(token) = token.filter(|&t| app.image_links.offered(t)) else {
        return (
            StatusCode::NOT_FOUND,
            "no open connection offers this image token (token: the hex `image_link` of its hello)",
        )
            .into_response();
    };
    let ping = app.config.idle_timeout / 3;
    ws.max_message_size(4 * 1024)
        .on_upgrade(move |socket| async move { app.image_links.serve(socket, token, ping).await })
}

/// Serialises a server message (serialising these types cannot fail).
fn json(body: ServerMessage) -> Message {
    let text = serde_json::to_string(&Envelope::new(body)).unwrap_or_else(|e| {
        format!(r#"{{"v":{PROTOCOL_VERSION},"type":"error","message":"encoding: {e}"}}"#)
    });
    Message::Text(Utf8Bytes::from(text))
}

/// A page looking at the live state, from its connection to its close
/// ([`LiveControl::page_opened`]), with its connection number.
struct PageWatch(Arc<AppState>, u64);

impl PageWatch {
    fn new(app: Arc<AppState>) -> Self {
        app.control.page_opened();
        let id = app.join();
        Self(app, id)
    }
}

impl Drop for PageWatch {
    fn drop(&mut self) {
        self.0.leave(self.1);
        self.0.control.page_closed();
    }
}

/// What one connection knows of its page: its number, states sent and
/// acknowledged, the frames it holds ([`WireState`]), its byte budget.
struct Conn {
    id: u64,
    sent: u64,
    acked: u64,
    /// An image frame is on its way or being decoded by the page.
    image_pending: bool,
    wire: WireState,
    /// The page's display box, and the frame reduced to it.
    fit: DisplayFit,
    /// When the next image may go ([`ImagePace`]).
    pace: ImagePace,
    /// Until when (s on `epoch`) this page's images answer its last probe
    /// command ([`super::image_pace::RESPONSE_WINDOW`]).
    respond_until: f64,
    /// The simulated time (s) of the newest state this connection had when
    /// that command came: a frame of an older state cannot show it.
    command_time: f64,
    /// A frame left unsent for that reason (not read again).
    skipped: u64,
    budget: ByteBudget,
    epoch: tokio::time::Instant,
    snap: LiveSnapshot,
    pixels: Vec<u8>,
    /// The colour overlay of the last image read (issue 17).
    overlay: Vec<u8>,
    /// The number of the next spectral line to send, and the lines read.
    next_line: u64,
    lines: echothigh_runtime::live_doppler::SpectralLines,
    /// The exam status's revision last sent on this connection.
    exam_rev: Option<u64>,
    /// [`AppState::mesh_epoch`] of the mesh this connection sent.
    mesh_epoch: u64,
    /// The token of this connection's image link, as its hello says it.
    image_link: Option<String>,
}

impl Conn {
    fn new(id: u64) -> Self {
        Self {
            id,
            sent: 0,
            acked: 0,
            image_pending: false,
            wire: WireState::default(),
            fit: DisplayFit::default(),
            pace: ImagePace::default(),
            respond_until: f64::NEG_INFINITY,
            command_time: f64::NEG_INFINITY,
            skipped: 0,
            budget: ByteBudget::new(BYTES_PER_SECOND, BURST_BYTES, 0.0),
            epoch: tokio::time::Instant::now(),
            snap: LiveSnapshot::default(),
            pixels: Vec::new(),
            overlay: Vec::new(),
            next_line: 0,
            lines: Default::default(),
            exam_rev: None,
            mesh_epoch: 0,
            image_link: None,
        }
    }
}

/// Handles a page message: an acknowledgement at once, anything else off
/// the async executor, since a command may restart the simulation's threads
/// (stopping and joining them), which must not stall the other connections
/// (issue 16).
async fn handle_text(app: &Arc<AppState>, conn: &mut Conn, text: &str) -> Vec<Message> {
    let decoded = decode_client(text, &app.control.limits());
    if let Ok(ClientMessage::Viewer(ViewerCommand::Ack { seq })) = decoded {
        // Only what was sent can be acknowledged.
        conn.acked = conn.acked.max(seq.min(conn.sent));
        return Vec::new();
    }
    if let Ok(ClientMessage::Viewer(ViewerCommand::ImageAck)) = decoded {
        conn.image_pending = false;
        return Vec::new();
    }
    if let Ok(ClientMessage::Viewer(ViewerCommand::ImageSize { width, height })) = decoded {
        // What this page shows, not what the simulation does: an observer
        // sets its own.
        conn.fit.set_display(width, height);
        return Vec::new();
    }
    let claim = matches!(
        decoded,
        Ok(ClientMessage::Viewer(ViewerCommand::TakeControl))
    );
    let moves_probe = matches!(
        decoded,
        Ok(ClientMessage::Live(
            LiveCommand::Probe { .. } | LiveCommand::Lift
        ))
    );
    if decoded.is_ok() && !app.drives(conn.id, claim) {
        return vec![json(ServerMessage::Error {
            message: "this tab only observes: another tab drives the probe (close it, then take control here)".into(),
        })];
    }
    if moves_probe {
        // The frames that show this command's effect go first (issue 19).
        conn.respond_until =
            conn.epoch.elapsed().as_secs_f64() + super::image_pace::RESPONSE_WINDOW;
        conn.command_time = conn.snap.status.time;
    }
    let app = app.clone();
    tokio::task::spawn_blocking(move || reply(&app, decoded))
        .await
        .unwrap_or_else(|e| {
            tracing::error!("a page command failed: {e}");
            vec![json(ServerMessage::Error {
                message: format!("the command failed inside the server: {e}"),
            })]
        })
}

/// One connection: hello, then state pushes and commands until it closes.
async fn session(mut socket: WebSocket, app: Arc<AppState>) {
    let watch = PageWatch::new(app.clone());
    let mut link = app.image_links.offer();
    let hello = ServerMessage::Hello {
        mesh: app.control.mesh(),
        state_rate: app.config.state_rate,
        image: app.control.image_geometry(),
        image_link: Some(format!("{:x}", link.token)),
    };
    if socket.send(json(hello)).await.is_err() {
        link.close(&app.image_links);
        return;
    }
    let period = Duration::from_secs_f64(1.0 / app.config.state_rate.clamp(1.0, 120.0));
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    // A new image goes as soon as it is rendered (within this poll's
    // period), not at the next state push (up to 25 ms later at 40 Hz):
    // the poll reads the frame counter, an atomic, 200 times a second.
    let mut image_poll = tokio::time::interval(IMAGE_POLL);
    image_poll.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut ping = tokio::time::interval(app.config.idle_timeout / 3);
    ping.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut conn = Conn::new(watch.1);
    conn.image_link = Some(format!("{:x}", link.token));
    loop {
        let outgoing: Vec<Message> = tokio::select! {
            incoming = socket.recv() => match incoming {
                None | Some(Err(_)) | Some(Ok(Message::Close(_))) => break,
                Some(Ok(Message::Text(text))) => handle_text(&app, &mut conn, text.as_str()).await,
                Some(Ok(Message::Binary(_))) => {
                    reply(&app, Err(super::protocol::ProtocolError::Binary))
                }
                Some(Ok(Message::Ping(_) | Message::Pong(_))) => Vec::new(),
            },
            _ = tick.tick() => push(&app, &mut conn),
            _ = image_poll.tick() => poll_image(&app, &mut conn),
            _ = ping.tick() => vec![Message::Ping(Default::default())],
            event = link.event() => {
                // An acknowledgement on the worker's socket, or the worker
                // gone (its image will never be acknowledged): the next
                // image may go.
                if event != LinkEvent::Attached {
                    conn.image_pending = false;
                }
                Vec::new()
            }
        };
        for m in outgoing {
            // Images go to the page's worker when it has its socket.
            let m = if is_image(&m) {
                match link.send(m) {
                    Ok(()) => continue,
                    Err(m) => m,
                }
            } else {
                m
            };
            if socket.send(m).await.is_err() {
                link.close(&app.image_links);
                return;
            }
        }
    }
    link.close(&app.image_links);
}

/// Whether `m` is an image frame (of the kinds [`push_image`] sends).
fn is_image(m: &Message) -> bool {
    match m {
        Message::Binary(b) => matches!(
            FrameHeader::parse(b),
            Some((h, _)) if matches!(h.kind, FrameKind::ImageJpeg | FrameKind::ImageJpegFlow)
        ),
        _ => false,
    }
}

/// The reply to a page message: nothing, or an error message.
fn reply(
    app: &AppState,
    decoded: Result<ClientMessage, super::protocol::ProtocolError>,
) -> Vec<Message> {
    let outcome = decoded
        .map_err(|e| e.to_string())
        .and_then(|msg| app.apply(msg));
    match outcome {
        Ok(()) => Vec::new(),
        Err(message) => {
            tracing::debug!(%message, "refused a page message");
            vec![json(ServerMessage::Error { message })]
        }
    }
}

/// The messages of one state push, latest wins: nothing while [`CREDIT`]
/// states are unacknowledged; else the state, then the streams that wait
/// for the byte budget ([`push_streams`]). Between pushes, a new image
/// goes as soon as it is rendered ([`poll_image`]).
fn push(app: &AppState, conn: &mut Conn) -> Vec<Message> {
    conn.budget.refill(conn.epoch.elapsed().as_secs_f64());
    // The state goes whenever the credit allows, and spends from the byte
    // budget like the rest: ~0.7 KB at 40 Hz, it no longer waits behind
    // the images that spent the budget (issue 19: the page took 15 of the
    // 40 states/s and a command's effect waited for the next one). The
    // budget's bound then holds up to the states sent while the balance is
    // below zero, ~28 KB/s at most; the images make room for them.
    if conn.sent - conn.acked >= CREDIT {
        return Vec::new();
    }
    let mut out = Vec::new();
    let epoch = app.mesh_epoch.load(std::sync::atomic::Ordering::Acquire);
    if epoch != conn.mesh_epoch {
        // A new leg: its mesh first, then the whole surface again.
        conn.mesh_epoch = epoch;
        conn.wire = WireState::default();
        conn.pace.reset();
        let hello = json(ServerMessage::Hello {
            mesh: app.control.mesh(),
            state_rate: app.config.state_rate,
            image: app.control.image_geometry(),
            image_link: conn.image_link.clone(),
        });
        conn.budget.spend(hello.to_text().map_or(0, str::len));
        out.push(hello);
    }
    app.control.snapshot(&mut conn.snap);
    conn.sent += 1;
    let mut state = app.view_state(&conn.snap, &mut conn.exam_rev);
    state.seq = conn.sent;
    state.sent_ms = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64() * 1e3);
    state.observer = !app.drives(conn.id, false);
    state.doppler = app.control.doppler_status();
    let mode = state.doppler.map(|d| d.mode);
    let state = json(ServerMessage::State(state));
    conn.budget.spend(state.to_text().map_or(0, str::len));
    out.push(state);
    push_streams(app, conn, mode, &mut out);
    out
}

/// The streams that wait for the byte budget, in their order of priority,
/// each while the budget lasts: the surface nodes that moved (of the
/// snapshot in `conn.snap`), the spectral lines in spectral Doppler `mode`,
/// and the newest image ([`push_image`]).
fn push_streams(
    app: &AppState,
    conn: &mut Conn,
    mode: Option<DopplerMode>,
    out: &mut Vec<Message>,
) {
    let spectral = mode == Some(DopplerMode::Spectral);
    if conn.budget.allows() {
        if let Some(surface) = conn.wire.surface(&conn.snap) {
            conn.budget.spend(surface.len());
            out.push(Message::Binary(surface.into()));
        }
    }
    // The spectral lines since the last sent (a page behind by more than
    // the runtime's ring misses the oldest: latest wins here too), before
    // the image: 64 bytes a line (~13 KB/s at 200 lines/s), they went
    // without when the images (~340 KB/s) had spent the budget.
    if spectral && conn.budget.allows() {
        app.control.spectral_lines(conn.next_line, &mut conn.lines);
        if let Some(frame) = super::flow_frames::spectral_frame(&conn.lines) {
            conn.next_line = conn.lines.first + conn.lines.count as u64;
            conn.budget.spend(frame.len());
            out.push(Message::Binary(frame.into()));
        }
    }
    let flow = matches!(mode, Some(DopplerMode::Color | DopplerMode::Power));
    out.extend(push_image(app, conn, flow));
}

/// Between state pushes, a new image frame as soon as it is rendered and
/// the page and the budget can take it, behind the streams of higher
/// priority ([`push_streams`]: the surface and the spectral lines go first,
/// else an image sent at each turn of the budget would starve them). While
/// the frames answer the page's probe command and the newest is sent, the
/// runtime is asked to render the next at once
/// ([`echothigh_runtime::live::LiveControl::hurry_image`]).
fn poll_image(app: &AppState, conn: &mut Conn) -> Vec<Message> {
    let mut out = Vec::new();
    if conn.image_pending {
        return out;
    }
    let now = conn.epoch.elapsed().as_secs_f64();
    conn.budget.refill(now);
    if !image_budget(conn, now) {
        return out;
    }
    let newest = app.control.image_frame();
    if conn.wire.has_frame(newest) || newest == conn.skipped {
        // Nothing new to send: while the frames answer the page's command,
        // the next one is rendered as soon as the runtime can.
        if now < conn.respond_until {
            app.control.hurry_image();
        }
        return out;
    }
    app.control.snapshot(&mut conn.snap);
    let mode = app.control.doppler_status().map(|d| d.mode);
    push_streams(app, conn, mode, &mut out);
    out
}

/// Whether the byte budget lets an image go at `now`: the frames answering
/// this page's probe command may overdraw it by a reserve
/// ([`super::image_pace::RESPONSE_RESERVE`]), repaid by the frames after
/// them.
fn image_budget(conn: &Conn, now: f64) -> bool {
    if now < conn.respond_until {
        conn.budget.allows_with(super::image_pace::RESPONSE_RESERVE)
    } else {
        conn.budget.allows()
    }
}

/// How often a connection looks for a new image frame (s): 5 ms, a tenth
/// of the imaging period at 20 frames/s ([`echothigh_runtime::live::IMAGING_RATE_SETTING`]).
const IMAGE_POLL: Duration = Duration::from_millis(5);

/// The newest image frame, once the page has taken the previous one
/// ([`ViewerCommand::ImageAck`]), while the byte budget lasts, when it is
/// due ([`ImagePace`]: at once while the probe in `conn.snap` moves or
/// `flow` colours it, a few a second while it holds still), reduced to the
/// page's display box ([`DisplayFit`]); `None` when there is no new frame
/// or it must wait.
fn push_image(app: &AppState, conn: &mut Conn, flow: bool) -> Option<Message> {
    let now = conn.epoch.elapsed().as_secs_f64();
    let (force, position) = (
        conn.snap.status.physics_force,
        conn.snap.status.probe_position,
    );
    if conn.image_pending || !image_budget(conn, now) || !conn.pace.due(now, force, position, flow)
    {
        return None;
    }
    let newest = app.control.image_frame();
    if conn.wire.has_frame(newest) || newest == conn.skipped {
        return None;
    }
    let info = app.control.flow_image(&mut conn.pixels, &mut conn.overlay);
    if conn.wire.has_frame(info.frame) {
        return None;
    }
    if now < conn.respond_until && info.time < conn.command_time {
        // Rendered before the page's command: it cannot show its effect,
        // and would spend the reserve the frame that does needs.
        conn.skipped = info.frame;
        return None;
    }
    let fitted = conn
        .fit
        .fit(info.width, info.height, &conn.pixels, &conn.overlay)?;
    let sized = echothigh_runtime::live::ImageInfo {
        width: fitted.width,
        height: fitted.height,
        ..info
    };
    let image = conn.wire.image(sized, fitted.pixels)?;
    let image = if fitted.overlay.is_empty() {
        image
    } else {
        super::flow_frames::with_overlay(&image, fitted.overlay).unwrap_or(image)
    };
    conn.budget.spend(image.len());
    conn.image_pending = true;
    conn.pace.sent(now, force, position);
    Some(Message::Binary(image.into()))
}
