//! Synchronous request/response over a [`Link`], for round-trip latency
//! measurements (`echothigh bench link`) and tests: an [`EchoResponder`]
//! thread stands in for the physics and answers every probe with a sample
//! naming it; [`round_trip`] sends a probe and waits for that answer.

use crate::link::{Link, LinkError};
use crate::message::{Message, ProbeMsg, SampleMsg};
use crate::sequence::LinkStats;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The sample an echo responder answers `probe` with: `probe_seq` names
/// the probe, `p` and `t_sample` copy its position and device time, the
/// rest is a free-space sample (distance 1 m, zero force).
pub fn echo_sample(probe: &ProbeMsg) -> SampleMsg {
    SampleMsg {
        t_sample: probe.t_device,
        probe_seq: probe.header.seq,
        p: probe.position,
        distance: 1.0,
        gradient: [0.0, 1.0, 0.0],
        ..SampleMsg::default()
    }
}

/// A thread answering each probe it receives with [`echo_sample`] until
/// stopped or told Bye. Its clock is the wall clock since spawning (s).
pub struct EchoResponder {
    stop: Arc<AtomicBool>,
    handle: JoinHandle<Result<LinkStats, LinkError>>,
}

impl EchoResponder {
    /// Starts answering on `link` (busy-polling with `yield_now`, for the
    /// lowest latency).
    pub fn spawn<L: Link + 'static>(mut link: L) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let handle = std::thread::spawn(move || {
            let clock = Instant::now();
            while !flag.load(Ordering::Relaxed) {
                let now = clock.elapsed().as_secs_f64();
                match link.recv(now)? {
                    Some(Message::Probe(p)) => {
                        link.send(Message::Sample(echo_sample(&p)), now)?;
                    }
                    Some(Message::Bye(_)) => break,
                    Some(_) => {}
                    None => std::thread::yield_now(),
                }
            }
            link.close(clock.elapsed().as_secs_f64())?;
            Ok(link.stats())
        });
        EchoResponder { stop, handle }
    }

    /// Stops the thread and returns its link's counters.
    pub fn stop(self) -> Result<LinkStats, LinkError> {
        self.stop.store(true, Ordering::Relaxed);
        match self.handle.join() {
            Ok(r) => r,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    }
}

/// Sends `probe` on `link` and waits (busy-polling, wall clock) for the
/// sample answering it; returns the round-trip time (s). `clock` is the
/// epoch of the link's time base. Answers to earlier probes are skipped.
pub fn round_trip<L: Link + ?Sized>(
    link: &mut L,
    probe: ProbeMsg,
    clock: Instant,
    timeout: Duration,
) -> Result<f64, LinkError> {
    let start = Instant::now();
    let seq = link.send(Message::Probe(probe), clock.elapsed().as_secs_f64())?;
    loop {
        let now = clock.elapsed().as_secs_f64();
        match link.recv(now)? {
            Some(Message::Sample(s)) if s.probe_seq == seq => {
                return Ok(start.elapsed().as_secs_f64());
            }
            Some(_) => {}
            None if start.elapsed() > timeout => {
                return Err(LinkError::RoundTripTimeout {
                    seq,
                    waited: timeout,
                })
            }
            None => std::thread::yield_now(),
        }
    }
}

/// Round-trip latency statistics (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundTripReport {
    /// Number of round trips measured.
    pub count: usize,
    /// Smallest round trip (s).
    pub min: f64,
    /// Median round trip (s).
    pub median: f64,
    /// 99th percentile (nearest rank) (s).
    pub p99: f64,
    /// Largest round trip (s).
    pub max: f64,
}

impl RoundTripReport {
    /// Statistics of `samples` (s); `None` when empty or not all finite.
    pub fn from_samples(samples: &mut [f64]) -> Option<Self> {
        if samples.is_empty() || !samples.iter().all(|s| s.is_finite()) {
            return None;
        }
        samples.sort_by(f64::total_cmp);
        let rank = |q: f64| {
            samples[((q * samples.len() as f64).ceil() as usize).clamp(1, samples.len()) - 1]
        };
        Some(RoundTripReport {
            count: samples.len(),
            min: samples[0],
            median: rank(0.5),
            p99: rank(0.99),
            max: samples[samples.len() - 1],
        })
    }
}

/// Measures `count` sequential [`round_trip`]s on `link` against an echo
/// responder (after `warmup` unrecorded ones).
pub fn measure_round_trips<L: Link + ?Sized>(
    link: &mut L,
    warmup: usize,
    count: usize,
    timeout: Duration,
) -> Result<Option<RoundTripReport>, LinkError> {
    let clock = Instant::now();
    let mut samples = Vec::with_capacity(count);
    for i in 0..warmup + count {
        let probe = ProbeMsg::new(i as f64, [0.0; 3], [1.0, 0.0, 0.0, 0.0], 0);
        let rtt = round_trip(link, probe, clock, timeout)?;
        if i >= warmup {
            samples.push(rtt);
        }
    }
    Ok(RoundTripReport::from_samples(&mut samples))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{in_process_pair, FaultConfig};

    #[test]
    fn in_process_round_trips_are_answered() {
        let (mut client, server) =
            in_process_pair(5, FaultConfig::default(), FaultConfig::default());
        let responder = EchoResponder::spawn(server);
        let clock = Instant::now();
        for i in 0..50 {
            let probe = ProbeMsg::new(f64::from(i), [0.0; 3], [1.0, 0.0, 0.0, 0.0], 0);
            let rtt = round_trip(&mut client, probe, clock, Duration::from_secs(5)).unwrap();
            assert!(rtt >= 0.0);
        }
        client.close(clock.elapsed().as_secs_f64()).unwrap();
        let stats = responder.stop().unwrap();
        assert!(stats.received >= 50);
    }

    #[test]
    fn report_uses_nearest_rank_percentiles() {
        let mut s: Vec<f64> = (1..=200).rev().map(f64::from).collect();
        let r = RoundTripReport::from_samples(&mut s).unwrap();
        assert_eq!((r.count, r.min, r.max), (200, 1.0, 200.0));
        assert_eq!(r.median, 100.0);
        assert_eq!(r.p99, 198.0);
        assert!(RoundTripReport::from_samples(&mut []).is_none());
        assert!(RoundTripReport::from_samples(&mut [1.0, f64::NAN]).is_none());
    }
}
