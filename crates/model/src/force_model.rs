//! The seam through which force models enter the implicit system (SOFA's
//! habit): each answers its force and its Jacobians, so the integrator never
//! special-cases a spring type. Contact implements it.

use crate::block_sparse::BlockSparse;
use crate::edge_matrix::EdgeMatrix;
use crate::timings::{seconds_since, StepTimings};
use crate::Vec3;
use std::time::Instant;

/// A force on the mesh nodes and its Jacobians.
///
/// Methods take `&mut self` so a model can refresh internal state (e.g.
/// contact detection) at every Newton iterate. Each is called with the same
/// `x` (m) and `v` (m/s) of one iterate: `add_forces` first, then, if the
/// iterate needs a linear solve, `add_jacobians`.
pub trait ForceModel {
    /// Adds this model's force on every node (N) into `f` (`f.len() == x.len()`).
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]);

    /// Adds `∂F/∂x` (N/m) into `k` and `∂F/∂v` (N·s/m) into `b`; only blocks
    /// of the fixed pattern (the diagonal and the mesh edges) may be written.
    fn add_jacobians(&mut self, x: &[Vec3], v: &[Vec3], k: &mut BlockSparse, b: &mut BlockSparse);

    /// Adds `α ∂F/∂x + β ∂F/∂v` into `a` (the implicit integrator's
    /// combination, e.g. `α = −λ²h²`, `β = −λh`; units those of `α·N/m`).
    ///
    /// The default assembles into `scratch` (cleared here) with
    /// [`Self::add_jacobians`] and accumulates the whole pattern into `a`; a
    /// model that touches few blocks should override it and write `a`
    /// directly (it is called once per Newton iteration).
    fn add_scaled_jacobians(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut BlockSparse,
        scratch: &mut JacobianScratch,
    ) {
        scratch.k.clear();
        scratch.b.clear();
        self.add_jacobians(x, v, &mut scratch.k, &mut scratch.b);
        a.add_scaled(alpha, &scratch.k, beta, &scratch.b);
    }

    /// Adds `α ∂F/∂x + β ∂F/∂v` into the edge-form matrix `a` (the model's
    /// system, issue 18): springs as [`EdgeMatrix::add_spring`], node blocks
    /// as [`EdgeMatrix::add_diagonal`], a contact sample as
    /// [`EdgeMatrix::add_rank_one`]. The default runs
    /// [`Self::add_scaled_jacobians`] into `a`'s block-sparse side matrix:
    /// exact for any model, but it costs a pass over the whole pattern, so
    /// the models of the step override it.
    fn add_scaled_jacobians_edge(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut EdgeMatrix,
        scratch: &mut JacobianScratch,
    ) {
        self.add_scaled_jacobians(x, v, alpha, beta, a.side_mut(), scratch);
    }

    /// Largest fraction `α ∈ [0, 1]` of the position change `dx` (m) from `x`
    /// that keeps this model in its valid domain along the whole path
    /// `x + s·dx, s ∈ [0, α]` (e.g. below a spring's asymptote). Default 1.
    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        let _ = (x, dx);
        1.0
    }

    /// Adds `α (∂F/∂x) w` into `out` (N for `α` = 1 and `w` in m) at `x`
    /// without assembling anything, `∂F/∂x` being the Jacobian that
    /// [`Self::add_scaled_jacobians_edge`] assembles with `β = 0`, and
    /// returns true. The default cannot (returns false, `out` untouched):
    /// a caller must then assemble. Used to test a warm start of the
    /// stiffness solve before paying for an assembly
    /// ([`crate::ThighModel::solve_stiffness_with_product`]).
    fn add_jacobian_product(
        &mut self,
        x: &[Vec3],
        alpha: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) -> bool {
        let _ = (x, alpha, w, out);
        false
    }
}

/// Scratch matrices for [`ForceModel::add_scaled_jacobians`]'s default.
#[derive(Debug, Clone)]
pub struct JacobianScratch {
    /// `∂F/∂x` (N/m).
    pub k: BlockSparse,
    /// `∂F/∂v` (N·s/m).
    pub b: BlockSparse,
}

impl JacobianScratch {
    /// Zeroed matrices of `pattern`'s pattern.
    pub fn new(pattern: &BlockSparse) -> Self {
        let mut k = pattern.clone();
        k.clear();
        JacobianScratch { b: k.clone(), k }
    }
}

/// No extra force: the tissue alone.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoExtraForce;

impl ForceModel for NoExtraForce {
    fn add_forces(&mut self, _x: &[Vec3], _v: &[Vec3], _f: &mut [Vec3]) {}
    fn add_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        _k: &mut BlockSparse,
        _b: &mut BlockSparse,
    ) {
    }

    fn add_scaled_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        _alpha: f64,
        _beta: f64,
        _a: &mut BlockSparse,
        _scratch: &mut JacobianScratch,
    ) {
    }

    fn add_scaled_jacobians_edge(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        _alpha: f64,
        _beta: f64,
        _a: &mut EdgeMatrix,
        _scratch: &mut JacobianScratch,
    ) {
    }

    fn add_jacobian_product(
        &mut self,
        _x: &[Vec3],
        _a: f64,
        _w: &[Vec3],
        _out: &mut [Vec3],
    ) -> bool {
        true
    }
}

/// The sum of two force models (e.g. tissue + contact). The time spent in
/// `second` is kept apart in [`Self::second_timings`] (its `forces`,
/// `assembly` and `step_fraction`), so that a step can report the contact's
/// share as a stage of its own.
pub struct SumForce<'a> {
    /// First model.
    pub first: &'a mut dyn ForceModel,
    /// Second model.
    pub second: &'a mut dyn ForceModel,
    /// Seconds spent in `second`'s methods, accumulated by stage.
    pub second_timings: StepTimings,
}

impl<'a> SumForce<'a> {
    /// `first + second`, timers at zero.
    pub fn new(first: &'a mut dyn ForceModel, second: &'a mut dyn ForceModel) -> Self {
        SumForce {
            first,
            second,
            second_timings: StepTimings::default(),
        }
    }
}

impl ForceModel for SumForce<'_> {
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        self.first.add_forces(x, v, f);
        let clock = Instant::now();
        self.second.add_forces(x, v, f);
        self.second_timings.forces += seconds_since(clock);
    }

    fn add_jacobians(&mut self, x: &[Vec3], v: &[Vec3], k: &mut BlockSparse, b: &mut BlockSparse) {
        self.first.add_jacobians(x, v, k, b);
        self.second.add_jacobians(x, v, k, b);
    }

    fn add_scaled_jacobians(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut BlockSparse,
        scratch: &mut JacobianScratch,
    ) {
        self.first
            .add_scaled_jacobians(x, v, alpha, beta, a, scratch);
        let clock = Instant::now();
        self.second
            .add_scaled_jacobians(x, v, alpha, beta, a, scratch);
        self.second_timings.assembly += seconds_since(clock);
    }

    fn add_scaled_jacobians_edge(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut EdgeMatrix,
        scratch: &mut JacobianScratch,
    ) {
        self.first
            .add_scaled_jacobians_edge(x, v, alpha, beta, a, scratch);
        let clock = Instant::now();
        self.second
            .add_scaled_jacobians_edge(x, v, alpha, beta, a, scratch);
        self.second_timings.assembly += seconds_since(clock);
    }

    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        self.first
            .max_step_fraction(x, dx)
            .min(self.second.max_step_fraction(x, dx))
    }

    /// True only if both models can (`out` then holds both products); on
    /// false `out` may hold the first model's part: the caller discards it
    /// (as [`crate::ThighModel::solve_stiffness_with_product`] does).
    fn add_jacobian_product(
        &mut self,
        x: &[Vec3],
        alpha: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) -> bool {
        self.first.add_jacobian_product(x, alpha, w, out)
            && self.second.add_jacobian_product(x, alpha, w, out)
    }
}
