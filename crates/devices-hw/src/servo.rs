//! The lock-free exchange between the haptic tick and an SDK's servo thread.
//!
//! Each SDK runs its own servo thread (HD's scheduler calls our callback at
//! 1 kHz; for DHD we run one, since every DHD call is USB I/O). The tick
//! must not block, allocate or do I/O, so it never calls the SDK: it reads
//! the latest [`ServoState`] and writes a [`ServoCommand`] through two
//! single-slot triple buffers (`triple_buffer`, wait-free, no allocation
//! after construction), SOFA's handoff habit.
//!
//! **Watchdog.** The servo side applies a command only while it is fresh:
//! when no new command arrived for `watchdog_timeout` (s), or the stop flag
//! is set (closing, emergency release), it commands zero force. The servo
//! thread belongs to the SDK, not to the tick, so a stalled tick (or a
//! panicking thread that never ticks again) still ends with zero force.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;
use triple_buffer::TripleBuffer;

/// What the servo thread last read from the device (device frame, SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoState {
    /// End-effector position (m, device frame).
    pub position: [f64; 3],
    /// End-effector velocity (m/s, device frame).
    pub velocity: [f64; 3],
    /// Tool orientation, row-major 3×3, device ← tool; identity when not sensed.
    pub rotation: [f64; 9],
    /// Button mask (bit 0 = first button).
    pub buttons: u32,
    /// Servo iterations since start.
    pub ticks: u64,
    /// Non-zero once the device failed (an SDK error code, or [`FAULT_LOST`]); latched.
    pub fault: u32,
}

/// The device stopped answering (unplugged, communication error).
pub const FAULT_LOST: u32 = u32::MAX;

impl Default for ServoState {
    fn default() -> Self {
        ServoState {
            position: [0.0; 3],
            velocity: [0.0; 3],
            rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            buttons: 0,
            ticks: 0,
            fault: 0,
        }
    }
}

/// A force command from the tick (N, device frame) with its sequence number.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ServoCommand {
    /// Force to render (N, device frame), already limited and ramped.
    pub force: [f64; 3],
    /// Incremented by every command; the watchdog watches it change.
    pub sequence: u64,
}

/// Flags and counters shared by the tick, the servo thread and any thread
/// that may press the emergency release.
#[derive(Debug, Default)]
pub struct Shared {
    /// Set to zero the force and stop (closing or emergency release).
    pub stop: AtomicBool,
    /// Set by [`EmergencyRelease::trigger`]: zero force until reopened.
    pub emergency: AtomicBool,
    /// Servo iterations at which the watchdog held a stale command at zero.
    pub watchdog_trips: AtomicU64,
    /// Servo iterations run (the closing side waits for one zero-force frame).
    pub servo_ticks: AtomicU64,
}

/// A handle that any thread (a key, a button of the page) can use to cut
/// the device's force at once; the servo thread obeys it on its next tick.
#[derive(Debug, Clone)]
pub struct EmergencyRelease(pub(crate) Arc<Shared>);

impl EmergencyRelease {
    /// Zeroes the force until the device is reopened.
    pub fn trigger(&self) {
        self.0.emergency.store(true, Ordering::Release);
    }
    /// Whether the release was triggered.
    pub fn triggered(&self) -> bool {
        self.0.emergency.load(Ordering::Acquire)
    }
}

/// The tick's half: reads states, writes commands.
pub struct TickSide {
    state: triple_buffer::Output<ServoState>,
    command: triple_buffer::Input<ServoCommand>,
    sequence: u64,
}

impl TickSide {
    /// The latest state the servo thread published (wait-free).
    pub fn latest(&mut self) -> ServoState {
        *self.state.read()
    }
    /// Publishes a force (N, device frame) (wait-free).
    pub fn command(&mut self, force: [f64; 3]) {
        self.sequence = self.sequence.wrapping_add(1);
        self.command.write(ServoCommand {
            force,
            sequence: self.sequence,
        });
    }
}

/// The servo thread's half: publishes states, takes commands through the watchdog.
pub struct ServoSide {
    state: triple_buffer::Input<ServoState>,
    command: triple_buffer::Output<ServoCommand>,
    shared: Arc<Shared>,
    watchdog_timeout: f64,
    epoch: Instant,
    last_sequence: u64,
    fresh_at: f64,
}

impl ServoSide {
    /// Publishes what the servo thread read from the device.
    pub fn publish(&mut self, state: ServoState) {
        self.state.write(state);
        self.shared.servo_ticks.fetch_add(1, Ordering::Release);
    }

    /// The force (N, device frame) to apply now: the latest command while it
    /// is fresh, zero when it is older than the watchdog timeout, when the
    /// stop or emergency flag is set, or when it is not finite.
    pub fn force_to_apply(&mut self) -> [f64; 3] {
        let now = self.epoch.elapsed().as_secs_f64();
        let command = *self.command.read();
        if command.sequence != self.last_sequence {
            self.last_sequence = command.sequence;
            self.fresh_at = now;
        }
        if self.stopping() || !command.force.iter().all(|f| f.is_finite()) {
            return [0.0; 3];
        }
        if now - self.fresh_at > self.watchdog_timeout {
            if command.force != [0.0; 3] {
                self.shared.watchdog_trips.fetch_add(1, Ordering::Relaxed);
            }
            return [0.0; 3];
        }
        command.force
    }

    /// Whether the servo must stop rendering (closing or emergency release).
    pub fn stopping(&self) -> bool {
        self.shared.stop.load(Ordering::Acquire) || self.shared.emergency.load(Ordering::Acquire)
    }
}

/// After the stop flag is set: waits (sleeping, off the tick) until the
/// servo thread ran two more iterations, each rendering zero, or `timeout` s passed.
pub fn wait_for_zero_frames(shared: &Shared, timeout: f64) {
    let start = shared.servo_ticks.load(Ordering::Acquire);
    let began = Instant::now();
    while shared.servo_ticks.load(Ordering::Acquire) < start + 2
        && began.elapsed().as_secs_f64() < timeout
    {
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
}

/// Creates both halves and their shared flags. `watchdog_timeout` in s.
pub fn exchange(watchdog_timeout: f64) -> (TickSide, ServoSide, Arc<Shared>) {
    let (state_in, state_out) = TripleBuffer::new(&ServoState::default()).split();
    let (command_in, command_out) = TripleBuffer::new(&ServoCommand::default()).split();
    let shared = Arc::new(Shared::default());
    (
        TickSide {
            state: state_out,
            command: command_in,
            sequence: 0,
        },
        ServoSide {
            state: state_in,
            command: command_out,
            shared: Arc::clone(&shared),
            watchdog_timeout,
            epoch: Instant::now(),
            last_sequence: 0,
            fresh_at: 0.0,
        },
        shared,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_command_is_zeroed_and_fresh_one_passes() {
        let (mut tick, mut servo, shared) = exchange(0.005);
        tick.command([1.0, -2.0, 0.5]);
        assert_eq!(servo.force_to_apply(), [1.0, -2.0, 0.5]);
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert_eq!(servo.force_to_apply(), [0.0; 3]);
        assert_eq!(shared.watchdog_trips.load(Ordering::Relaxed), 1);
        tick.command([0.0, 1.0, 0.0]);
        assert_eq!(servo.force_to_apply(), [0.0, 1.0, 0.0]);
        EmergencyRelease(Arc::clone(&shared)).trigger();
        tick.command([0.0, 1.0, 0.0]);
        assert_eq!(servo.force_to_apply(), [0.0; 3]);
    }

    #[test]
    fn non_finite_command_renders_zero() {
        let (mut tick, mut servo, _) = exchange(1.0);
        tick.command([f64::NAN, 0.0, 0.0]);
        assert_eq!(servo.force_to_apply(), [0.0; 3]);
    }
}
