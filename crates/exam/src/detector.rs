//! Compression events detected from the live state (issue 14 "Compression
//! events"): not from the trainee's word but from the probe force, where
//! the probe is, and the lumens under it.
//!
//! A press starts when the force rises above [`CONTACT_ON`] and ends when it
//! falls below [`CONTACT_OFF`] (hysteresis). During it the detector keeps
//! the peak force (and the vein and `s` at that peak), the smallest vein
//! lumen ratio, whether the artery deformed (its ratio below
//! [`ARTERY_CUE`]) and whether the walls met (vein ratio below
//! [`COAPTATION`]), how far the probe slid along the skin, and the force
//! trace at most [`TRACE_RATE`].
//!
//! Bounded memory: the trace's capacity is fixed when the detector is
//! built; a press longer than it holds is decimated in place (every other
//! point dropped, the interval doubled), so no sample allocates. Only the
//! event handed out at a press's end allocates (its vein name and trace).

use crate::CompressionEvent;
use serde::{Deserialize, Serialize};

/// Force (N) above which a press starts. The mean face pressure of 1 N on
/// the 40 × 10 mm face is 2.5 kPa (19 mmHg); the fidelity review's force
/// chain (§ "Force needed in the simulator") leaves every lumen at 1.00 up
/// to 1.6 N, so a probe resting on the skin below 1 N compresses nothing: it
/// is coupling, not a press.
pub const CONTACT_ON: f64 = 1.0;
/// Force (N) below which a press ends: half of [`CONTACT_ON`], so that the
/// force's ripple while holding (the haptic loop's, measured in the
/// scripted runs at a few hundredths of a newton) or a hand relaxing by up
/// to 0.5 N does not split one press into two.
pub const CONTACT_OFF: f64 = 0.5;
/// The companion artery's lumen ratio under which it has begun to deform:
/// the pressure is adequate (review §1 "Positive criterion"; the artery
/// law's 10 % is the "began to deform").
pub const ARTERY_CUE: f64 = 0.9;
/// The vein's lumen ratio under which its walls have met (the coaptation
/// criterion of the disease issue's tests: healthy < 10 % of rest).
pub const COAPTATION: f64 = 0.1;
/// Largest rate of the force trace (Hz).
pub const TRACE_RATE: f64 = 50.0;

/// What the detector reads at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExamSample {
    /// Time (s since the case started).
    pub t: f64,
    /// Probe force magnitude (N).
    pub force: f64,
    /// Where the probe's face centre is on the skin (m): `[s along the leg,
    /// arc around it]`, so that pressing in (along the normal) is not
    /// sliding.
    pub skin: [f64; 2],
    /// The vein under the probe (`cfv`, `fv`, `pv`, …), `None` when none is
    /// in the image.
    pub vein: Option<&'static str>,
    /// Where the image cuts that vein (m below the inguinal ligament).
    pub s: f64,
    /// The vein's lumen area over its rest area.
    pub vein_ratio: f64,
    /// The companion artery's lumen area over its rest area.
    pub artery_ratio: f64,
}

/// Why a sample was refused (the field named).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DetectorError {
    /// A field is not finite or out of its range.
    #[error("exam sample at t = {t} s: {field} = {value} {reason}")]
    Bad {
        /// The sample's time.
        t: f64,
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What is wrong.
        reason: &'static str,
    },
    /// Time went backwards.
    #[error("exam sample at t = {t} s comes before the previous one ({previous} s)")]
    Backwards {
        /// The sample's time.
        t: f64,
        /// The previous sample's.
        previous: f64,
    },
}

/// The press being tracked.
#[derive(Debug, Clone, Copy)]
struct Press {
    t_start: f64,
    peak: f64,
    vein: Option<&'static str>,
    s: f64,
    min_vein: f64,
    min_artery: f64,
    skin0: [f64; 2],
    slide: f64,
}

/// Turns a stream of [`ExamSample`]s into [`CompressionEvent`]s.
#[derive(Debug, Clone)]
pub struct EventDetector {
    press: Option<Press>,
    trace: Vec<[f64; 2]>,
    capacity: usize,
    interval: f64,
    last_t: f64,
}

impl EventDetector {
    /// A detector whose force trace holds `max_press` seconds at
    /// [`TRACE_RATE`] before it decimates (at least 16 points).
    pub fn new(max_press: f64) -> Self {
        let capacity = ((max_press.max(0.0) * TRACE_RATE).ceil() as usize).clamp(16, 1 << 20);
        EventDetector {
            press: None,
            trace: Vec::with_capacity(capacity),
            capacity,
            interval: 1.0 / TRACE_RATE,
            last_t: f64::NEG_INFINITY,
        }
    }

    /// Whether a press is under way.
    pub fn pressing(&self) -> bool {
        self.press.is_some()
    }

    /// Feeds one sample; returns the press that ended with it, if any.
    pub fn push(&mut self, x: &ExamSample) -> Result<Option<CompressionEvent>, DetectorError> {
        check(x)?;
        if x.t < self.last_t {
            return Err(DetectorError::Backwards {
                t: x.t,
                previous: self.last_t,
            });
        }
        self.last_t = x.t;
        match self.press.as_mut() {
            None => {
                if x.force > CONTACT_ON {
                    self.trace.clear();
                    self.interval = 1.0 / TRACE_RATE;
                    self.press = Some(Press {
                        t_start: x.t,
                        peak: x.force,
                        vein: x.vein,
                        s: x.s,
                        min_vein: x.vein_ratio,
                        min_artery: x.artery_ratio,
                        skin0: x.skin,
                        slide: 0.0,
                    });
                    self.record(x.t, x.force);
                }
                Ok(None)
            }
            Some(p) => {
                if x.force > p.peak {
                    p.peak = x.force;
                    p.vein = x.vein;
                    p.s = x.s;
                }
                p.min_vein = p.min_vein.min(x.vein_ratio);
                p.min_artery = p.min_artery.min(x.artery_ratio);
                let d = (x.skin[0] - p.skin0[0]).hypot(x.skin[1] - p.skin0[1]);
                p.slide = p.slide.max(d);
                if x.force < CONTACT_OFF {
                    let p = *p;
                    self.press = None;
                    self.record_last(x.t, x.force);
                    return Ok(Some(self.event(&p, x.t)));
                }
                self.record(x.t, x.force);
                Ok(None)
            }
        }
    }

    /// Ends a press still under way at `t` (the case is over), if any.
    pub fn finish(&mut self, t: f64) -> Option<CompressionEvent> {
        let p = self.press.take()?;
        Some(self.event(&p, t.max(p.t_start)))
    }

    fn event(&mut self, p: &Press, t_end: f64) -> CompressionEvent {
        CompressionEvent {
            t_start: p.t_start,
            t_end,
            vein: p.vein.map(str::to_string),
            s: p.s,
            peak_force: p.peak,
            min_lumen_ratio: p.min_vein,
            artery_deformed: p.min_artery < ARTERY_CUE,
            coapted: p.min_vein < COAPTATION,
            slide: p.slide,
            force_trace: std::mem::replace(&mut self.trace, Vec::with_capacity(self.capacity)),
        }
    }

    /// Keeps `(t, f)` if the trace's interval has passed since its last
    /// point; decimates a full trace first.
    fn record(&mut self, t: f64, f: f64) {
        if let Some(last) = self.trace.last() {
            if t - last[0] < self.interval - 1e-9 {
                return;
            }
        }
        self.push_point(t, f);
    }

    /// Keeps the press's last point whatever the interval (its end).
    fn record_last(&mut self, t: f64, f: f64) {
        if self
            .trace
            .last()
            .is_some_and(|l| t - l[0] < self.interval - 1e-9)
        {
            self.trace.pop();
        }
        self.push_point(t, f);
    }

    fn push_point(&mut self, t: f64, f: f64) {
        if self.trace.len() == self.capacity {
            // Halve in place: keep the even points, double the interval.
            let n = self.trace.len();
            for i in 0..n.div_ceil(2) {
                self.trace[i] = self.trace[2 * i];
            }
            self.trace.truncate(n.div_ceil(2));
            self.interval *= 2.0;
        }
        self.trace.push([t, f]);
    }
}

fn check(x: &ExamSample) -> Result<(), DetectorError> {
    let bad = |field, value, reason| {
        Err(DetectorError::Bad {
            t: x.t,
            field,
            value,
            reason,
        })
    };
    if !x.t.is_finite() {
        return bad("t", x.t, "must be finite");
    }
    if !(x.force.is_finite() && x.force >= 0.0) {
        return bad("force", x.force, "must be finite and >= 0 N");
    }
    for (field, v) in [("skin[0]", x.skin[0]), ("skin[1]", x.skin[1]), ("s", x.s)] {
        if !v.is_finite() {
            return bad(field, v, "must be finite");
        }
    }
    for (field, v) in [
        ("vein_ratio", x.vein_ratio),
        ("artery_ratio", x.artery_ratio),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return bad(field, v, "must be finite and >= 0");
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "detector_tests.rs"]
mod tests;
