//! Manoeuvres in time: calf squeezes, a Valsalva strain, the release of a
//! probe compression; each a timed event whose effect on venous flow is a
//! time course (shapes and numbers in [`crate::physiology`]).
//!
//! At most [`MAX_EVENTS`] events are kept (the oldest is dropped): a
//! fixed array, so updating and evaluating allocate nothing.

use crate::physiology::FlowConfig;
use serde::{Deserialize, Serialize};

/// Largest number of events a [`Maneuvers`] keeps.
pub const MAX_EVENTS: usize = 16;

/// What the examiner does during a recording (`--maneuver`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Maneuver {
    /// Quiet breathing.
    #[default]
    None,
    /// A calf squeeze (distal augmentation).
    Augment,
    /// A Valsalva strain.
    Valsalva,
}

/// One timed event.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Event {
    /// Calf squeeze at `t` (s).
    Squeeze(f64),
    /// Valsalva strain from `start` to `end` (s).
    Valsalva(f64, f64),
    /// A probe compression released at `t` (s).
    Release(f64),
}

/// The events of a recording or a live session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Maneuvers {
    events: [Option<Event>; MAX_EVENTS],
    next: usize,
}

impl Default for Maneuvers {
    fn default() -> Self {
        Maneuvers {
            events: [None; MAX_EVENTS],
            next: 0,
        }
    }
}

/// Gamma-variate pulse `(x) e^{1 − x}`, `x = t/τ`: 0 at 0, 1 at `τ`.
fn pulse(t: f64, tau: f64) -> f64 {
    if t <= 0.0 {
        0.0
    } else {
        let x = t / tau;
        x * (1.0 - x).exp()
    }
}

impl Maneuvers {
    /// No events.
    pub fn new() -> Self {
        Self::default()
    }

    /// The standard timeline of `m` in a recording: a squeeze at `t0`, or a
    /// Valsalva strain from `t0` lasting `hold` s.
    pub fn scripted(m: Maneuver, t0: f64, hold: f64) -> Self {
        let mut s = Self::new();
        match m {
            Maneuver::None => {}
            Maneuver::Augment => s.squeeze(t0),
            Maneuver::Valsalva => s.valsalva(t0, t0 + hold),
        }
        s
    }

    fn push(&mut self, e: Event) {
        self.events[self.next % MAX_EVENTS] = Some(e);
        self.next = self.next.wrapping_add(1);
    }

    /// A calf squeeze at `t` (s).
    pub fn squeeze(&mut self, t: f64) {
        self.push(Event::Squeeze(t));
    }

    /// A Valsalva strain from `start` to `end` (s).
    pub fn valsalva(&mut self, start: f64, end: f64) {
        self.push(Event::Valsalva(start, end.max(start)));
    }

    /// A held Valsalva strain begun at `start` (s), open until
    /// [`Maneuvers::end_valsalva`] (the live viewer's "hold" control).
    pub fn begin_valsalva(&mut self, start: f64) {
        self.push(Event::Valsalva(start, f64::INFINITY));
    }

    /// Ends every open strain at `t` (s) (one that began after `t` ends
    /// where it began). Returns whether one was open.
    pub fn end_valsalva(&mut self, t: f64) -> bool {
        let mut open = false;
        for e in self.events.iter_mut().flatten() {
            if let Event::Valsalva(t0, t1) = e {
                if t1.is_infinite() {
                    *t1 = t.max(*t0);
                    open = true;
                }
            }
        }
        open
    }

    /// Whether a strain is held open ([`Maneuvers::begin_valsalva`]).
    pub fn valsalva_held(&self) -> bool {
        self.events
            .iter()
            .flatten()
            .any(|e| matches!(e, Event::Valsalva(_, t1) if t1.is_infinite()))
    }

    /// A probe compression released at `t` (s): a brief augmentation.
    pub fn release(&mut self, t: f64) {
        self.push(Event::Release(t));
    }

    /// The strongest augmentation at `t`: `(γ, F)` with `γ` in [0, 1] the
    /// pulse's weight and `F` its peak relative to the resting peak
    /// velocity; the velocity is `base + (F·peak − base)·γ`.
    pub fn augmentation(&self, cfg: &FlowConfig, t: f64) -> (f64, f64) {
        let tau = cfg.augmentation_rise;
        let mut best = (0.0, 1.0);
        for e in self.events.iter().flatten() {
            let (g, f) = match *e {
                Event::Squeeze(t0) => (pulse(t - t0, tau), cfg.augmentation_factor),
                Event::Release(t0) => (pulse(t - t0, tau), cfg.release_factor),
                Event::Valsalva(_, t1) => (pulse(t - t1, tau), cfg.valsalva_release_factor),
            };
            if g * f > best.0 * best.1 {
                best = (g, f);
            }
        }
        best
    }

    /// Fraction of resting flow a Valsalva strain lets through at `t`: 1
    /// without strain, `exp(−(t − start)/τ)` during it, recovering as
    /// `1 − (1 − b₁) exp(−(t − end)/τ)` after it.
    pub fn valsalva_flow(&self, cfg: &FlowConfig, t: f64) -> f64 {
        let tau = cfg.valsalva_time_constant;
        let mut f = 1.0f64;
        for e in self.events.iter().flatten() {
            if let Event::Valsalva(t0, t1) = *e {
                let b = if t < t0 {
                    1.0
                } else if t < t1 {
                    (-(t - t0) / tau).exp()
                } else {
                    let b1 = (-(t1 - t0) / tau).exp();
                    1.0 - (1.0 - b1) * (-(t - t1) / tau).exp()
                };
                f = f.min(b);
            }
        }
        f
    }

    /// Fraction (0 to 1) of the full Valsalva distension at `t` (the venous
    /// pressure follows the strain with the same time constant).
    pub fn valsalva_strain(&self, cfg: &FlowConfig, t: f64) -> f64 {
        1.0 - self.valsalva_flow(cfg, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gamma-variate pulse peaks at exactly 1 at `τ` (its derivative
    /// `(1 − x) e^{1−x}/τ` vanishes there) and is 5 e^{−4} ≈ 0.092 at 5τ.
    #[test]
    fn pulse_peak_and_decay() {
        assert!((pulse(0.3, 0.3) - 1.0).abs() < 1e-12);
        assert!(pulse(0.29, 0.3) < 1.0 && pulse(0.31, 0.3) < 1.0);
        assert!((pulse(1.5, 0.3) - 5.0 * (-4.0f64).exp()).abs() < 1e-12);
        assert_eq!(pulse(-1.0, 0.3), 0.0);
    }

    /// Valsalva: full flow before, `e^{-1}` one time constant into the
    /// strain, continuous at release, back towards 1 after.
    #[test]
    fn valsalva_time_course() {
        let cfg = FlowConfig::default();
        let m = Maneuvers::scripted(Maneuver::Valsalva, 1.0, 3.0);
        assert_eq!(m.valsalva_flow(&cfg, 0.5), 1.0);
        let tau = cfg.valsalva_time_constant;
        assert!((m.valsalva_flow(&cfg, 1.0 + tau) - (-1.0f64).exp()).abs() < 1e-12);
        let before = m.valsalva_flow(&cfg, 4.0 - 1e-9);
        let after = m.valsalva_flow(&cfg, 4.0 + 1e-9);
        assert!((before - after).abs() < 1e-6);
        assert!(m.valsalva_flow(&cfg, 10.0) > 0.999);
    }

    /// A held strain is the scripted one of the same length: the same
    /// flow before, during and after its end, to the last bit (the open
    /// end only changes which branch is taken before `end_valsalva`).
    #[test]
    fn a_held_valsalva_equals_the_scripted_one() {
        let cfg = FlowConfig::default();
        let scripted = Maneuvers::scripted(Maneuver::Valsalva, 1.0, 2.5);
        let mut held = Maneuvers::new();
        held.begin_valsalva(1.0);
        assert!(held.valsalva_held());
        for t in [0.5, 1.2, 3.0] {
            assert_eq!(held.valsalva_flow(&cfg, t), scripted.valsalva_flow(&cfg, t));
        }
        assert!(held.end_valsalva(3.5));
        assert!(!held.valsalva_held());
        assert!(!held.end_valsalva(4.0), "nothing left open");
        for t in [0.5, 1.2, 3.0, 3.6, 5.0] {
            assert_eq!(held.valsalva_flow(&cfg, t), scripted.valsalva_flow(&cfg, t));
            assert_eq!(
                held.augmentation(&cfg, t),
                scripted.augmentation(&cfg, t),
                "t = {t}"
            );
        }
    }
}
