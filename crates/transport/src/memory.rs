//! In-process link for the threaded deployment: two endpoints connected in
//! memory by one lock-free triple buffer per direction (no sockets).
//!
//! Latest wins by construction: the receiver sees the last message written
//! since it last looked; messages written in between are overwritten and
//! counted in [`LinkStats::overwritten`]. Faults apply as on UDP (the delay
//! line sits in front of the buffer), and the receiver's sequence filter
//! drops what jitter reordered.

use crate::fault::FaultConfig;
use crate::link::{count_decode_error, Endpoint, LinkError, Transport};
use crate::message::{ByeMsg, Message};
use crate::sequence::LinkStats;
use crate::DecodeError;
use triple_buffer::{triple_buffer, Input, Output};

#[derive(Clone, Copy)]
struct Slot {
    /// Write counter, 0 = never written.
    index: u64,
    msg: Message,
}

/// One side of an in-process connection.
pub struct MemoryTransport {
    tx: Input<Slot>,
    rx: Output<Slot>,
    written: u64,
    last_read: u64,
}

/// An in-process [`crate::Link`].
pub type InProcessEndpoint = Endpoint<MemoryTransport>;

/// Two connected in-process endpoints of session `session` (any id; no
/// tag: the memory of one process needs none): what `a` sends
/// (with faults `a_faults`), `b` receives, and the other way round with
/// `b_faults`. Validate the fault configurations first.
pub fn in_process_pair(
    session: u64,
    a_faults: FaultConfig,
    b_faults: FaultConfig,
) -> (InProcessEndpoint, InProcessEndpoint) {
    let (a, b) = MemoryTransport::pair();
    (
        Endpoint::new(a, session, a_faults),
        Endpoint::new(b, session, b_faults),
    )
}

impl MemoryTransport {
    /// Two connected raw transports (no faults, no filter): what one
    /// transmits, the other receives.
    pub fn pair() -> (MemoryTransport, MemoryTransport) {
        let empty = Slot {
            index: 0,
            msg: Message::Bye(ByeMsg::new(0)),
        };
        let (a_tx, b_rx) = triple_buffer(&empty);
        let (b_tx, a_rx) = triple_buffer(&empty);
        let side = |tx, rx| MemoryTransport {
            tx,
            rx,
            written: 0,
            last_read: 0,
        };
        (side(a_tx, a_rx), side(b_tx, b_rx))
    }
}

impl Transport for MemoryTransport {
    fn transmit(&mut self, msg: &Message, _stats: &mut LinkStats) -> Result<(), LinkError> {
        self.written += 1;
        self.tx.write(Slot {
            index: self.written,
            msg: *msg,
        });
        Ok(())
    }

    fn receive(
        &mut self,
        session: u64,
        stats: &mut LinkStats,
    ) -> Result<Option<Message>, LinkError> {
        if !self.rx.updated() {
            return Ok(None);
        }
        let slot = *self.rx.read();
        if slot.index <= self.last_read {
            return Ok(None);
        }
        stats.overwritten += slot.index - self.last_read - 1;
        self.last_read = slot.index;
        let found = slot.msg.header().session;
        if found != session {
            count_decode_error(DecodeError::WrongSession { found }, stats);
            return Ok(None);
        }
        Ok(Some(slot.msg))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::{ProbeMsg, SampleMsg};
    use crate::Link;

    fn probe(x: f64) -> Message {
        Message::Probe(ProbeMsg::new(x, [x, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], 0))
    }

    #[test]
    fn messages_cross_both_ways_and_latest_wins() {
        let (mut a, mut b) = in_process_pair(9, FaultConfig::default(), FaultConfig::default());
        assert!(b.recv(0.0).unwrap().is_none());
        for i in 0..5 {
            a.send(probe(f64::from(i)), 0.0).unwrap();
        }
        let got = b.recv(0.001).unwrap().unwrap();
        assert_eq!(got.seq(), 4);
        assert!(b.recv(0.001).unwrap().is_none());
        assert_eq!(b.stats().overwritten, 4);
        assert_eq!(b.last_heard(), Some(0.001));

        b.send(Message::Sample(SampleMsg::default()), 0.002)
            .unwrap();
        let got = a.recv(0.003).unwrap().unwrap();
        assert!(matches!(got, Message::Sample(_)));
        assert_eq!(got.header().session, 9);
        assert_eq!(got.header().t_send, 0.002);
    }

    #[test]
    fn latency_holds_messages_until_due() {
        let faults = FaultConfig {
            latency: 0.01,
            ..FaultConfig::default()
        };
        let (mut a, mut b) = in_process_pair(1, faults, FaultConfig::default());
        a.send(probe(1.0), 0.0).unwrap();
        assert!(b.recv(0.005).unwrap().is_none());
        a.poll(0.00999).unwrap();
        assert!(b.recv(0.00999).unwrap().is_none());
        a.poll(0.01).unwrap();
        assert_eq!(b.recv(0.01).unwrap().unwrap().seq(), 0);
    }

    #[test]
    fn duplicates_are_delivered_once_after_filtering() {
        let faults = FaultConfig {
            duplicate: 1.0,
            ..FaultConfig::default()
        };
        let (mut a, mut b) = in_process_pair(1, faults, FaultConfig::default());
        let mut delivered = Vec::new();
        for i in 0..100 {
            let now = f64::from(i) * 1e-3;
            // The receiver reads after each copy lands: both copies reach it.
            a.send(probe(now), now).unwrap();
            while let Some(m) = b.recv(now).unwrap() {
                delivered.push(m.seq());
            }
        }
        assert_eq!(delivered, (0..100).collect::<Vec<u64>>());
        assert_eq!(a.stats().fault_duplicated, 100);
        assert_eq!(a.stats().transmitted, 200);
    }

    #[test]
    fn bye_marks_peer_closed_and_silence_is_detected() {
        let (mut a, mut b) = in_process_pair(1, FaultConfig::default(), FaultConfig::default());
        assert!(b.peer_silent(0.0, 0.1), "never heard counts as silent");
        a.send(probe(0.0), 0.0).unwrap();
        b.recv(0.0).unwrap();
        assert!(!b.peer_silent(0.05, 0.1));
        assert!(b.peer_silent(0.2, 0.1));
        a.close(0.3).unwrap();
        assert!(matches!(a.send(probe(0.0), 0.3), Err(LinkError::Closed)));
        assert!(matches!(b.recv(0.3).unwrap(), Some(Message::Bye(_))));
        assert!(b.peer_closed());
        assert!(b.peer_silent(0.3, 1.0));
    }

    #[test]
    fn wrong_session_is_counted_not_delivered() {
        let (mut a, mut b) = MemoryTransport::pair();
        let mut stats = LinkStats::default();
        let mut msg = probe(0.0);
        msg.header_mut().session = 1;
        a.transmit(&msg, &mut stats).unwrap();
        assert!(b.receive(2, &mut stats).unwrap().is_none());
        assert_eq!(stats.wrong_session, 1);
        a.transmit(&msg, &mut stats).unwrap();
        assert!(b.receive(1, &mut stats).unwrap().is_some());
    }
}
