//! How often a connection sends image frames (issue 19): as fast as the
//! byte budget allows while the probe moves, at [`STILL_RATE`] while it
//! holds still.
//!
//! A live frame of speckle is ~39 KB as a JPEG, so the 400 KB/s budget
//! carries ~9 frames/s, and the frame that first shows a command's effect
//! waited for the budget (up to a frame's worth, ~110 ms). While the probe
//! holds still the image changes only by its noise and by slow motions
//! (breathing, the smoke of slow flow): a few frames a second show them,
//! and the budget they leave builds up in the bucket
//! ([`super::frames::BURST_BYTES`]), so that the frames after the next press
//! or slide go at once; for the same reason the frames answering the
//! page's own probe command may overdraw the budget by
//! [`RESPONSE_RESERVE`] for [`RESPONSE_WINDOW`]. In colour or power Doppler the overlay moves with
//! the flow's pulse even under a still probe: every frame counts as moving.

/// How long after a probe command from the page its frames may draw on
/// [`RESPONSE_RESERVE`] (s): the state shows a command's effect within
/// ~0.1 s at the 95th percentile (the browser test's server part of the
/// lag), and the frame after it follows within an imaging period (50 ms).
pub const RESPONSE_WINDOW: f64 = 0.3;

/// Bytes the frames answering a probe command may go below an empty
/// budget: two live frames (~39 KB each), the one rendered before the
/// command's effect reached the physics and the one showing it. The
/// frames after them repay it; over any span the bytes stay within
/// `rate · T + burst + reserve + one message`.
pub const RESPONSE_RESERVE: f64 = 80_000.0;

/// Frames per second sent while the probe holds still.
pub const STILL_RATE: f64 = 5.0;

/// Force change (N) since the last frame sent that counts as moving: 0.1 N,
/// the force gauge's smallest division a trainee reads (its scale is in N
/// with one decimal), about 1 % of a compression's ~10 N.
pub const MOVING_FORCE: f64 = 0.1;

/// Probe displacement (m) since the last frame sent that counts as
/// moving: 0.1 mm, under a pixel of the live image (0.16 mm a column).
pub const MOVING_DISTANCE: f64 = 1e-4;

/// What the last frame sent showed, and when it went.
#[derive(Debug, Default, Clone, Copy)]
pub struct ImagePace {
    last: Option<Sent>,
}

#[derive(Debug, Clone, Copy)]
struct Sent {
    at: f64,
    force: [f64; 3],
    position: [f64; 3],
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

impl ImagePace {
    /// Whether a new frame may go at `now` (s, monotonic) with the probe's
    /// physics `force` (N) and `position` (m); `flow`: a colour or power
    /// overlay is drawn. The first frame always may; a non-finite reading
    /// counts as moving (the frame goes, the page shows what there is).
    pub fn due(&self, now: f64, force: [f64; 3], position: [f64; 3], flow: bool) -> bool {
        let Some(last) = self.last else {
            return true;
        };
        let moved = distance(force, last.force) > MOVING_FORCE
            || distance(position, last.position) > MOVING_DISTANCE;
        let unknown = !(distance(force, last.force).is_finite()
            && distance(position, last.position).is_finite());
        flow || moved || unknown || now - last.at >= 1.0 / STILL_RATE
    }

    /// Records the frame sent at `now` with the probe's `force` and `position`.
    pub fn sent(&mut self, now: f64, force: [f64; 3], position: [f64; 3]) {
        self.last = Some(Sent {
            at: now,
            force,
            position,
        });
    }

    /// Forgets the last frame (a new leg: the next frame goes at once).
    pub fn reset(&mut self) {
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: [f64; 3] = [0.0, 0.07, 0.0];
    const F: [f64; 3] = [0.0, 5.0, 0.0];

    #[test]
    fn a_still_probe_gets_still_frames_and_a_moving_one_every_frame() {
        let mut pace = ImagePace::default();
        assert!(pace.due(0.0, F, P, false), "the first frame");
        pace.sent(0.0, F, P);
        // Still: not before 1 / STILL_RATE = 0.2 s.
        assert!(!pace.due(0.1, F, P, false));
        assert!(!pace.due(0.1, [0.0, 5.09, 0.0], [0.0, 0.07009, 0.0], false));
        assert!(pace.due(0.2, F, P, false));
        // A press (0.11 N), a slide (0.11 mm), colour flow: at once.
        assert!(pace.due(0.01, [0.0, 5.11, 0.0], P, false));
        assert!(pace.due(0.01, F, [0.00011, 0.07, 0.0], false));
        assert!(pace.due(0.01, F, P, true));
        // A NaN reading: the frame goes.
        assert!(pace.due(0.01, [f64::NAN, 5.0, 0.0], P, false));
        pace.reset();
        assert!(pace.due(0.01, F, P, false), "after a reset");
    }
}
