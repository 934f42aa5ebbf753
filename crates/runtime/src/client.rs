//! The haptic side's real-time deployment (paper Fig. 1, left): the 1 kHz
//! haptic loop on its own thread, and a link thread that sends the device
//! position to the physics and feeds the returned samples to the model
//! manager. The loop never touches the link: the position goes out and the
//! models come in through lock-free single-slot handoffs, so neither a slow
//! physics, a socket, nor a vanished peer can stall it. Serves the threaded
//! deployment (in-process link) and the `haptic-client` process (UDP).

use super::haptic_side::{ForceSource, SampleSink};
use super::physics_loop::Clock;
use super::physics_side::PhysicsSide;
use super::recorder::RecordSink;
use super::tick::{HandoffObserver, HapticTick, TickCounters, TickDevice};
use super::trace::TickRecord;
use anyhow::{Context, Result};
use echothigh_device::{ForceScale, SimulatedDevice};
use echothigh_haptics::{LoopConfig, LoopRunner, TimingSummary};
use echothigh_transport::{Link, LinkStats, Message, ProbeMsg};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Why the haptic client ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClientEnd {
    /// The planned duration elapsed.
    Completed,
    /// The physics was silent for longer than the peer timeout (or said Bye):
    /// the force was faded out and the run stopped early.
    PeerLost,
    /// Stopped from outside (SIGINT, SIGTERM, a recorder that cannot write)
    /// before the planned duration.
    Interrupted,
}

/// What the client recorded.
pub struct ClientReport {
    /// Why it ended.
    pub end: ClientEnd,
    /// Loop time when the peer was declared lost (s).
    pub lost_at: Option<f64>,
    /// One record per tick (empty when they were streamed to a recorder).
    pub ticks: Vec<TickRecord>,
    /// Tick records the recorder's ring could not take.
    pub dropped: u64,
    /// Ticks run.
    pub tick_count: u64,
    /// Timing of the loop.
    pub timing: TimingSummary,
    /// Link counters.
    pub link: LinkStats,
    /// Samples received.
    pub samples: u64,
    /// Physics rate achieved, as the last sample reported it (Hz).
    pub physics_rate: f64,
    /// Non-finite forces caught before the device.
    pub faults: u64,
}

/// Everything the haptic loop owns.
pub struct LoopParts<D = SimulatedDevice> {
    /// The device: simulated with its hand, or a real one (`--device`).
    pub device: D,
    /// The force source of the coupling mode.
    pub source: ForceSource,
    /// Tissue → device force scale.
    pub scale: ForceScale,
    /// In `direct` mode the physics runs inside the loop.
    pub direct_physics: Option<PhysicsSide>,
}

/// Loop state handed back when the loop thread ends.
struct LoopResult {
    runner: LoopRunner,
    ticks: RecordSink<TickRecord>,
    counters: TickCounters,
    error: Option<anyhow::Error>,
}

/// How a client run is set up besides its parts.
pub struct ClientConfig<'a> {
    /// The haptic loop's rate and scheduling.
    pub loop_config: &'a LoopConfig,
    /// Planned duration (s of wall time).
    pub duration: f64,
    /// Silence of the physics after which the force is faded and the run stops (s).
    pub peer_timeout: f64,
    /// Set from outside (a signal, the recorder) to stop the run early.
    pub stop: Arc<AtomicBool>,
    /// The probe's orientation (w, x, y, z) sent while the device senses
    /// none ([`crate::scenario::Scenario::probe_orientation`]).
    pub orientation: [f64; 4],
}

/// Runs the haptic client for `config.duration` (s) of wall time, until the
/// physics goes silent for `config.peer_timeout` (s), or until
/// `config.stop` is set. `link` is `None` in `direct` mode (the physics
/// runs inside the loop). Every tick's record goes to `ticks`. Both threads
/// are joined on every path; an error of either is returned after both
/// have stopped, the device's force set to zero.
pub fn run_client<D: TickDevice + Send + 'static>(
    mut link: Option<Box<dyn Link>>,
    mut sink: SampleSink,
    parts: LoopParts<D>,
    config: ClientConfig<'_>,
    ticks: RecordSink<TickRecord>,
) -> Result<ClientReport> {
    let ClientConfig {
        loop_config,
        duration,
        peer_timeout,
        stop,
        orientation,
    } = config;
    let clock = Clock::start();
    let n_ticks = (duration * loop_config.rate_hz).ceil() as u64;
    let period = 1.0 / loop_config.rate_hz;
    let (pose_in, mut pose_out) = triple_buffer::triple_buffer(&None::<ProbeMsg>);
    let mut runner = LoopRunner::new(loop_config).map_err(anyhow::Error::msg)?;
    let loop_stop = stop.clone();
    let LoopParts {
        device,
        source,
        scale,
        direct_physics,
    } = parts;
    let mut tick = HapticTick::new(device, source, scale, direct_physics, period);
    // Real time: the `direct` tick renders the force only, within its period
    // (its physics records are not kept here).
    tick.set_direct_queries(false);
    tick.set_orientation(orientation);
    let mut observer = HandoffObserver::new(pose_in, ticks);
    let handle = std::thread::Builder::new()
        .name("haptic-loop".into())
        .spawn(move || {
            let mut error = None;
            runner.run(&loop_stop, Some(n_ticks), |_, _| {
                if error.is_some() {
                    return;
                }
                if let Err(e) = tick.tick(clock.now(), &mut observer) {
                    error = Some(e);
                    loop_stop.store(true, Ordering::Relaxed);
                }
            });
            // Zero force on every exit path of the loop.
            tick.release();
            LoopResult {
                runner,
                ticks: observer.into_records(),
                counters: tick.counters(),
                error,
            }
        })
        .context("starting the haptic loop thread")?;

    // The link thread (this one): position out, samples in, peer watch.
    let sleeper = spin_sleep::SpinSleeper::default();
    let mut last_sent = -1.0;
    let mut lost_at = None;
    let mut started = None;
    let mut physics_rate = 0.0;
    let mut link_error = None;
    while !handle.is_finished() {
        let now = clock.now();
        if let Some(link) = link.as_mut().filter(|_| lost_at.is_none()) {
            // Once the peer is declared lost nothing it sends is rendered:
            // the force stays on its way to zero until the loop stops.
            let exchange = exchange(
                link.as_mut(),
                &mut pose_out,
                &mut sink,
                &mut last_sent,
                &mut physics_rate,
                now,
            );
            if let Err(e) = exchange {
                // Stop the loop (its force fades with the stale model) and
                // report the link's error after joining it.
                link_error = Some(e);
                stop.store(true, Ordering::Relaxed);
                break;
            }
            let t0 = *started.get_or_insert(now);
            // Until the first physics sample the startup grace applies: the
            // handshake's Welcome marks the peer heard, but the server steps
            // only once this side's first pose has reached it, a round trip
            // through both loops' start (seen in `app/tests/suite/faults.rs` on two
            // busy cores: 0.25 s passed with no sample and the client quit).
            let silent = link.peer_closed()
                || match link.last_heard() {
                    Some(_) if sink.count() > 0 => link.peer_silent(now, peer_timeout),
                    _ => now - t0 > peer_timeout.max(2.0),
                };
            if silent && lost_at.is_none() {
                tracing::warn!(
                    "physics silent for more than {peer_timeout} s at t = {now:.3} s: fading the force out"
                );
                lost_at = Some(now);
            }
        }
        // Let the loop fade the stale force to zero, then stop.
        if let Some(t) = lost_at {
            if now - t > 0.5 {
                stop.store(true, Ordering::Relaxed);
            }
        }
        sleeper.sleep(Duration::from_micros(500));
    }
    let result = handle
        .join()
        .map_err(|_| anyhow::anyhow!("the haptic loop thread panicked"))?;
    if let Some(e) = result.error {
        return Err(e.context("the haptic loop stopped"));
    }
    if let Some(e) = link_error {
        return Err(e);
    }
    let link_stats = match link.as_mut() {
        Some(l) => {
            let _ = l.close(clock.now());
            l.stats()
        }
        None => LinkStats::default(),
    };
    let end = if lost_at.is_some() {
        ClientEnd::PeerLost
    } else if result.counters.ticks < n_ticks {
        ClientEnd::Interrupted
    } else {
        ClientEnd::Completed
    };
    Ok(ClientReport {
        end,
        lost_at,
        dropped: result.ticks.dropped(),
        tick_count: result.counters.ticks,
        ticks: result.ticks.into_records(),
        timing: result.runner.summary(),
        link: link_stats,
        samples: sink.count(),
        physics_rate,
        faults: result.counters.faults,
    })
}

/// One exchange of the link thread: the newest probe pose out, the samples
/// in (to the model manager). Returns the link's error, if any.
pub fn exchange(
    link: &mut dyn Link,
    pose: &mut triple_buffer::Output<Option<ProbeMsg>>,
    sink: &mut SampleSink,
    last_sent: &mut f64,
    physics_rate: &mut f64,
    now: f64,
) -> Result<()> {
    if let Some(probe) = *pose.read() {
        if probe.t_device > *last_sent {
            link.send(Message::Probe(probe), now)
                .context("haptic → physics link")?;
            *last_sent = probe.t_device;
        }
    }
    link.poll(now).context("haptic link")?;
    while let Some(m) = link.recv(now).context("haptic link")? {
        if let Message::Sample(s) = m {
            sink.on_sample(&s, now);
            *physics_rate = s.physics_rate;
        }
    }
    Ok(())
}
