//! The imaging thread's share of the CPU under load (issue 19: "the
//! simulation keeps its rates under load").
//!
//! The haptic loop (FIFO 99) and the physics (FIFO 50) preempt every
//! time-shared thread. The imaging thread is not real-time work: a late
//! frame is a stale picture, not an unstable force. It stays time-shared
//! (SCHED_OTHER), so it can never starve the browser or the server that
//! sends its frames, but at nice [`IMAGING_NICE`]: the kernel's CFS weighs
//! nice −10 at 9 548 against 1 024 for nice 0 (kernel/sched/core.c,
//! `sched_prio_to_weight`), so against a busy browser process on its core it
//! gets ~90 % of that core while it has a frame to render. It needs ~25–40 %
//! of one at 20 frames/s (a 256 × 384 frame is ~12 ms, plus its lumens,
//! labels and overlay). On the 2-core CI machine under Chromium it reached
//! 2.9–7.8 frames/s of 20 at nice 0.

/// The imaging thread's nice value where the process may raise it
/// (CAP_SYS_NICE or root; RLIMIT_NICE otherwise).
pub const IMAGING_NICE: i32 = -10;

/// Sets the calling thread's nice value to [`IMAGING_NICE`] if `raise`;
/// whether it was granted. On Linux the nice value is per thread:
/// `setpriority(PRIO_PROCESS, 0, …)` sets the caller's (setpriority(2),
/// "Linux notes").
pub fn request_imaging_priority(raise: bool) -> bool {
    if !raise {
        return false;
    }
    #[cfg(target_os = "linux")]
    {
        // SAFETY: setpriority reads no memory of ours; who = 0 is this thread.
        let ret = unsafe { libc::setpriority(libc::PRIO_PROCESS, 0, IMAGING_NICE) };
        if ret == 0 {
            tracing::info!(nice = IMAGING_NICE, "imaging thread at raised priority");
            return true;
        }
        tracing::info!(
            "imaging thread at normal priority (raising it refused: {})",
            std::io::Error::last_os_error()
        );
        false
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}
