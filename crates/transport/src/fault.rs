//! Fault injection on the link: latency, jitter, loss, duplication.
//!
//! A sender-side delay line on the *caller's* clock: [`DelayLine::push`]
//! draws the message's fate (lost, delivered once, delivered twice) and its
//! delivery time(s); [`DelayLine::pop_due`] releases the messages whose time
//! has come, earliest first. The queue is a binary heap preallocated to a
//! fixed capacity, so no message allocates. With a virtual clock and a fixed
//! seed the faults are deterministic.
//!
//! Delay model: each copy is delivered `latency + U(0, jitter)` after it is
//! sent, with `U` uniform. `latency` is the minimum (propagation) delay and
//! `jitter` the width of the spread, so the mean one-way delay is
//! `latency + jitter / 2`. Jitter reorders messages sent less than `jitter`
//! apart; the receiver's sequence filter then drops the stale ones.

use crate::sequence::LinkStats;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// Default capacity of a delay line (messages in flight per direction):
/// enough for 1 kHz traffic with a 1 s delay.
pub const DEFAULT_DELAY_CAPACITY: usize = 1024;

/// An invalid configuration value, naming the key (e.g. `link.loss`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("invalid `{key}`: {reason}")]
pub struct ConfigError {
    /// Full key, `"{prefix}.{field}"`.
    pub key: String,
    /// What is wrong with the value.
    pub reason: String,
}

/// Faults injected on one direction of the link (scenario section
/// `[link]`). All zero (the default) is a perfect link.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FaultConfig {
    /// One-way minimum added delay (s), in [0, 0.5]: teleoperation links
    /// of interest are below ~0.5 s one way, and `latency + jitter` ≤ 1 s
    /// keeps 1 kHz traffic within the delay line's
    /// [`DEFAULT_DELAY_CAPACITY`] messages. Default 0.
    pub latency: f64,
    /// Width of the uniform delay spread added to `latency` (s), in [0, 0.5]
    /// (as `latency`). Default 0.
    pub jitter: f64,
    /// Probability that a message is lost, in [0, 1]. Default 0.
    pub loss: f64,
    /// Probability that a delivered message is delivered twice (each copy
    /// with its own delay), in [0, 1]. Default 0.
    pub duplicate: f64,
    /// Seed of the fault generator (ChaCha8). Default 0.
    pub seed: u64,
}

impl Default for FaultConfig {
    fn default() -> Self {
        FaultConfig {
            latency: 0.0,
            jitter: 0.0,
            loss: 0.0,
            duplicate: 0.0,
            seed: 0,
        }
    }
}

impl FaultConfig {
    /// Checks every field; the error names `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let err = |field: &str, reason: String| ConfigError {
            key: format!("{prefix}.{field}"),
            reason,
        };
        for (field, value) in [("latency", self.latency), ("jitter", self.jitter)] {
            if !(0.0..=0.5).contains(&value) {
                return Err(err(
                    field,
                    format!(
                        "must be in [0, 0.5] s (teleoperation delays; with latency + jitter \
                         <= 1 s the delay line holds 1 s of 1 kHz traffic), got {value:?}"
                    ),
                ));
            }
        }
        for (field, value) in [("loss", self.loss), ("duplicate", self.duplicate)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(err(
                    field,
                    format!("must be in [0, 1] (a probability), got {value:?}"),
                ));
            }
        }
        Ok(())
    }

    /// The same faults with another seed (e.g. one per direction).
    pub fn with_seed(self, seed: u64) -> Self {
        FaultConfig { seed, ..self }
    }
}

#[derive(Clone, Copy)]
struct Entry<T> {
    due: f64,
    order: u64,
    msg: T,
}

impl<T> PartialEq for Entry<T> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl<T> Eq for Entry<T> {}
impl<T> PartialOrd for Entry<T> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl<T> Ord for Entry<T> {
    fn cmp(&self, other: &Self) -> Ordering {
        self.due
            .total_cmp(&other.due)
            .then(self.order.cmp(&other.order))
    }
}

/// Fixed-capacity delay line applying a [`FaultConfig`].
pub struct DelayLine<T> {
    config: FaultConfig,
    rng: ChaCha8Rng,
    queue: BinaryHeap<Reverse<Entry<T>>>,
    capacity: usize,
    order: u64,
}

impl<T: Copy> DelayLine<T> {
    /// A delay line holding at most `capacity` messages in flight
    /// (allocated here, once). `config` should have been validated.
    pub fn new(config: FaultConfig, capacity: usize) -> Self {
        DelayLine {
            config,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            queue: BinaryHeap::with_capacity(capacity.max(1)),
            capacity: capacity.max(1),
            order: 0,
        }
    }

    /// The faults applied.
    pub fn config(&self) -> &FaultConfig {
        &self.config
    }

    /// Messages in flight.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// True when nothing is in flight.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Drops every message in flight.
    pub fn clear(&mut self) {
        self.queue.clear();
    }

    /// Sends `msg` at time `now` (s, caller's clock): lost with probability
    /// `loss`, else queued for `now + latency + U(0, jitter)`, and with
    /// probability `duplicate` queued a second time with its own delay.
    /// Counts losses, duplicates and overflows in `stats`. Never allocates.
    pub fn push(&mut self, msg: T, now: f64, stats: &mut LinkStats) {
        if self.config.loss > 0.0 && self.rng.gen::<f64>() < self.config.loss {
            stats.fault_lost += 1;
            return;
        }
        self.enqueue(msg, now, stats);
        if self.config.duplicate > 0.0 && self.rng.gen::<f64>() < self.config.duplicate {
            stats.fault_duplicated += 1;
            self.enqueue(msg, now, stats);
        }
    }

    fn enqueue(&mut self, msg: T, now: f64, stats: &mut LinkStats) {
        if self.queue.len() >= self.capacity {
            stats.queue_overflow += 1;
            return;
        }
        let jitter = if self.config.jitter > 0.0 {
            self.config.jitter * self.rng.gen::<f64>()
        } else {
            0.0
        };
        let due = now + self.config.latency + jitter;
        self.order += 1;
        self.queue.push(Reverse(Entry {
            due,
            order: self.order,
            msg,
        }));
    }

    /// The earliest message due at or before `now` (s), with its due time;
    /// ties leave in the order they were pushed.
    pub fn pop_due(&mut self, now: f64) -> Option<(f64, T)> {
        match self.queue.peek() {
            Some(Reverse(e)) if e.due <= now => {
                let Reverse(e) = self.queue.pop()?;
                Some((e.due, e.msg))
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(latency: f64, jitter: f64, loss: f64, duplicate: f64) -> FaultConfig {
        FaultConfig {
            latency,
            jitter,
            loss,
            duplicate,
            seed: 7,
        }
    }

    #[test]
    fn loss_rate_is_within_binomial_bounds() {
        let n = 10_000u64;
        let p = 0.2;
        let mut line = DelayLine::new(cfg(0.0, 0.0, p, 0.0), 16);
        let mut stats = LinkStats::default();
        let mut delivered = 0u64;
        for i in 0..n {
            line.push(i, i as f64 * 1e-3, &mut stats);
            while line.pop_due(i as f64 * 1e-3).is_some() {
                delivered += 1;
            }
        }
        // 4.5 sigma of Binomial(n, p): a failure means a broken generator.
        let sigma = (n as f64 * p * (1.0 - p)).sqrt();
        let lost = stats.fault_lost as f64;
        assert!((lost - n as f64 * p).abs() < 4.5 * sigma, "lost {lost}");
        assert_eq!(delivered + stats.fault_lost, n);
    }

    #[test]
    fn latency_is_exact_without_jitter_and_order_is_kept() {
        let latency = 0.0123;
        let mut line = DelayLine::new(cfg(latency, 0.0, 0.0, 0.0), 64);
        let mut stats = LinkStats::default();
        for i in 0..10u32 {
            line.push(i, f64::from(i) * 1e-3, &mut stats);
        }
        assert!(line.pop_due(latency - 1e-9).is_none());
        for i in 0..10u32 {
            let sent = f64::from(i) * 1e-3;
            let (due, msg) = line.pop_due(sent + latency).unwrap();
            assert_eq!(msg, i);
            assert_eq!(due, sent + latency);
        }
        assert!(line.is_empty());
    }

    #[test]
    fn jitter_stays_within_its_band_and_reorders() {
        let (latency, jitter) = (0.005, 0.004);
        let mut line = DelayLine::new(cfg(latency, jitter, 0.0, 0.0), 64);
        let mut stats = LinkStats::default();
        let mut reordered = 0;
        let mut last = None;
        for i in 0..2000u32 {
            let now = f64::from(i) * 1e-3;
            line.push((i, now), now, &mut stats);
            while let Some((due, (seq, sent))) = line.pop_due(now) {
                let delay = due - sent;
                assert!(delay >= latency && delay <= latency + jitter, "{delay}");
                if last.is_some_and(|l| seq < l) {
                    reordered += 1;
                }
                last = Some(seq);
            }
        }
        assert!(reordered > 100, "jitter of 4 ms at 1 kHz must reorder");
    }

    #[test]
    fn duplicates_are_counted_and_capacity_is_respected() {
        let mut line = DelayLine::new(cfg(1.0, 0.0, 0.0, 1.0), 10);
        let mut stats = LinkStats::default();
        for i in 0..8u32 {
            line.push(i, 0.0, &mut stats);
        }
        assert_eq!(line.len(), 10);
        assert_eq!(stats.fault_duplicated, 8);
        assert_eq!(stats.queue_overflow, 6);
    }

    #[test]
    fn same_seed_same_faults() {
        let run = || {
            let mut line = DelayLine::new(cfg(0.001, 0.003, 0.3, 0.2), 64);
            let mut stats = LinkStats::default();
            let mut out = Vec::new();
            for i in 0..500u32 {
                let now = f64::from(i) * 1e-3;
                line.push(i, now, &mut stats);
                while let Some((due, m)) = line.pop_due(now) {
                    out.push((due, m));
                }
            }
            out
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn validation_names_the_key() {
        assert!(FaultConfig::default().validate("link").is_ok());
        let e = cfg(-1.0, 0.0, 0.0, 0.0).validate("link").unwrap_err();
        assert_eq!(e.key, "link.latency");
        let e = cfg(0.0, f64::NAN, 0.0, 0.0).validate("link").unwrap_err();
        assert_eq!(e.key, "link.jitter");
        let e = cfg(0.0, 0.0, 1.5, 0.0).validate("link").unwrap_err();
        assert_eq!(e.key, "link.loss");
        let e = cfg(0.0, 0.0, 0.0, f64::NAN).validate("link").unwrap_err();
        assert_eq!(e.key, "link.duplicate");
    }

    #[test]
    fn toml_section_rejects_unknown_keys_and_fills_defaults() {
        let c: FaultConfig = toml::from_str("latency = 0.002\nloss = 0.1\n").unwrap();
        assert_eq!(c.latency, 0.002);
        assert_eq!(c.loss, 0.1);
        assert_eq!(c.jitter, 0.0);
        let e = toml::from_str::<FaultConfig>("latncy = 0.002\n").unwrap_err();
        assert!(e.to_string().contains("latncy"), "{e}");
    }
}
