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
use super::trace::TickRecord;
use super::virtual_clock::{phase_code, EXAM_ORIENTATION};
use anyhow::{Context, Result};
use echothigh_device::{ExamPhase, ForceScale, HapticDevice, SimulatedDevice};
use echothigh_haptics::{LoopConfig, LoopRunner, TimingSummary, Vec3};
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
}

/// What the client recorded.
pub struct ClientReport {
    /// Why it ended.
    pub end: ClientEnd,
    /// Loop time when the peer was declared lost (s).
    pub lost_at: Option<f64>,
    /// One record per tick.
    pub ticks: Vec<TickRecord>,
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
pub struct LoopParts {
    /// The device (simulated, with its hand).
    pub device: SimulatedDevice,
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
    ticks: Vec<TickRecord>,
    faults: u64,
}

#[derive(Debug, Clone, Copy, Default)]
struct Position {
    t: f64,
    p: [f64; 3],
    valid: bool,
}

/// Runs the haptic client for `duration` (s) of wall time, or until the
/// physics goes silent for `peer_timeout` (s). `link` is `None` in `direct`
/// mode (the physics runs inside the loop).
pub fn run_client(
    mut link: Option<Box<dyn Link>>,
    mut sink: SampleSink,
    parts: LoopParts,
    loop_config: &LoopConfig,
    duration: f64,
    peer_timeout: f64,
) -> Result<ClientReport> {
    let clock = Clock::start();
    let stop = Arc::new(AtomicBool::new(false));
    let n_ticks = (duration * loop_config.rate_hz).ceil() as u64;
    let period = 1.0 / loop_config.rate_hz;
    let (mut pos_in, mut pos_out) = triple_buffer::triple_buffer(&Position::default());
    let mut runner = LoopRunner::new(loop_config).map_err(anyhow::Error::msg)?;
    let loop_stop = stop.clone();
    let handle = std::thread::Builder::new()
        .name("haptic-loop".into())
        .spawn(move || {
            let LoopParts {
                mut device,
                mut source,
                scale,
                mut direct_physics,
            } = parts;
            let mut ticks = Vec::with_capacity(n_ticks as usize + 1);
            let mut faults = 0u64;
            runner.run(&loop_stop, Some(n_ticks), |_, _| {
                let now = clock.now();
                let p = device.position();
                pos_in.write(Position {
                    t: now,
                    p: p.into(),
                    valid: true,
                });
                let r = match direct_physics.as_mut() {
                    Some(physics) => {
                        let probe = ProbeMsg::new(now, p.into(), EXAM_ORIENTATION, 0);
                        let (sample, _) = physics.step(&probe, period, now);
                        source.direct(Vec3::from(sample.force), p, 0.0)
                    }
                    None => source.tick(p, now),
                };
                faults += u64::from(r.fault);
                device.set_force(scale.tissue_to_device(r.force));
                let status = device.exam_status();
                if ticks.len() < ticks.capacity() {
                    ticks.push(TickRecord {
                        t: now,
                        device: p.into(),
                        proxy: r.proxy.into(),
                        force: r.force.into(),
                        device_force: device.force().into(),
                        model_age: if r.model_age.is_finite() {
                            r.model_age
                        } else {
                            -1.0
                        },
                        phase: status.map_or(255, |s| phase_code(s.phase)),
                        holding: status.is_some_and(|s| s.phase == ExamPhase::Hold),
                    });
                }
                device.advance(period);
            });
            LoopResult {
                runner,
                ticks,
                faults,
            }
        })
        .context("starting the haptic loop thread")?;

    // The link thread (this one): position out, samples in, peer watch.
    let sleeper = spin_sleep::SpinSleeper::default();
    let mut last_sent = -1.0;
    let mut lost_at = None;
    let mut started = None;
    let mut physics_rate = 0.0;
    while !handle.is_finished() {
        let now = clock.now();
        if let Some(link) = link.as_mut() {
            let pos = *pos_out.read();
            if pos.valid && pos.t > last_sent {
                link.send(
                    Message::Probe(ProbeMsg::new(pos.t, pos.p, EXAM_ORIENTATION, 0)),
                    now,
                )
                .context("haptic → physics link")?;
                last_sent = pos.t;
            }
            link.poll(now).context("haptic link")?;
            while let Some(m) = link.recv(now).context("haptic link")? {
                if let Message::Sample(s) = m {
                    sink.on_sample(&s, now);
                    physics_rate = s.physics_rate;
                }
            }
            let t0 = *started.get_or_insert(now);
            let silent = link.peer_closed()
                || match link.last_heard() {
                    Some(_) => link.peer_silent(now, peer_timeout),
                    None => now - t0 > peer_timeout.max(2.0),
                };
            if silent && lost_at.is_none() {
                tracing::warn!(
                    "physics silent for more than {peer_timeout} s at t = {now:.3} s: fading the force out"
                );
                lost_at = Some(now);
            }
            // Let the loop fade the stale force to zero, then stop.
            if let Some(t) = lost_at {
                if now - t > 0.5 {
                    stop.store(true, Ordering::Relaxed);
                }
            }
        }
        sleeper.sleep(Duration::from_micros(500));
    }
    let result = handle
        .join()
        .map_err(|_| anyhow::anyhow!("the haptic loop thread panicked"))?;
    let link_stats = match link.as_mut() {
        Some(l) => {
            let _ = l.close(clock.now());
            l.stats()
        }
        None => LinkStats::default(),
    };
    Ok(ClientReport {
        end: if lost_at.is_some() {
            ClientEnd::PeerLost
        } else {
            ClientEnd::Completed
        },
        lost_at,
        ticks: result.ticks,
        timing: result.runner.summary(),
        link: link_stats,
        samples: sink.count(),
        physics_rate,
        faults: result.faults,
    })
}
