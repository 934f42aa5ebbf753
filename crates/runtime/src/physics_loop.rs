//! The physics side's real-time loop (paper Fig. 1, right): receive the
//! latest probe pose, step the model at its rate, send the sample back. The
//! same loop serves the threaded deployment (over the in-process link) and
//! the `physics-server` process (over UDP).

use super::physics_side::PhysicsSide;
use super::recorder::RecordSink;
use super::trace::PhysicsRecord;
use anyhow::{Context, Result};
use echothigh_transport::{Link, Message, ProbeMsg};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A monotonic clock shared by the threads of one process (s since `epoch`).
#[derive(Debug, Clone, Copy)]
pub struct Clock {
    epoch: Instant,
}

impl Clock {
    /// A clock starting now.
    pub fn start() -> Self {
        Self {
            epoch: Instant::now(),
        }
    }
    /// Seconds since the start.
    pub fn now(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }
}

/// Why the physics loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhysicsEnd {
    /// The stop flag was set.
    Stopped,
    /// The haptic side said Bye.
    PeerClosed,
    /// The haptic side was silent for longer than the timeout.
    PeerSilent,
}

/// What the loop did.
#[derive(Debug, Clone)]
pub struct PhysicsReport {
    /// Why it ended.
    pub end: PhysicsEnd,
    /// Steps run.
    pub steps: u64,
    /// Wall time from the first step to the last (s).
    pub elapsed: f64,
    /// Steps per second achieved.
    pub rate: f64,
}

/// Runs the physics loop at `rate` (Hz) until `stop`, a Bye, or `peer_timeout`
/// (s) of silence after the peer was first heard. Each step's record goes
/// into `records` while capacity lasts (preallocate for the run).
pub fn physics_loop(
    physics: &mut PhysicsSide,
    link: &mut dyn Link,
    clock: Clock,
    stop: &AtomicBool,
    rate: f64,
    peer_timeout: f64,
    records: &mut RecordSink<PhysicsRecord>,
) -> Result<PhysicsReport> {
    physics_loop_with(
        physics,
        link,
        clock,
        stop,
        rate,
        peer_timeout,
        records,
        &mut |_, _| {},
    )
}

/// The physics thread's real-time FIFO priority: below the haptic loop's
/// (the policy's maximum, 99 on Linux), so the tick still preempts it, and
/// above every time-shared thread, so a busy browser on the same machine no
/// longer starves the model (issue 19: physics fell from 100 to 23–39 Hz
/// under Chromium on two cores). A step takes ~1 ms of its 10 ms period on
/// the default mesh; a loop that falls behind runs flat out, and the
/// kernel's real-time throttling (`sched_rt_runtime_us`, 95 % by default)
/// still leaves the core's other threads their share.
pub const PHYSICS_FIFO_PRIORITY: u8 = 50;

/// Puts the calling (physics) thread at [`PHYSICS_FIFO_PRIORITY`] when
/// `realtime` (`[haptics.runner] realtime_priority`) and the kernel permits;
/// logs what it got and returns whether FIFO was granted.
pub fn request_physics_priority(realtime: bool) -> bool {
    use thread_priority::{ThreadPriority, ThreadPriorityValue};
    if !realtime {
        return false;
    }
    let granted = ThreadPriorityValue::try_from(PHYSICS_FIFO_PRIORITY)
        .is_ok_and(|p| echothigh_haptics::runner::request_fifo(ThreadPriority::Crossplatform(p)));
    if granted {
        tracing::info!(
            priority = PHYSICS_FIFO_PRIORITY,
            "physics thread at real-time priority (FIFO)"
        );
    } else {
        tracing::info!("physics thread time-shared (real-time priority refused)");
    }
    granted
}

/// [`physics_loop`] calling `after_step(physics, probe)` after every step
/// (e.g. to publish the deformation to a viewer).
#[allow(clippy::too_many_arguments)]
pub fn physics_loop_with(
    physics: &mut PhysicsSide,
    link: &mut dyn Link,
    clock: Clock,
    stop: &AtomicBool,
    rate: f64,
    peer_timeout: f64,
    records: &mut RecordSink<PhysicsRecord>,
    after_step: &mut dyn FnMut(&PhysicsSide, &ProbeMsg),
) -> Result<PhysicsReport> {
    let period = 1.0 / rate;
    let sleeper = spin_sleep::SpinSleeper::default();
    let mut latest: Option<ProbeMsg> = None;
    let mut next = clock.now();
    let (mut steps, mut first, mut last) = (0u64, None, 0.0);
    let end = loop {
        if stop.load(Ordering::Relaxed) {
            break PhysicsEnd::Stopped;
        }
        let now = clock.now();
        link.poll(now).context("physics link")?;
        while let Some(m) = link.recv(now).context("physics link")? {
            if let Message::Probe(p) = m {
                latest = Some(p);
            }
        }
        if link.peer_closed() {
            break PhysicsEnd::PeerClosed;
        }
        if link.last_heard().is_some() && link.peer_silent(now, peer_timeout) {
            break PhysicsEnd::PeerSilent;
        }
        if now >= next {
            if let Some(probe) = latest {
                let started = Instant::now();
                let (mut sample, mut rec) = physics.step(&probe, period, now);
                physics.check()?;
                rec.compute_time = started.elapsed().as_secs_f64();
                rec.t = now;
                sample.probe_seq = probe.header.seq;
                sample.physics_rate = if steps > 0 {
                    steps as f64 / (now - first.unwrap_or(now)).max(1e-9)
                } else {
                    rate
                };
                link.send(Message::Sample(sample), clock.now())
                    .context("physics → haptic link")?;
                records.push(rec);
                after_step(physics, &probe);
                first.get_or_insert(now);
                last = now;
                steps += 1;
            }
            next += period;
            if next < clock.now() {
                // Behind (a step took longer than a period): run flat out
                // rather than bursting to catch up.
                next = clock.now();
            }
        }
        // Wake every millisecond to serve the link's delay line.
        let wake = (clock.now() + 1e-3).min(next);
        let sleep = wake - clock.now();
        if sleep > 0.0 {
            sleeper.sleep(Duration::from_secs_f64(sleep));
        }
    };
    let elapsed = first.map_or(0.0, |f| last - f);
    let rate = if elapsed > 0.0 {
        (steps.saturating_sub(1)) as f64 / elapsed
    } else {
        0.0
    };
    Ok(PhysicsReport {
        end,
        steps,
        elapsed,
        rate,
    })
}
