//! Per-stage timers of the physics step (rapier's counters, SOFA's scoped
//! timers): plain data, filled by the integrator and the contact driver,
//! returned with the step's statistics. Monotonic wall-clock time
//! (`std::time::Instant`, a vDSO read on Linux: no system call, no
//! allocation), in seconds: on a loaded machine it includes time the thread
//! waited for a core, so benchmarks report the thread's CPU time of the
//! whole step beside these.

use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Seconds spent in each stage of one physics step (0 for a stage not run).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StepTimings {
    /// Contact broad and narrow phase (grid rebuild, surface under the
    /// probe's face samples), s.
    pub broad_phase: f64,
    /// Force evaluations of the Newton iterations (tissue forces and
    /// residuals; the contact's share is in [`Self::contact`]), s.
    pub forces: f64,
    /// Newton matrix assembly `M − λhB − λ²h²K` (tissue; the contact's
    /// share is in [`Self::contact`]), s.
    pub assembly: f64,
    /// Preconditioned conjugate gradient of the Newton solves (with the
    /// preconditioner's set-up), s.
    pub pcg: f64,
    /// Local stiffness query: its assembly, solve and `K w`, s.
    pub stiffness_solve: f64,
    /// Distance query (closest surface point to the probe), s.
    pub distance_query: f64,
    /// The asymptote limiter: the largest step fraction that keeps the
    /// force models in their domain (start and Newton updates), s.
    pub step_fraction: f64,
    /// The extra force model's (the probe contact's) forces and Jacobians
    /// during the Newton iterations, s.
    pub contact: f64,
    /// The active window's own work (issue 18, [`crate::window`]): finding
    /// the probe's node, re-centring, and the patch's state gathered from
    /// and written back to the mesh, s.
    #[serde(default)]
    pub window: f64,
}

impl StepTimings {
    /// Field names, in the order of [`Self::values`] (e.g. CSV columns).
    pub const NAMES: [&'static str; 9] = [
        "broad_phase",
        "forces",
        "assembly",
        "pcg",
        "stiffness_solve",
        "distance_query",
        "step_fraction",
        "contact",
        "window",
    ];

    /// The stage times in the order of [`Self::NAMES`], s.
    pub fn values(&self) -> [f64; 9] {
        [
            self.broad_phase,
            self.forces,
            self.assembly,
            self.pcg,
            self.stiffness_solve,
            self.distance_query,
            self.step_fraction,
            self.contact,
            self.window,
        ]
    }

    /// Sum of the stages, s.
    pub fn total(&self) -> f64 {
        self.values().iter().sum()
    }

    /// Adds `other`'s stages to these.
    pub fn accumulate(&mut self, other: &StepTimings) {
        self.broad_phase += other.broad_phase;
        self.forces += other.forces;
        self.assembly += other.assembly;
        self.pcg += other.pcg;
        self.stiffness_solve += other.stiffness_solve;
        self.distance_query += other.distance_query;
        self.step_fraction += other.step_fraction;
        self.contact += other.contact;
        self.window += other.window;
    }

    /// Moves an extra force model's share (`extra`: its `forces` and
    /// `assembly`, as [`crate::SumForce::second_timings`] counts them) out
    /// of those stages into [`Self::contact`].
    pub fn move_to_contact(&mut self, extra: &StepTimings) {
        self.forces = (self.forces - extra.forces).max(0.0);
        self.assembly = (self.assembly - extra.assembly).max(0.0);
        self.contact += extra.forces + extra.assembly;
    }
}

/// Seconds since `start` (a stage timer's stop).
#[inline]
pub fn seconds_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64()
}
