//! The loop runner: calls a tick closure at a fixed rate (1 kHz by default)
//! with precise sleeping (spin_sleep: native sleep, then spin to the
//! deadline), best-effort real-time priority, and a stop flag. Per-tick
//! compute time and period error go into a preallocated ring, summarized
//! afterwards (median, p99, p99.9, max, missed deadlines).
//!
//! Each tick's compute is timed twice: on the wall clock and on the thread's
//! own CPU clock. On a shared machine the two tell a missed deadline's cause
//! apart: a tick whose thread-CPU time exceeds the period could not have
//! made it on any schedule (the computation is too long); one whose
//! thread-CPU time fits but whose wall time does not was preempted or woke
//! late (the scheduler).
//!
//! Schedule: deadlines `t_k = t_0 + k T`. The period error of tick `k` is its
//! start time minus `t_k`. A deadline is missed when a tick ends after the
//! next deadline `t_{k+1}`; if the loop falls more than one period behind it
//! skips the deadlines already past (counted as missed) instead of bursting.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::config::{ConfigError, LoopConfig};

/// One tick's timing, ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TickTiming {
    /// Time spent in the tick closure, ns (wall clock).
    pub compute_ns: u32,
    /// CPU time the loop's thread spent in the tick closure, ns (0 where the
    /// platform has no thread clock).
    pub cpu_ns: u32,
    /// Start time minus the deadline, ns (≥ 0 except for clock jitter).
    pub period_error_ns: i32,
}

/// Preallocated ring of the most recent tick timings.
#[derive(Debug, Clone)]
pub struct TimingRing {
    records: Vec<TickTiming>,
    next: usize,
    filled: usize,
}

impl TimingRing {
    /// A ring holding the last `capacity` ticks (allocates once, here).
    pub fn new(capacity: usize) -> Self {
        TimingRing {
            records: vec![TickTiming::default(); capacity.max(1)],
            next: 0,
            filled: 0,
        }
    }

    /// Records one tick (no allocation).
    pub fn push(&mut self, t: TickTiming) {
        self.records[self.next] = t;
        self.next = (self.next + 1) % self.records.len();
        self.filled = (self.filled + 1).min(self.records.len());
    }

    /// Number of records held.
    pub fn len(&self) -> usize {
        self.filled
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.filled == 0
    }

    /// The records held (in ring order, not time order).
    pub fn records(&self) -> &[TickTiming] {
        &self.records[..self.filled]
    }
}

/// Order statistics of a set of durations, s.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Percentiles {
    /// Number of values.
    pub count: usize,
    /// Median, s.
    pub median: f64,
    /// 99th percentile, s.
    pub p99: f64,
    /// 99.9th percentile, s.
    pub p999: f64,
    /// Maximum, s.
    pub max: f64,
}

impl Percentiles {
    /// Nearest-rank percentiles of `values` (sorted in place); zeros if empty.
    pub fn of(values: &mut [f64]) -> Self {
        if values.is_empty() {
            return Percentiles::default();
        }
        values.sort_by(|a, b| a.total_cmp(b));
        let n = values.len();
        let rank = |q: f64| values[((q * n as f64).ceil() as usize).clamp(1, n) - 1];
        Percentiles {
            count: n,
            median: rank(0.5),
            p99: rank(0.99),
            p999: rank(0.999),
            max: values[n - 1],
        }
    }
}

/// Summary of a run of the loop.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TimingSummary {
    /// Ticks run.
    pub ticks: u64,
    /// Target period, s.
    pub period: f64,
    /// Compute time per tick (over the ring), s, wall clock.
    pub compute: Percentiles,
    /// Thread-CPU time per tick (over the ring), s: the computation's own
    /// cost, which other processes do not inflate.
    pub compute_cpu: Percentiles,
    /// Absolute period error (start − deadline) per tick (over the ring), s.
    pub period_error: Percentiles,
    /// Deadlines missed (tick ended after the next deadline, or skipped).
    pub missed_deadlines: u64,
    /// Missed deadlines of ticks whose thread-CPU time alone exceeded the
    /// period (the computation too long); the rest of `missed_deadlines`
    /// came from waiting for the CPU (preemption, late wake-up) or from the
    /// deadlines skipped after a late tick.
    pub missed_over_budget: u64,
    /// Missed deadlines per 10 000 ticks.
    pub missed_per_10k: f64,
    /// Whether real-time priority was obtained.
    pub realtime_priority: bool,
}

static PRIORITY_WARNED: AtomicBool = AtomicBool::new(false);

/// Asks for real-time (FIFO) priority, else the highest normal priority.
/// Returns whether real-time priority was obtained; logs a failure once per
/// process.
pub fn request_realtime_priority() -> bool {
    if request_fifo(thread_priority::ThreadPriority::Max) {
        return true;
    }
    let fallback =
        thread_priority::set_current_thread_priority(thread_priority::ThreadPriority::Max);
    if !PRIORITY_WARNED.swap(true, Ordering::Relaxed) {
        tracing::warn!(
            normal_priority_raised = fallback.is_ok(),
            "haptic loop: real-time priority not granted; running at normal priority"
        );
    }
    false
}

/// Puts the calling thread under the real-time FIFO policy at `priority`
/// (on Linux 1–99, higher first); whether the kernel granted it (it needs
/// `CAP_SYS_NICE` or an `RLIMIT_RTPRIO` limit). Nothing changes on refusal.
pub fn request_fifo(priority: thread_priority::ThreadPriority) -> bool {
    #[cfg(unix)]
    {
        use thread_priority::unix::{
            set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy,
            ThreadSchedulePolicy,
        };
        let policy = ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo);
        set_thread_priority_and_policy(thread_native_id(), priority, policy).is_ok()
    }
    #[cfg(not(unix))]
    {
        let _ = priority;
        false
    }
}

/// CPU time consumed by the calling thread so far (ns; 0 where the platform
/// has no thread clock). One `clock_gettime(CLOCK_THREAD_CPUTIME_ID)`: no
/// allocation, no lock.
pub fn thread_cpu_ns() -> u64 {
    cpu_time::ThreadTime::try_now().map_or(0, |t| t.as_duration().as_nanos() as u64)
}

/// Fixed-rate loop runner.
pub struct LoopRunner {
    period: Duration,
    ring: TimingRing,
    realtime: bool,
    want_realtime: bool,
    ticks: u64,
    missed: u64,
    missed_over_budget: u64,
}

impl LoopRunner {
    /// A runner for `config` (allocates the ring here).
    pub fn new(config: &LoopConfig) -> Result<Self, ConfigError> {
        config.validate("haptics.loop")?;
        Ok(LoopRunner {
            period: Duration::from_secs_f64(1.0 / config.rate_hz),
            ring: TimingRing::new(config.ring_capacity),
            realtime: false,
            want_realtime: config.realtime_priority,
            ticks: 0,
            missed: 0,
            missed_over_budget: 0,
        })
    }

    /// Runs `tick(now_s, index)` on the calling thread every period until
    /// `stop` is set or `max_ticks` ticks have run; `now_s` is seconds since
    /// the start of this run. Returns the number of ticks run.
    pub fn run<F: FnMut(f64, u64)>(
        &mut self,
        stop: &AtomicBool,
        max_ticks: Option<u64>,
        mut tick: F,
    ) -> u64 {
        if self.want_realtime {
            self.realtime = request_realtime_priority();
        }
        let sleeper = spin_sleep::SpinSleeper::default();
        let t0 = Instant::now();
        let mut k: u32 = 0;
        let mut ran = 0;
        while !stop.load(Ordering::Relaxed) && max_ticks.is_none_or(|m| ran < m) {
            let deadline = t0 + self.period * k;
            sleeper.sleep_until(deadline);
            let start = Instant::now();
            let cpu_start = thread_cpu_ns();
            tick((start - t0).as_secs_f64(), ran);
            let cpu = thread_cpu_ns().saturating_sub(cpu_start);
            let end = Instant::now();
            let error = start.saturating_duration_since(deadline).as_nanos() as i64
                - deadline.saturating_duration_since(start).as_nanos() as i64;
            self.ring.push(TickTiming {
                compute_ns: (end - start).as_nanos().min(u32::MAX as u128) as u32,
                cpu_ns: cpu.min(u64::from(u32::MAX)) as u32,
                period_error_ns: error.clamp(i32::MIN as i64, i32::MAX as i64) as i32,
            });
            ran += 1;
            k += 1;
            if end > t0 + self.period * k {
                self.missed += 1;
                if cpu > self.period.as_nanos() as u64 {
                    self.missed_over_budget += 1;
                }
                // Skip deadlines already past rather than bursting to catch up.
                let behind = ((end - t0).as_secs_f64() / self.period.as_secs_f64()).ceil() as u32;
                if behind > k {
                    self.missed += u64::from(behind - k);
                    k = behind;
                }
            }
        }
        self.ticks += ran;
        ran
    }

    /// Moves the runner to a new thread running `tick` until `stop` is set
    /// (or `max_ticks`); join the handle to get the runner back.
    pub fn spawn<F>(
        mut self,
        stop: Arc<AtomicBool>,
        max_ticks: Option<u64>,
        mut tick: F,
    ) -> std::io::Result<std::thread::JoinHandle<LoopRunner>>
    where
        F: FnMut(f64, u64) + Send + 'static,
    {
        std::thread::Builder::new()
            .name("haptic-loop".into())
            .spawn(move || {
                self.run(&stop, max_ticks, &mut tick);
                self
            })
    }

    /// The timing ring.
    pub fn timings(&self) -> &TimingRing {
        &self.ring
    }

    /// Summary statistics (allocates; call outside the loop).
    pub fn summary(&self) -> TimingSummary {
        let recs = self.ring.records();
        let mut compute: Vec<f64> = recs.iter().map(|r| r.compute_ns as f64 * 1e-9).collect();
        let mut cpu: Vec<f64> = recs.iter().map(|r| r.cpu_ns as f64 * 1e-9).collect();
        let mut error: Vec<f64> = recs
            .iter()
            .map(|r| (r.period_error_ns as f64 * 1e-9).abs())
            .collect();
        TimingSummary {
            ticks: self.ticks,
            period: self.period.as_secs_f64(),
            compute: Percentiles::of(&mut compute),
            compute_cpu: Percentiles::of(&mut cpu),
            period_error: Percentiles::of(&mut error),
            missed_deadlines: self.missed,
            missed_over_budget: self.missed_over_budget,
            missed_per_10k: if self.ticks > 0 {
                self.missed as f64 * 1e4 / self.ticks as f64
            } else {
                0.0
            },
            realtime_priority: self.realtime,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_nearest_rank() {
        let mut v: Vec<f64> = (1..=1000).map(|i| i as f64).collect();
        v.reverse();
        let p = Percentiles::of(&mut v);
        assert_eq!(
            (p.count, p.median, p.p99, p.p999, p.max),
            (1000, 500.0, 990.0, 999.0, 1000.0)
        );
        assert_eq!(Percentiles::of(&mut []).count, 0);
    }

    /// A tick that sleeps through three periods misses its deadline on the
    /// wall clock without using the CPU (the scheduler's case); one that
    /// computes for two periods of its own CPU time is over budget (the
    /// computation's case). The thread clock is Linux's; elsewhere it reads 0
    /// and nothing is over budget.
    #[test]
    fn missed_deadlines_tell_computation_from_waiting() {
        let cfg = LoopConfig {
            rate_hz: 1000.0,
            ring_capacity: 16,
            realtime_priority: false,
        };
        let period_ns = 1_000_000;
        let stop = AtomicBool::new(false);
        let mut sleeper = LoopRunner::new(&cfg).unwrap();
        sleeper.run(&stop, Some(3), |_, _| {
            std::thread::sleep(Duration::from_millis(3));
        });
        let s = sleeper.summary();
        assert!(s.missed_deadlines >= 3, "{s:?}");
        assert_eq!(s.missed_over_budget, 0, "{s:?}");
        // Thread-CPU ≤ wall time on every tick.
        assert!(sleeper
            .timings()
            .records()
            .iter()
            .all(|r| r.cpu_ns <= r.compute_ns));
        let mut busy = LoopRunner::new(&cfg).unwrap();
        busy.run(&stop, Some(3), |_, _| {
            let start = thread_cpu_ns();
            let mut x = 0u64;
            // Two periods of this thread's own CPU time (bounded by a wall
            // clock guard where the thread clock reads 0).
            let wall = Instant::now();
            while thread_cpu_ns() - start < 2 * period_ns && wall.elapsed().as_millis() < 20 {
                x = x.wrapping_add(std::hint::black_box(x) | 1);
            }
            std::hint::black_box(x);
        });
        let s = busy.summary();
        if cfg!(target_os = "linux") {
            assert_eq!(s.missed_over_budget, 3, "{s:?}");
            assert!(s.compute_cpu.median >= 2e-3, "{s:?}");
        }
    }

    #[test]
    fn ring_keeps_the_last_records() {
        let mut r = TimingRing::new(3);
        for i in 0..5 {
            r.push(TickTiming {
                compute_ns: i,
                cpu_ns: 0,
                period_error_ns: 0,
            });
        }
        let mut got: Vec<u32> = r.records().iter().map(|t| t.compute_ns).collect();
        got.sort();
        assert_eq!(got, vec![2, 3, 4]);
    }

    #[test]
    fn runs_max_ticks_and_stops_on_flag() {
        let cfg = LoopConfig {
            rate_hz: 5000.0,
            ring_capacity: 16,
            realtime_priority: false,
        };
        let mut runner = LoopRunner::new(&cfg).unwrap();
        let stop = AtomicBool::new(false);
        let mut seen = Vec::new();
        let n = runner.run(&stop, Some(20), |t, i| seen.push((t, i)));
        assert_eq!(n, 20);
        assert_eq!(runner.timings().len(), 16);
        // Tick times are increasing and indices consecutive.
        assert!(seen
            .windows(2)
            .all(|w| w[1].0 > w[0].0 && w[1].1 == w[0].1 + 1));
        // A set flag stops the loop before the first tick.
        stop.store(true, Ordering::Relaxed);
        assert_eq!(runner.run(&stop, None, |_, _| {}), 0);
        let s = runner.summary();
        assert_eq!(s.ticks, 20);
        assert_eq!(s.compute.count, 16);

        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let handle = LoopRunner::new(&cfg)
            .unwrap()
            .spawn(stop.clone(), None, move |_, i| {
                if i == 9 {
                    flag.store(true, Ordering::Relaxed);
                }
            })
            .unwrap();
        assert_eq!(handle.join().unwrap().summary().ticks, 10);
    }
}
