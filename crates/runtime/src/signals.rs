//! The stop signal of a run: SIGINT (Ctrl-C) and SIGTERM set a flag that
//! every loop of the run polls; the loops stop, their threads are joined, the
//! recorder writes what it holds and the summary says the run was
//! interrupted. Nothing runs in the signal handler itself but the flag's
//! store (`signal-hook`'s `flag` module). A second SIGINT or SIGTERM while
//! the first is being handled ends the process at once (exit status 1),
//! as a user pressing Ctrl-C twice expects.

use anyhow::{Context, Result};
use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Returns a flag that SIGINT and SIGTERM set (installed once per call; call
/// it once per command).
pub fn stop_on_signals() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        // Order matters: the conditional shutdown sees the flag before the
        // first registration sets it, so only a second signal exits.
        signal_hook::flag::register_conditional_shutdown(sig, 1, stop.clone())
            .context("installing the signal handlers")?;
        signal_hook::flag::register(sig, stop.clone()).context("installing the signal handlers")?;
    }
    Ok(stop)
}
