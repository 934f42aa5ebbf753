//! Receiver-side ordering: the latest message wins, reordered and duplicated
//! datagrams are dropped by sequence number; counters in [`LinkStats`].

/// Counters of one endpoint (both directions). Plain data, `Copy`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Messages handed to [`crate::Link::send`].
    pub sent: u64,
    /// Datagrams actually put on the transport (after loss and duplication).
    pub transmitted: u64,
    /// Messages dropped by the fault injector's loss.
    pub fault_lost: u64,
    /// Extra copies made by the fault injector's duplication.
    pub fault_duplicated: u64,
    /// Messages dropped because the delay line was full.
    pub queue_overflow: u64,
    /// Messages accepted by the receiver (passed the sequence filter).
    pub received: u64,
    /// Datagrams that failed to decode (size, magic, version, kind, NaN).
    pub malformed: u64,
    /// Datagrams with the wrong session token.
    pub wrong_token: u64,
    /// Datagrams whose sequence equals the last accepted one.
    pub duplicate: u64,
    /// Datagrams whose sequence is below the last accepted one (reordered).
    pub stale: u64,
    /// In-process link: messages overwritten before the receiver read them.
    pub overwritten: u64,
    /// Transport errors that were survived (e.g. ICMP port unreachable).
    pub io_errors: u64,
}

/// Verdict of the [`SequenceFilter`] on one sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqVerdict {
    /// Newer than anything accepted: deliver.
    Accept,
    /// Equal to the last accepted sequence.
    Duplicate,
    /// Older than the last accepted sequence.
    Stale,
}

/// Drops every datagram whose sequence number is not greater than the last
/// accepted one (one sender, one counter over all kinds).
#[derive(Clone, Copy, Debug, Default)]
pub struct SequenceFilter {
    last: Option<u64>,
}

impl SequenceFilter {
    /// A filter that accepts any first sequence number.
    pub fn new() -> Self {
        SequenceFilter { last: None }
    }

    /// Judges `seq`; on [`SeqVerdict::Accept`] it becomes the last accepted.
    pub fn check(&mut self, seq: u64) -> SeqVerdict {
        match self.last {
            Some(last) if seq == last => SeqVerdict::Duplicate,
            Some(last) if seq < last => SeqVerdict::Stale,
            _ => {
                self.last = Some(seq);
                SeqVerdict::Accept
            }
        }
    }

    /// Judges `seq` and counts a rejection in `stats`; true if accepted.
    pub fn accept(&mut self, seq: u64, stats: &mut LinkStats) -> bool {
        match self.check(seq) {
            SeqVerdict::Accept => true,
            SeqVerdict::Duplicate => {
                stats.duplicate += 1;
                false
            }
            SeqVerdict::Stale => {
                stats.stale += 1;
                false
            }
        }
    }

    /// The last accepted sequence number.
    pub fn last_accepted(&self) -> Option<u64> {
        self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reordered_and_duplicated_sequences_are_dropped() {
        let mut f = SequenceFilter::new();
        let mut stats = LinkStats::default();
        let arrivals = [5u64, 6, 6, 4, 8, 7, 8, 9, 1, 10];
        let accepted: Vec<u64> = arrivals
            .iter()
            .copied()
            .filter(|&s| f.accept(s, &mut stats))
            .collect();
        assert_eq!(accepted, vec![5, 6, 8, 9, 10]);
        assert_eq!(stats.duplicate, 2);
        assert_eq!(stats.stale, 3);
        assert_eq!(f.last_accepted(), Some(10));
    }

    #[test]
    fn first_sequence_zero_is_accepted() {
        let mut f = SequenceFilter::new();
        assert_eq!(f.check(0), SeqVerdict::Accept);
        assert_eq!(f.check(0), SeqVerdict::Duplicate);
    }

    #[test]
    fn accepted_sequence_is_strictly_increasing() {
        // Invariant over a pseudo-random arrival order.
        let mut f = SequenceFilter::new();
        let mut stats = LinkStats::default();
        let mut prev = None;
        let mut x = 12345u64;
        for _ in 0..1000 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let seq = (x >> 33) % 500;
            if f.accept(seq, &mut stats) {
                assert!(!matches!(prev, Some(p) if seq <= p));
                prev = Some(seq);
            }
        }
    }
}
