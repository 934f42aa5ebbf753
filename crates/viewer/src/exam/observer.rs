//! The exam observer: a thread that samples the live state at
//! [`SAMPLE_RATE`] for the open case's event detector, whatever the pages'
//! push rates (one sample stream per session, not per connection). It has a
//! stop signal and is joined when the server stops.

use crate::server::AppState;
use echothigh_exam::ExamSample;
use echothigh_runtime::live::{LiveSnapshot, LiveStatus};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Sampling rate of the live state (Hz): the detector's force trace rate
/// ([`echothigh_exam::detector::TRACE_RATE`]); a press lasts ≥ 0.5 s, so its
/// peak is caught within 20 ms (the force changes < 1 N in that time at a
/// trainee's ~30 N/s).
pub const SAMPLE_RATE: f64 = 50.0;

/// Nominal radius of the thigh (m) that turns the probe's angle around the
/// leg into an arc length on the skin for the slide measure: a mid-thigh
/// circumference of ~0.5 m (the average build of `crates/anatomy`) over 2π.
/// The slide threshold (1 cm) is a few degrees, so the leg's taper matters
/// little.
pub const NOMINAL_RADIUS: f64 = 0.08;

/// The detector's sample from the live `status` at `t` (s since the case
/// started): the force the hand applies (the rendered force's magnitude),
/// the probe's place on the skin (`[z along the leg, angle × radius]`: not
/// changed by pressing in), and the imaging thread's reading of the section
/// (vein, `s`, lumen ratios). `None` before the first reading.
pub fn sample(status: &LiveStatus, t: f64) -> Option<ExamSample> {
    let r = status.section?;
    let [fx, fy, fz] = status.rendered_force;
    let [x, y, z] = status.probe_position;
    Some(ExamSample {
        t,
        force: (fx * fx + fy * fy + fz * fz).sqrt(),
        skin: [z, x.atan2(y) * NOMINAL_RADIUS],
        vein: r.vein.map(|v| v.as_str()),
        s: r.s,
        vein_ratio: r.vein_lumen_ratio,
        artery_ratio: r.artery_lumen_ratio,
    })
}

/// The running observer.
pub struct ExamObserver {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl ExamObserver {
    /// Starts sampling `app`'s live state.
    pub fn spawn(app: Arc<AppState>) -> std::io::Result<ExamObserver> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("exam-observer".into())
            .spawn(move || {
                let period = Duration::from_secs_f64(1.0 / SAMPLE_RATE);
                let mut snap = LiveSnapshot::default();
                let mut next = Instant::now();
                while !flag.load(Ordering::Acquire) {
                    app.snapshot_into(&mut snap);
                    app.observe_exam(&snap, Instant::now());
                    next += period;
                    let now = Instant::now();
                    if next > now {
                        std::thread::sleep(next - now);
                    } else {
                        next = now;
                    }
                }
            })?;
        Ok(ExamObserver {
            stop,
            thread: Some(thread),
        })
    }

    /// Stops the thread and joins it.
    pub fn stop(mut self) {
        self.halt();
    }

    fn halt(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            if t.join().is_err() {
                tracing::error!("the exam observer thread panicked");
            }
        }
    }
}

impl Drop for ExamObserver {
    fn drop(&mut self) {
        self.halt();
    }
}
