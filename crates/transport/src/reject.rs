//! Rate limits on what a wrong-token Hello costs the server: a rejecting
//! reply at most once per second per source address and at most
//! [`MAX_REJECTIONS_PER_S`] per second over all sources, and a log line at
//! most once per second that counts the Hellos refused since the last one
//! (issue 20: 1 M forged Hellos once cost 120 k replies and 21 MB of log).
//!
//! The per-source memory is a fixed table of [`SOURCES`] addresses, oldest
//! replaced first: a flood from more addresses than that is still capped
//! by the global limit. Sources are compared by IP address, not port (a
//! sender changing ports is the same host). No allocation.

use std::net::{IpAddr, SocketAddr};
use std::time::{Duration, Instant};

/// Most rejecting replies per second over all sources.
pub const MAX_REJECTIONS_PER_S: u32 = 10;
/// Sources remembered for the per-source limit.
const SOURCES: usize = 64;
const SECOND: Duration = Duration::from_secs(1);

/// Decides which wrong-token Hellos get an answer, and logs them sparsely.
pub(crate) struct RejectLimiter {
    recent: [Option<(IpAddr, Instant)>; SOURCES],
    next: usize,
    window_start: Option<Instant>,
    in_window: u32,
    last_log: Option<Instant>,
    unlogged: u64,
}

impl RejectLimiter {
    pub(crate) fn new() -> Self {
        RejectLimiter {
            recent: [None; SOURCES],
            next: 0,
            window_start: None,
            in_window: 0,
            last_log: None,
            unlogged: 0,
        }
    }

    /// Records a wrong-token Hello from `from` at `now`; true if it may be
    /// answered.
    pub(crate) fn refused(&mut self, from: SocketAddr, now: Instant) -> bool {
        self.unlogged += 1;
        if !matches!(self.last_log, Some(t) if now.duration_since(t) < SECOND) {
            tracing::warn!(
                refused = self.unlogged,
                last_source = %from,
                "refused Hello(s) with a wrong session token"
            );
            self.last_log = Some(now);
            self.unlogged = 0;
        }
        let ip = from.ip();
        let seen = self.recent.iter_mut().flatten().find(|(a, _)| *a == ip);
        if let Some((_, last)) = seen {
            if now.duration_since(*last) < SECOND {
                return false;
            }
        }
        if !matches!(self.window_start, Some(t) if now.duration_since(t) < SECOND) {
            self.window_start = Some(now);
            self.in_window = 0;
        }
        if self.in_window >= MAX_REJECTIONS_PER_S {
            return false;
        }
        self.in_window += 1;
        match self.recent.iter_mut().flatten().find(|(a, _)| *a == ip) {
            Some(entry) => entry.1 = now,
            None => {
                self.recent[self.next] = Some((ip, now));
                self.next = (self.next + 1) % SOURCES;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::Ipv4Addr;

    fn addr(host: u8, port: u16) -> SocketAddr {
        SocketAddr::from((Ipv4Addr::new(10, 0, 0, host), port))
    }

    #[test]
    fn one_answer_per_source_per_second() {
        let mut l = RejectLimiter::new();
        let t0 = Instant::now();
        assert!(l.refused(addr(1, 1000), t0));
        // Same host, any port, within the second: silent.
        for i in 0..1000u16 {
            let t = t0 + Duration::from_micros(u64::from(i) * 900);
            assert!(!l.refused(addr(1, 1000 + i), t));
        }
        assert!(l.refused(addr(1, 5), t0 + SECOND), "a second later");
    }

    #[test]
    fn at_most_the_global_cap_over_many_sources() {
        let mut l = RejectLimiter::new();
        let t0 = Instant::now();
        // 200 hosts in 0.2 s: 10 answers; the next second 10 more.
        let answered = (0..200u8)
            .filter(|&h| l.refused(addr(h, 1), t0 + Duration::from_millis(u64::from(h))))
            .count();
        assert_eq!(answered, MAX_REJECTIONS_PER_S as usize);
        let later = t0 + Duration::from_millis(1500);
        let answered = (0..200u8).filter(|&h| l.refused(addr(h, 2), later)).count();
        assert_eq!(answered, MAX_REJECTIONS_PER_S as usize);
    }
}
