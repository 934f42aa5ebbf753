//! Receiver-side ordering: the latest message wins, reordered, duplicated
//! and replayed datagrams are dropped by sequence number, and so is a
//! sequence too far ahead to be real; counters in [`LinkStats`].
//!
//! The accepted sequence is strictly increasing, so a replayed datagram
//! (a captured copy sent again) is always `Duplicate` or `Stale`. A jump
//! ahead is bounded by [`MAX_SEQ_JUMP`]: a sender's sequence advances once
//! per message sent, so the gap between two accepted datagrams is at most
//! the messages lost in between, i.e. the send rate times the time lost.
//! With [`MAX_SEND_RATE`] = 10 kHz (ten times the 1 kHz haptic loop, the
//! fastest sender) and [`MAX_GAP`] = 60 s of total loss (beyond any peer
//! timeout: a link silent that long has ended its session), the bound is
//! 600 000. A datagram further ahead (e.g. sequence 2⁶⁴−1) is refused and
//! counted, and cannot freeze the session at an unreachable sequence.

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
    /// Rejected: datagrams of the wrong size, magic, version or kind.
    pub malformed: u64,
    /// Rejected: values non-finite or out of bounds ([`crate::limits`]).
    pub bad_value: u64,
    /// Rejected: datagrams whose tag does not verify (forged or altered).
    pub bad_mac: u64,
    /// Rejected: datagrams of another session (another session id).
    pub wrong_session: u64,
    /// Rejected at the handshake: Hellos whose tag shows a wrong token.
    pub wrong_token: u64,
    /// Rejecting Byes sent to wrong-token Hellos.
    pub rejections_sent: u64,
    /// Wrong-token Hellos left unanswered by the rate limit (at most one
    /// answer per source per second, and a cap over all sources).
    pub rejections_suppressed: u64,
    /// Rejected: sequence equal to the last accepted one (duplicate, replay).
    pub duplicate: u64,
    /// Rejected: sequence below the last accepted one (reordered, replay).
    pub stale: u64,
    /// Rejected: sequence more than [`MAX_SEQ_JUMP`] ahead.
    pub seq_jump: u64,
    /// In-process link: messages overwritten before the receiver read them.
    pub overwritten: u64,
    /// Transport errors that were survived (e.g. ICMP port unreachable).
    pub io_errors: u64,
}

impl LinkStats {
    /// Every datagram rejected on receipt, all reasons together.
    pub fn rejected(&self) -> u64 {
        self.malformed
            + self.bad_value
            + self.bad_mac
            + self.wrong_session
            + self.wrong_token
            + self.duplicate
            + self.stale
            + self.seq_jump
    }
}

/// Fastest sender of the link, messages/s (see the module docs).
pub const MAX_SEND_RATE: u64 = 10_000;
/// Longest stretch of total loss a live session can see, s.
pub const MAX_GAP: u64 = 60;
/// Largest accepted jump of the sequence: `MAX_SEND_RATE · MAX_GAP`.
pub const MAX_SEQ_JUMP: u64 = MAX_SEND_RATE * MAX_GAP;

/// Verdict of the [`SequenceFilter`] on one sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeqVerdict {
    /// Newer than anything accepted: deliver.
    Accept,
    /// Equal to the last accepted sequence.
    Duplicate,
    /// Older than the last accepted sequence.
    Stale,
    /// More than [`MAX_SEQ_JUMP`] ahead of the last accepted sequence.
    TooFarAhead,
}

/// Drops every datagram whose sequence number is not greater than the last
/// accepted one, or more than [`MAX_SEQ_JUMP`] greater (one sender, one
/// counter over all kinds). The first sequence is accepted as it comes:
/// on UDP it is the handshake's, which only the peer can tag.
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
            Some(last) if seq - last > MAX_SEQ_JUMP => SeqVerdict::TooFarAhead,
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
            SeqVerdict::TooFarAhead => {
                stats.seq_jump += 1;
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
    fn jumps_beyond_the_bound_are_refused_and_do_not_move_the_window() {
        let mut f = SequenceFilter::new();
        let mut stats = LinkStats::default();
        assert!(f.accept(10, &mut stats));
        assert!(!f.accept(u64::MAX, &mut stats));
        assert!(!f.accept(10 + MAX_SEQ_JUMP + 1, &mut stats));
        assert_eq!(stats.seq_jump, 2);
        assert!(f.accept(11, &mut stats), "the real sender goes on");
        assert!(f.accept(11 + MAX_SEQ_JUMP, &mut stats), "the bound itself");
        assert_eq!(stats.rejected(), 2);
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
