//! Force shading across model updates: when a new buffer model arrives the
//! rendered constraint is blended from the one displayed at that instant to
//! the new one over one physics period, so the force's direction and
//! magnitude do not jump (DESIGN §3; the 100 Hz steps of the paper's Fig. 4
//! become ramps).

use crate::local_model::ModelParams;

/// A blend in progress (or finished) between two `(u, k)` pairs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shading {
    from: (ModelParams, f64),
    to: (ModelParams, f64),
    start: f64,
    duration: f64,
}

impl Shading {
    /// A finished blend showing `(params, k)` (k in N/m).
    pub fn settled(params: ModelParams, stiffness: f64) -> Self {
        Shading {
            from: (params, stiffness),
            to: (params, stiffness),
            start: f64::NEG_INFINITY,
            duration: 0.0,
        }
    }

    /// Starts blending from what is displayed at `now` (s) to `(params, k)`
    /// over `duration` (s; ≤ 0 switches at once).
    pub fn retarget(&mut self, params: ModelParams, stiffness: f64, now: f64, duration: f64) {
        let (u, k, _) = self.at(now);
        *self = Shading {
            from: (u, k),
            to: (params, stiffness),
            start: now,
            duration,
        };
    }

    /// Blend fraction α ∈ [0, 1] at time `now` (s).
    pub fn alpha(&self, now: f64) -> f64 {
        if self.duration <= 0.0 {
            return 1.0;
        }
        ((now - self.start) / self.duration).clamp(0.0, 1.0)
    }

    /// The displayed `(u, k, α)` at time `now` (s): linear in the parameters
    /// and in `k`.
    pub fn at(&self, now: f64) -> (ModelParams, f64, f64) {
        let a = self.alpha(now);
        if a >= 1.0 {
            return (self.to.0, self.to.1, 1.0);
        }
        let u = self.from.0.blend(&self.to.0, a);
        let k = self.from.1 + (self.to.1 - self.from.1) * a;
        (u, k, a)
    }
}
