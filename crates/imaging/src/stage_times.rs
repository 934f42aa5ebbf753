//! Per-stage times of the last frame ([`crate::Renderer::stage_times`]),
//! read from a clock the caller may choose (issue 21's benchmark reads the
//! thread's CPU time): nine clock reads a frame, nothing allocated.

use std::sync::OnceLock;
use std::time::Instant;

/// Seconds since the first call in the process, on the monotonic wall
/// clock: the renderer's default stage clock.
pub fn wall_seconds() -> f64 {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    EPOCH.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Time (s) spent in each stage of the last rendered frame, on the
/// renderer's stage clock ([`crate::Renderer::set_stage_clock`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// Frame geometry, lumens, warps, edge shadows and the specular
    /// interfaces' depths ([`crate::Renderer`]'s stage 1).
    pub prepare: f64,
    /// Axial splat of the scatterers and specular points into the padded
    /// columns.
    pub splat: f64,
    /// Lateral convolution with the depth-dependent lateral PSF.
    pub convolve: f64,
    /// Round-trip loss exponent of every column (the attenuation).
    pub loss: f64,
    /// Reverberation and smoke added to the echo.
    pub echoes: f64,
    /// Loss averaged across the beam near the vessels' margins, edge
    /// shadows, clutter, noise, TGC and log compression.
    pub compress: f64,
    /// Transpose of the column-major gray levels into the row-major frame.
    pub transpose: f64,
}

impl StageTimes {
    /// The sum of the stages (s).
    pub fn total(&self) -> f64 {
        self.prepare
            + self.splat
            + self.convolve
            + self.loss
            + self.echoes
            + self.compress
            + self.transpose
    }
}

/// Reads a clock at the end of each stage.
pub(crate) struct Lap {
    clock: fn() -> f64,
    last: f64,
}

impl Lap {
    /// Starts at the clock's current time.
    #[inline]
    pub fn start(clock: fn() -> f64) -> Self {
        Lap {
            clock,
            last: clock(),
        }
    }

    /// Seconds since the last lap (or the start).
    #[inline]
    pub fn lap(&mut self) -> f64 {
        let now = (self.clock)();
        let dt = now - self.last;
        self.last = now;
        dt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laps_add_up_to_the_elapsed_time() {
        // A fake clock advancing 1, 2, 3, ... seconds per read.
        fn fake() -> f64 {
            use std::sync::atomic::{AtomicU64, Ordering};
            static N: AtomicU64 = AtomicU64::new(0);
            let n = N.fetch_add(1, Ordering::Relaxed) as f64;
            n * (n + 1.0) / 2.0
        }
        let mut lap = Lap::start(fake);
        let (a, b) = (lap.lap(), lap.lap());
        assert_eq!((a, b), (1.0, 2.0));
        let t = StageTimes {
            prepare: a,
            splat: b,
            ..Default::default()
        };
        assert_eq!(t.total(), 3.0);
    }
}
