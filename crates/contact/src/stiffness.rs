//! The local stiffness sent to the haptic side (paper §2: "a linear
//! approximation of the local stiffness, i.e. rate of change of the force
//! with respect to a change of position in the direction normal to the
//! surface"), quasi-static, by a Schur complement.
//!
//! Let the probe move by `δ` along `k̂` with the tissue at equilibrium. Each
//! face sample `j` in contact is a penalty spring of stiffness
//! `c_j = λ_c a_j` on the surface height `β_jᵀ y` under it; together they
//! form `C = Σ_j c_j (β_j ⊗ k̂)(β_j ⊗ k̂)ᵀ`. With `T = −∂F_tissue/∂x`, the
//! equilibrium of the nodes gives `(T + C) w = C 1`, `w = ∂x/∂δ`, `1` the
//! field equal to `k̂` on the contact nodes (`Σ_m β_jm = 1`). The force on
//! the tissue is `Σ_j c_j (δ − β_jᵀ k̂·x) k̂`, so
//!
//! `k = ∂|F·n|/∂δ = 1ᵀC1 − 1ᵀC(T + C)⁻¹C1 = 1ᵀ C (1 − w)`,
//!
//! the Schur complement of the node block: one extra linear solve
//! ([`ThighModel::solve_stiffness`]). On free nodes `C(1 − w) = T w`, so we
//! evaluate `k = Σ_m k̂·(T w)_m` over the free contact nodes (fixed ones add
//! `k̂·(C(1 − w))_m`): with a stiff `λ_c`, `1 − k̂·w` is a small difference
//! of numbers near 1, while `T w` is of the tissue's own size, so the
//! solver's tolerance is not amplified by `λ_c / (tissue stiffness)`. For one
//! node on one spring of stiffness `s` this is `s c / (s + c)`, the two in
//! series. `n = −k̂` is the outward normal; with `F` the force on the
//! tissue, `k = −∂(F·n)/∂depth`.
//!
//! **`T w` from the solve's own matrix** (issue 18). The solve assembles
//! `A = T + C`; `T w = A w − C w`, and `A w` is one product through the
//! matrix the solve packed (or its start product if the warm start already
//! met the tolerance, [`ThighModel::solve_stiffness_with_product`]), `C w`
//! one pass over the springs: a few µs where the matrix-free `K w` of the
//! tissue re-evaluated every spring (~50 µs on the default mesh). On
//! contact nodes `A w` and `C w` are both ≈ `C 1`: their difference loses
//! `log₁₀(λ_c a / tissue)` ≈ 2 of the 16 digits, far below the solver's.
//!
//! **Warm start without assembly** (issue 18). While the probe holds, the
//! previous `w` usually meets the solver's stop test as it is; the model
//! then checks it with a matrix-free `A w̃` (tissue, then these springs'
//! `C w̃`) and assembles nothing
//! ([`ThighModel::solve_stiffness_with_product`]). That `A w̃` is the same
//! operator at the same state, so `T w = A w − C w` below and the bound
//! that follows are unchanged.
//!
//! **Error bound.** Let `S` zero the fixed nodes, `b = S C 1`, `w*` the exact
//! solution and `w̃` one with residual `r = b − S A S w̃`. On free nodes
//! `C(1 − w̃) = T w̃ + r`, so the evaluated `k(w̃) = Σ_free 1·T w̃ + (fixed
//! terms)` equals `1ᵀC(1 − w̃) − 1ᵀS r`; with `1ᵀC(1 − w̃) − 1ᵀC(1 − w*) =
//! −bᵀ(w̃ − w*) = bᵀ A⁻¹ r = w*ᵀ r` (A symmetric, `A w* = b`):
//!
//! `k(w̃) − k(w*) = (w* − 1)ᵀ S r`, so `|k(w̃) − k(w*)| ≤ |S(w* − 1)| · tol · |b|`
//!
//! whenever PCG stops on `|r| ≤ tol |b|` (`tol` =
//! `integrator.stiffness_tol`). A warm and a cold solve thus agree within
//! `2 tol |b| |S(w* − 1)|`, whatever their starts; the bound is small
//! because `w* ≈ 1` on the contact nodes (the tissue follows the probe).

use echothigh_model::{
    BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, SolveStats, ThighModel, Vec3,
};
use nalgebra::Matrix3;

use crate::penalty::PenaltyContact;

/// One linearized penalty spring: stiffness `c` (N/m) on the surface
/// height `Σ_m β_m k̂·x_m` under a face sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSpring {
    /// Nodes of the triangle under the sample.
    pub nodes: [usize; 3],
    /// Barycentric weights (sum 1).
    pub beta: [f64; 3],
    /// Storage indices of the triangle's 9 blocks in the model's pattern.
    pub blocks: [usize; 9],
    /// Stiffness `c = λ_c a`, N/m.
    pub c: f64,
}

/// A set of contact springs that contributes only its stiffness: the
/// linearized contact used by the Schur complement, either the actual
/// contact or the one the probe would meet at first touch.
#[derive(Debug, Clone)]
pub struct ContactSet {
    /// Contact direction `k̂` (unit).
    pub direction: Vec3,
    /// The springs.
    pub springs: Vec<ContactSpring>,
}

impl ContactSet {
    /// An empty set with room for `n` springs.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            direction: -Vec3::y(),
            springs: Vec::with_capacity(n),
        }
    }

    /// Empties the set (capacity kept) and sets the direction.
    pub fn reset(&mut self, direction: Vec3) {
        self.direction = direction;
        self.springs.clear();
    }

    /// `1ᵀC1 = Σ c`, N/m: the stiffness if the tissue were rigid.
    pub fn rigid_stiffness(&self) -> f64 {
        self.springs.iter().map(|s| s.c).sum()
    }
}

impl ForceModel for ContactSet {
    /// The linearized set has no force of its own at the linearization point.
    fn add_forces(&mut self, _x: &[Vec3], _v: &[Vec3], _f: &mut [Vec3]) {}

    fn add_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        k: &mut BlockSparse,
        _b: &mut BlockSparse,
    ) {
        let kk: Matrix3<f64> = self.direction * self.direction.transpose();
        for s in &self.springs {
            PenaltyContact::add_sample_block(k, &s.blocks, &s.beta, &kk, s.c);
        }
    }

    /// Direct assembly of `α ∂F/∂x` (the set has no damping) into `a`.
    fn add_scaled_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        alpha: f64,
        _beta: f64,
        a: &mut BlockSparse,
        _scratch: &mut JacobianScratch,
    ) {
        let kk: Matrix3<f64> = self.direction * self.direction.transpose();
        for s in &self.springs {
            PenaltyContact::add_sample_block(a, &s.blocks, &s.beta, &kk, alpha * s.c);
        }
    }

    /// `out += α ∂F/∂x w = −α C w`: spring by spring, `−α c s β_m k̂` on
    /// node `m` with `s = Σ_m β_m k̂·w_m` (the rank-one terms assembled
    /// below, applied without assembly).
    fn add_jacobian_product(
        &mut self,
        _x: &[Vec3],
        alpha: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) -> bool {
        let dir = self.direction;
        for s in &self.springs {
            let stretch = LocalStiffness::stretch(s, &dir, w);
            for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                out[m] -= (alpha * s.c * b * stretch) * dir;
            }
        }
        true
    }

    /// Edge-form assembly: each spring is the rank-one term `−α c (β ⊗ k̂)(β ⊗ k̂)ᵀ`.
    fn add_scaled_jacobians_edge(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        alpha: f64,
        _beta: f64,
        a: &mut EdgeMatrix,
        _scratch: &mut JacobianScratch,
    ) {
        for s in &self.springs {
            // Triangle edges are mesh edges: in the side pattern.
            let written = a.add_rank_one(s.nodes, s.beta, &self.direction, -alpha * s.c);
            debug_assert!(written.is_ok());
        }
    }
}

/// Scratch of the Schur-complement stiffness; allocation-free after `new`.
#[derive(Debug, Clone)]
pub struct LocalStiffness {
    rhs: Vec<Vec3>,
    w: Vec<Vec3>,
    tw: Vec<Vec3>,
    matrix_free: bool,
}

impl LocalStiffness {
    /// Scratch for `model`.
    pub fn new(model: &ThighModel) -> Self {
        let n = model.node_count();
        Self {
            rhs: vec![Vec3::zeros(); n],
            w: vec![Vec3::zeros(); n],
            tw: vec![Vec3::zeros(); n],
            matrix_free: false,
        }
    }

    /// Evaluates `T w` with the matrix-free `K w` of the tissue (`true`:
    /// the implementation before issue 18, for same-run comparisons and
    /// tests) instead of through the solve's matrix (`false`, the default).
    /// Both give `k` within the module's bound of the exact one.
    pub fn set_matrix_free(&mut self, on: bool) {
        self.matrix_free = on;
    }

    /// Forgets the previous solution: the next solve starts from `w = 0`.
    pub fn reset(&mut self) {
        self.w.fill(Vec3::zeros());
    }

    /// The quasi-static stiffness `k` (N/m) the probe feels along `k̂` with
    /// the contact springs `set`, at the model's current state, and the
    /// statistics of the extra solve. Zero for an empty set. The previous
    /// solution warm-starts the solve (a non-finite one is dropped for
    /// `w = 0`); the result is within `tol |b| |S(w* − 1)|` of the exact `k`
    /// whatever the start (module docs).
    pub fn compute(&mut self, model: &mut ThighModel, set: &mut ContactSet) -> (f64, SolveStats) {
        if set.springs.is_empty() {
            return (0.0, SolveStats::default());
        }
        let dir = set.direction;
        self.rhs.fill(Vec3::zeros());
        for s in &set.springs {
            for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                self.rhs[m] += (s.c * b) * dir;
            }
        }
        if self.w.iter().any(|w| !w.iter().all(|c| c.is_finite())) {
            self.w.fill(Vec3::zeros());
        }
        let stats = if self.matrix_free {
            let stats = model.solve_stiffness(set, &self.rhs, &mut self.w);
            // tw = K w of the tissue, K = −T.
            model.tissue_stiffness_product(&self.w, &mut self.tw);
            stats
        } else {
            let stats =
                model.solve_stiffness_with_product(set, &self.rhs, &mut self.w, &mut self.tw);
            // tw = A w = (T + C) w; K w = −T w = C w − A w.
            for v in &mut self.tw {
                *v = -*v;
            }
            for s in &set.springs {
                let stretch = Self::stretch(s, &dir, &self.w);
                for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                    self.tw[m] += (s.c * b * stretch) * dir;
                }
            }
            stats
        };
        let fixed = model.fixed();
        let mut k = 0.0;
        // Free contact nodes: T = −K_tissue, so (T w)·k̂ = −(K w)·k̂.
        for (m, r) in self.rhs.iter().enumerate() {
            if !fixed[m] && *r != Vec3::zeros() {
                k -= self.tw[m].dot(&dir);
            }
        }
        // Fixed contact nodes: (C (1 − w))·k̂ directly.
        for s in &set.springs {
            let stretch = Self::stretch(s, &dir, &self.w);
            for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                if fixed[m] {
                    k += s.c * b * (1.0 - stretch);
                }
            }
        }
        (k, stats)
    }

    /// `Σ_m β_m k̂·w_m`: the spring's surface motion per unit probe travel.
    fn stretch(s: &ContactSpring, dir: &Vec3, w: &[Vec3]) -> f64 {
        s.nodes
            .iter()
            .zip(&s.beta)
            .map(|(&m, &b)| b * dir.dot(&w[m]))
            .sum()
    }

    /// `w = ∂x/∂δ` of the last [`Self::compute`] (m per m of probe travel).
    pub fn node_sensitivity(&self) -> &[Vec3] {
        &self.w
    }

    /// The right-hand side `C 1` (N per m of probe travel) of the last
    /// [`Self::compute`], unfiltered.
    pub fn rhs(&self) -> &[Vec3] {
        &self.rhs
    }
}
