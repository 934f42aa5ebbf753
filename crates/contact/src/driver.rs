//! One physics step of the probe on the thigh, and the queries the haptic
//! side needs (paper §2: the physical model "receives the actual position of
//! the virtual echographic probe ... computes and returns the minimum
//! distance ... the partial derivatives of this distance ... a linear
//! approximation of the local stiffness. Finally it updates its own dynamic
//! state").
//!
//! [`ProbeContact::step`] reads as its stages: pose the probe, broad phase,
//! implicit step with the penalty contact (Eq. 1 + Eq. 2), then the queries
//! at the new state: contact wrench, stiffness (Schur complement), distance.
//!
//! **Distance sent to the haptic side** (`DESIGN.md` §2). Out of contact, `D`
//! is the signed distance from `p` to the deformed surface and `∇D` the unit
//! vector from the closest surface point to `p`. In contact the surface
//! follows the probe, so the geometric distance says nothing; we send
//! `D = −|F·n|/k` with `n = −k̂` and `∇D = n`: the buffer model's first-order
//! force `k·(−D)` then equals the physics' contact force at the sample.
//!
//! **Stiffness out of contact.** `k` is the stiffness the probe would meet at
//! first touch, if it went on along `k̂`: the Schur complement with the face
//! samples whose surface lies within `first_contact_band` of the highest
//! one (the first to be touched), each with its penalty stiffness `λ_c a`.
//! It is recomputed every step (one solve, as in contact). If no surface
//! lies under the face (the probe beside the thigh), the last value is kept.
//!
//! **Query path** (issue 18, [`QueryPath`]). By default the stiffness takes
//! `T w` from its solve's matrix, the signed distance is queried only when
//! it is sent (out of contact, or in contact with no usable `k`), and the
//! broad-phase grid is kept up to date in place; [`QueryPath::Reference`]
//! keeps the previous implementation for same-run comparisons and tests.
//! Both send the same samples but for `k` (and `D = −|F·n|/k`), which agree
//! within the solver's bound (see [`crate::stiffness`]).

use crate::error::ConfigError;
use crate::params::ContactParams;
use crate::penalty::{PenaltyContact, Wrench};
use crate::probe::Probe;
use crate::stiffness::{ContactSet, ContactSpring, LocalStiffness};
use crate::surface::SurfaceDistance;
use echothigh_model::timings::seconds_since;
use echothigh_model::{SolveStats, StepStats, StepTimings, ThighModel, Vec3};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What the physics sends the haptic side after each step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HapticSample {
    /// Probe reference point `p` (face centre), m, thigh frame.
    pub p: Vec3,
    /// `D`, m: signed distance to the surface (> 0 outside) out of contact,
    /// `−|F·n|/k` in contact.
    pub distance: f64,
    /// `∇D` with respect to `p`, unit.
    pub gradient: Vec3,
    /// Local stiffness `k = −∂(F·n)/∂depth`, N/m, quasi-static.
    pub stiffness: f64,
    /// Net contact force on the probe, N.
    pub force: Vec3,
    /// Net contact torque on the probe about `p`, N·m.
    pub torque: Vec3,
    /// True if the tissue presses on the probe.
    pub in_contact: bool,
}

/// Cost and outcome of the queries of one sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct QueryStats {
    /// Face samples pressing on the tissue.
    pub contact_samples: usize,
    /// Springs in the Schur complement (actual or first-touch contact).
    pub stiffness_springs: usize,
    /// The extra solve of the stiffness.
    pub stiffness_solve: SolveStats,
    /// True if that solve's warm start passed the stop test matrix-free
    /// and nothing was assembled
    /// ([`ThighModel::solve_stiffness_with_product`]).
    #[serde(default)]
    pub stiffness_unassembled: bool,
    /// True if the distance came from the surface query (out of contact).
    pub geometric_distance: bool,
    /// Time of the queries' stages (s): `broad_phase` (their own),
    /// `stiffness_solve`, `distance_query`.
    pub timings: StepTimings,
}

/// Which implementation [`ProbeContact`]'s queries run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QueryPath {
    /// `T w` through the stiffness solve's matrix, the signed distance only
    /// when it is sent, the broad-phase grid kept up to date in place.
    #[default]
    Fast,
    /// The implementation before issue 18: matrix-free `T w`, the signed
    /// distance at every sample, the grid rebuilt from scratch each time.
    Reference,
}

/// The outcome of [`ProbeContact::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactStep {
    /// The sample for the haptic side.
    pub sample: HapticSample,
    /// The implicit step's statistics.
    pub physics: StepStats,
    /// The queries' statistics.
    pub query: QueryStats,
}

/// Bundles the penalty contact, the distance and stiffness queries, and
/// their scratch, for a given model. Allocation-free after construction.
#[derive(Debug, Clone)]
pub struct ProbeContact {
    contact: PenaltyContact,
    surface: SurfaceDistance,
    stiffness: LocalStiffness,
    set: ContactSet,
    last_pose: Option<Isometry3<f64>>,
    first_touch_k: f64,
    path: QueryPath,
}

impl ProbeContact {
    /// Contact of `probe` with `model`'s surface; validates the parameters
    /// (errors name `probe.*` and `contact.*`).
    pub fn new(
        model: &ThighModel,
        probe: Probe,
        params: ContactParams,
    ) -> Result<Self, ConfigError> {
        probe.validate("probe")?;
        params.validate("contact")?;
        let mesh = model.mesh();
        let n = model.node_count();
        Ok(Self {
            contact: PenaltyContact::new(model, probe, params),
            surface: SurfaceDistance::new(
                mesh.rest_positions(),
                mesh.rest_normals(),
                mesh.triangles(),
            ),
            stiffness: LocalStiffness::new(model),
            set: ContactSet::with_capacity(n),
            last_pose: None,
            first_touch_k: 0.0,
            path: QueryPath::Fast,
        })
    }

    /// Chooses the implementation of the queries ([`QueryPath::Fast`]
    /// unless set). No allocation.
    pub fn set_query_path(&mut self, path: QueryPath) {
        self.path = path;
        let reference = path == QueryPath::Reference;
        self.contact.set_incremental_grid(!reference);
        self.stiffness.set_matrix_free(reference);
    }

    /// The implementation of the queries.
    pub fn query_path(&self) -> QueryPath {
        self.path
    }

    /// The springs of the last stiffness query (actual or first-touch
    /// contact; empty if there was none).
    pub fn stiffness_set(&self) -> &ContactSet {
        &self.set
    }

    /// The Schur-complement solver's scratch (its last `w` warm-starts the
    /// next query).
    pub fn local_stiffness(&self) -> &LocalStiffness {
        &self.stiffness
    }

    /// The penalty contact (Eq. 2).
    pub fn contact(&self) -> &PenaltyContact {
        &self.contact
    }

    /// The penalty contact, mutable (e.g. to change `λ_c`).
    pub fn contact_mut(&mut self) -> &mut PenaltyContact {
        &mut self.contact
    }

    /// The probe displacement along `k̂` (m) from `pose` to first touch: the
    /// distance, along the face normal, from the face to the highest surface
    /// point under it (negative if the surface already penetrates). `None`
    /// if no surface lies under the face within `reach` (m).
    pub fn gap_along_normal(
        &mut self,
        model: &ThighModel,
        pose: &Isometry3<f64>,
        reach: f64,
    ) -> Option<f64> {
        let saved = (*self.contact.pose(), self.last_pose);
        self.contact.set_probe(*pose, Vec3::zeros());
        self.contact
            .prepare_with_reach(model.positions(), model.velocities(), 0.0, reach);
        let top = self
            .contact
            .sample_surfaces()
            .iter()
            .flatten()
            .map(|s| s.height)
            .fold(f64::NEG_INFINITY, f64::max);
        self.contact.set_probe(saved.0, Vec3::zeros());
        self.last_pose = saved.1;
        top.is_finite().then_some(-top)
    }

    /// Forgets the previous pose (the next step sees a probe at rest).
    pub fn reset(&mut self) {
        self.last_pose = None;
    }

    /// One physics step of `h` (s) with the probe at `pose` at the step's
    /// end (backward Euler evaluates the contact there); the probe's velocity
    /// is the pose change over `h`. Allocation-free.
    pub fn step(&mut self, model: &mut ThighModel, pose: &Isometry3<f64>, h: f64) -> ContactStep {
        let (mut physics, _) = self.advance(model, pose, h);
        let (sample, query) = self.sample(model);
        physics.timings.accumulate(&query.timings);
        ContactStep {
            sample,
            physics,
            query,
        }
    }

    /// One physics step of `h` (s) with the probe at `pose`, without the
    /// haptic queries: returns the step's statistics and the contact wrench
    /// at the step's end (the force the step applied). Allocation-free.
    pub fn advance(
        &mut self,
        model: &mut ThighModel,
        pose: &Isometry3<f64>,
        h: f64,
    ) -> (StepStats, Wrench) {
        let p = Probe::reference_point(pose);
        // The active window (if configured) follows the probe.
        model.set_focus(&p);
        let velocity = match self.last_pose {
            Some(prev) if h > 0.0 => (p - Probe::reference_point(&prev)) / h,
            _ => Vec3::zeros(),
        };
        self.last_pose = Some(*pose);
        self.contact.set_probe(*pose, velocity);
        let clock = Instant::now();
        self.contact
            .prepare(model.positions(), model.velocities(), h);
        let broad_phase = seconds_since(clock);
        let mut stats = model.step(h, &mut self.contact);
        stats.timings.broad_phase += broad_phase;
        (
            stats,
            self.contact.wrench(model.positions(), model.velocities()),
        )
    }

    /// The contact wrench on the probe (N, N·m; the penalty contact of the
    /// paper's Eq. 2) at the model's current state, the
    /// broad phase rebuilt on the current positions: the force and torque
    /// [`Self::sample`] reports, without its queries (the `direct`
    /// coupling's real-time tick renders only this). [`Self::advance`]'s
    /// own wrench differs from it by the face samples' surfaces, found there
    /// at the step's start (relative 1e-5 at contact onset). Allocation-free.
    pub fn wrench_now(&mut self, model: &ThighModel) -> Wrench {
        self.contact
            .prepare(model.positions(), model.velocities(), 0.0);
        self.contact.wrench(model.positions(), model.velocities())
    }

    /// Steps with the probe held still at `pose` until every node is slower
    /// than `speed_tol` (m/s) or `max_steps` steps of `h` (s) were taken: the
    /// quasi-static equilibrium. Returns the steps taken and the last step.
    pub fn settle(
        &mut self,
        model: &mut ThighModel,
        pose: &Isometry3<f64>,
        h: f64,
        max_steps: usize,
        speed_tol: f64,
    ) -> (usize, ContactStep) {
        let mut last = None;
        let mut taken = 0;
        for _ in 0..max_steps.max(1) {
            self.last_pose = Some(*pose);
            let s = self.step(model, pose, h);
            taken += 1;
            last = Some(s);
            let vmax = model
                .velocities()
                .iter()
                .map(|v| v.norm())
                .fold(0.0, f64::max);
            if !s.physics.finite || vmax < speed_tol {
                break;
            }
        }
        (taken, last.expect("at least one step"))
    }

    /// The queries at the model's current state and the current probe pose:
    /// wrench, local stiffness, distance and gradient. Rebuilds the broad
    /// phase on the current positions. Allocation-free.
    pub fn sample(&mut self, model: &mut ThighModel) -> (HapticSample, QueryStats) {
        let pose = *self.contact.pose();
        let p = Probe::reference_point(&pose);
        let k_dir = Probe::contact_direction(&pose);
        // Out of contact the distance comes before the stiffness: it bounds
        // how far below the face the first-touch surface can be.
        let mut timings = StepTimings::default();
        let clock = Instant::now();
        self.contact
            .prepare(model.positions(), model.velocities(), 0.0);
        timings.broad_phase += seconds_since(clock);
        let (x, v) = (model.positions(), model.velocities());
        let wrench: Wrench = self.contact.wrench(x, v);
        let in_contact = wrench.samples > 0;
        // In contact the distance sent is −|F·n|/k: the surface query is
        // needed only if k turns out unusable (below).
        let mut surface = None;
        if !in_contact || self.path == QueryPath::Reference {
            let clock = Instant::now();
            surface = self.surface.query(self.contact.grid(), x, &p);
            timings.distance_query += seconds_since(clock);
        }
        let mut query = QueryStats {
            contact_samples: wrench.samples,
            ..QueryStats::default()
        };
        let lambda = self.contact.params().stiffness;
        let (_, area) = self.contact.samples();
        self.set.reset(k_dir);
        if in_contact {
            let (set, contact) = (&mut self.set, &self.contact);
            contact.for_each_contact(x, v, |s, _| {
                set.springs.push(ContactSpring {
                    nodes: s.nodes,
                    beta: s.beta,
                    blocks: *contact.triangle_blocks(s.triangle),
                    c: lambda * area,
                })
            });
        } else {
            let reach = surface.map(|s| s.distance.abs()).unwrap_or(0.0);
            // Room for a tilted face: its far corner may be lower than p.
            let below = 2.0 * reach + self.contact.params().first_contact_band;
            let clock = Instant::now();
            self.contact.prepare_with_reach(x, v, 0.0, below);
            timings.broad_phase += seconds_since(clock);
            let band = self.contact.params().first_contact_band;
            let surfaces = self.contact.sample_surfaces();
            let top = surfaces
                .iter()
                .flatten()
                .map(|s| s.height)
                .fold(f64::NEG_INFINITY, f64::max);
            for s in surfaces.iter().flatten().filter(|s| s.height >= top - band) {
                self.set.springs.push(ContactSpring {
                    nodes: s.nodes,
                    beta: s.beta,
                    blocks: *self.contact.triangle_blocks(s.triangle),
                    c: lambda * area,
                });
            }
        }
        query.stiffness_springs = self.set.springs.len();
        let mut k = if self.set.springs.is_empty() {
            0.0
        } else {
            let clock = Instant::now();
            let (k, stats) = self.stiffness.compute(model, &mut self.set);
            timings.stiffness_solve += seconds_since(clock);
            query.stiffness_solve = stats;
            query.stiffness_unassembled = model.stiffness_unassembled();
            k
        };
        if !in_contact {
            if k > 0.0 && k.is_finite() {
                self.first_touch_k = k;
            } else {
                k = self.first_touch_k;
            }
        }
        let normal_force = -wrench.force.dot(&k_dir); // F·n, n = −k̂, ≥ 0
        let usable_k = in_contact && k > 0.0 && k.is_finite();
        if in_contact && !usable_k && self.path == QueryPath::Fast {
            let clock = Instant::now();
            surface = self
                .surface
                .query(self.contact.grid(), model.positions(), &p);
            timings.distance_query += seconds_since(clock);
        }
        let (distance, gradient) = match (usable_k, surface) {
            (true, _) => (-normal_force / k, -k_dir),
            (false, Some(s)) => {
                query.geometric_distance = true;
                (s.distance, s.gradient)
            }
            (false, None) => (f64::INFINITY, -k_dir),
        };
        query.timings = timings;
        let sample = HapticSample {
            p,
            distance,
            gradient,
            stiffness: k,
            force: wrench.force,
            torque: wrench.torque,
            in_contact,
        };
        (sample, query)
    }
}
