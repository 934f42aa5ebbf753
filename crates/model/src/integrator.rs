//! Implicit integration of the paper's Eq. 1 in the symmetric velocity form,
//! with Newton iterations and an asymptote step limiter.
//!
//! # The system
//! With `h` the step, `M` the lumped masses, `F(x, v)` the total force and
//! the blend `λ ∈ [0, 1]` of Eq. 1, the step is
//!
//! `Δx = h (v₀ + λ Δv)`, `M Δv = h F(x₀ + λ Δx, v₀ + λ Δv)`.
//!
//! `λ = 1` is backward Euler; `λ = 0` is explicit Euler (`x₁ = x₀ + h v₀`,
//! `v₁ = v₀ + h M⁻¹ F(x₀, v₀)`). Substituting `Δx` gives one equation in
//! `Δv`, the residual
//!
//! `R(Δv) = h F(x₀ + λ h (v₀ + λ Δv), v₀ + λ Δv) − M Δv = 0`,
//!
//! whose Jacobian is `−(M − λ h B − λ² h² K)` with `K = ∂F/∂x`, `B = ∂F/∂v`.
//! Newton's step `δ` thus solves the symmetric system
//!
//! `(M − λ h B − λ² h² K) δ = R(Δv)`.
//!
//! Linearizing `F` about `(x₀, v₀)` at `Δv = 0` gives DESIGN.md's
//! `(M − λ h B − λ² h² K) Δv = h F₀ + λ h² K v₀`: the paper's single linear
//! solve is the first Newton iterate. Near the normal springs' asymptote one
//! solve is not enough (a 10 ms step can throw a node past `b/a`), so Newton
//! iterates, each solve by PCG (warm-started with the previous step's first
//! correction), and each update is cut to the largest fraction that keeps
//! every force model in its domain ([`ForceModel::max_step_fraction`]),
//! checked on both the evaluation point `x₀ + λ Δx` and the end point
//! `x₀ + Δx`. The start `Δv = 0` is also checked: if `x₀ + h v₀` leaves the
//! domain, Newton starts from `Δv = −(1 − α) v₀ / λ` (end point `x₀ + α h v₀`).
//! With `λ = 0` positions do not depend on `Δv` and nothing can be limited.
//!
//! **Convergence.** Newton stops when a solve has brought the residual to
//! `newton_tol` of the step's first one (relative, so the test scales with
//! the load: a 1e-4 N load is solved as a 10 N one is), or when the
//! residual's position equivalent `h max_i |r_i|/m_i` is below the rounding
//! floor `newton_floor · max_i |x_i|∞`. The relative test is never judged
//! before the first solve: the start `Δv = 0` is a solution only if the
//! residual is at the floor (an absolute tolerance checked there once let
//! small loads never move the model, and let free motion coast explicitly).
//!
//! `K` omits the damper's `∂F/∂x` (not symmetric); Newton stays exact in the
//! residual and converges, at worst linearly while the dampers work hard.
//!
//! **The matrix.** The system is assembled in edge form ([`EdgeMatrix`],
//! solved by the fused [`EdgePcg`]); [`SystemForm::BlockSparse`] keeps the
//! 3×3 block-sparse matrix and its [`Pcg`] as the reference implementation
//! (same iterates in exact arithmetic, for same-run comparisons).

use crate::block_sparse::BlockSparse;
use crate::config::IntegratorParams;
use crate::edge_matrix::EdgeMatrix;
use crate::edge_pcg::EdgePcg;
use crate::force_model::{ForceModel, JacobianScratch};
use crate::pcg::{Pcg, PcgParams, SolveStats};
use crate::simd_pcg::SimdPcg;
use crate::stencil::StencilLayout;
use crate::timings::{seconds_since, StepTimings};
use crate::Vec3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StepStats {
    /// Newton iterations (linear solves) taken.
    pub newton_iterations: u32,
    /// Total PCG iterations over the step's linear solves.
    pub cg_iterations: u32,
    /// Relative residual of the last PCG solve.
    pub cg_residual: f64,
    /// Final Newton residual relative to the step's first one.
    pub newton_residual: f64,
    /// Times the asymptote limiter cut a Newton update (or the start).
    pub limited: u32,
    /// Times a linear solve met an indefinite matrix and was retried with a
    /// larger mass term (see [`ImplicitEuler::step`]).
    pub regularized: u32,
    /// True if Newton met its tolerance within the cap.
    pub converged: bool,
    /// False if the step produced a non-finite state; the state was then
    /// restored to the step's start (or `h` was not a positive finite number).
    pub finite: bool,
    /// Time per stage (s): forces, assembly and PCG here; the contact driver
    /// adds its broad phase and queries.
    pub timings: StepTimings,
}

/// Which matrix form the Newton systems are assembled and solved in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SystemForm {
    /// [`EdgeMatrix`] and the fused [`EdgePcg`] (the default).
    #[default]
    Edge,
    /// [`BlockSparse`] and [`Pcg`]: the reference implementation.
    BlockSparse,
}

/// Which kernels the edge-form system runs on (issue 18).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kernels {
    /// Four-lane SIMD with FMA over structure-of-arrays data
    /// ([`SimdPcg`]; `pulp` picks AVX2 + FMA at run time, else scalar
    /// code of the same order). The default.
    #[default]
    Simd,
    /// The scalar array-of-structures code ([`EdgePcg`]): the previous
    /// implementation, kept for same-run comparisons and tests.
    Scalar,
}

/// The mutable state and the constant data of a system being stepped.
pub struct Dynamics<'a> {
    /// Positions (m), updated in place.
    pub x: &'a mut [Vec3],
    /// Velocities (m/s), updated in place.
    pub v: &'a mut [Vec3],
    /// Lumped masses (kg), all > 0.
    pub mass: &'a [f64],
    /// Dirichlet flags: fixed nodes keep their position, zero velocity.
    pub fixed: &'a [bool],
    /// Constant external force per node during the step (N).
    pub external: &'a [Vec3],
    /// Gravity acceleration (m/s²), applied as `m g`.
    pub gravity: Vec3,
}

/// Implicit Euler with Newton and PCG; owns only scratch memory.
#[derive(Debug, Clone)]
pub struct ImplicitEuler {
    form: SystemForm,
    kernels: Kernels,
    scratch: JacobianScratch,
    a: BlockSparse,
    pcg: Pcg,
    edge: EdgeMatrix,
    edge_pcg: EdgePcg,
    simd_pcg: SimdPcg,
    x0: Vec<Vec3>,
    v0: Vec<Vec3>,
    dv: Vec<Vec3>,
    delta: Vec<Vec3>,
    warm: Vec<Vec3>,
    f: Vec<Vec3>,
    r: Vec<Vec3>,
    x_eval: Vec<Vec3>,
    v_eval: Vec<Vec3>,
    path: Vec<Vec3>,
    diag_scratch: Vec<f64>,
}

/// `v[i] = 0` where `fixed[i]`.
pub(crate) fn filter(v: &mut [Vec3], fixed: &[bool]) {
    for (vi, &f) in v.iter_mut().zip(fixed) {
        if f {
            *vi = Vec3::zeros();
        }
    }
}

impl ImplicitEuler {
    /// Scratch for systems with the block pattern of `pattern` (allocates
    /// once), in edge form. Room for `n` rank-one terms (contact face
    /// samples) per assembly; more go into the edge matrix's side matrix.
    pub fn new(pattern: &BlockSparse) -> Self {
        let n = pattern.n();
        let scratch = JacobianScratch::new(pattern);
        let vecs = || vec![Vec3::zeros(); n];
        ImplicitEuler {
            form: SystemForm::Edge,
            kernels: Kernels::default(),
            a: scratch.k.clone(),
            edge: EdgeMatrix::new(pattern, n),
            edge_pcg: EdgePcg::new(n),
            simd_pcg: SimdPcg::new(
                &StencilLayout::from_pattern(pattern),
                (pattern.nnz_blocks() - n) / 2,
            ),
            scratch,
            pcg: Pcg::new(n),
            x0: vecs(),
            v0: vecs(),
            dv: vecs(),
            delta: vecs(),
            warm: vecs(),
            f: vecs(),
            r: vecs(),
            x_eval: vecs(),
            v_eval: vecs(),
            path: vecs(),
            diag_scratch: vec![0.0; n],
        }
    }

    /// The matrix form of the Newton systems.
    pub fn system_form(&self) -> SystemForm {
        self.form
    }

    /// Chooses the matrix form of the Newton systems (takes effect at the
    /// next assembly; no allocation).
    pub fn set_system_form(&mut self, form: SystemForm) {
        self.form = form;
    }

    /// The kernels of the edge-form system.
    pub fn kernels(&self) -> Kernels {
        self.kernels
    }

    /// Chooses the kernels of the edge-form system (no allocation).
    pub fn set_kernels(&mut self, kernels: Kernels) {
        self.kernels = kernels;
    }

    /// Forgets the warm start (after a reset of the state).
    pub fn reset(&mut self) {
        self.warm.fill(Vec3::zeros());
    }

    /// Advances `sys` by `h` (s) under `forces` (Eq. 1, see the module docs).
    /// Allocates nothing.
    pub fn step(
        &mut self,
        sys: Dynamics<'_>,
        h: f64,
        params: &IntegratorParams,
        forces: &mut dyn ForceModel,
    ) -> StepStats {
        let mut stats = StepStats::default();
        if !(h.is_finite() && h > 0.0) {
            return stats;
        }
        let lambda = params.lambda;
        let pcg = params.pcg();
        self.x0.copy_from_slice(sys.x);
        self.v0.copy_from_slice(sys.v);
        filter(&mut self.v0, sys.fixed);
        self.dv.fill(Vec3::zeros());
        if lambda > 0.0 {
            let clock = Instant::now();
            self.safe_start(h, lambda, sys.fixed, forces, &mut stats);
            stats.timings.step_fraction += seconds_since(clock);
        }
        // Rounding floor of the residual's position equivalent (m): a
        // fraction of the model's size (see `IntegratorParams::newton_floor`).
        let floor = params.newton_floor * self.x0.iter().map(|x| x.amax()).fold(0.0, f64::max);
        let mut r_first = 0.0;
        for it in 0..=params.newton_max_iterations {
            let clock = Instant::now();
            self.evaluate(&sys, h, lambda, forces);
            stats.timings.forces += seconds_since(clock);
            let r_norm = self.r.iter().map(|r| r.norm_squared()).sum::<f64>().sqrt();
            let pos_err = h * self
                .r
                .iter()
                .zip(sys.mass)
                .map(|(r, m)| r.amax() / m)
                .fold(0.0, f64::max);
            if it == 0 {
                r_first = r_norm;
            }
            stats.newton_residual = if r_first > 0.0 { r_norm / r_first } else { 0.0 };
            // The relative test is judged only after a solve: before it the
            // residual is its own reference, and a load of any size must move
            // the model (the start Δv = 0 is not a solution unless r = 0).
            let reduced = it > 0 && stats.newton_residual <= params.newton_tol;
            if reduced || pos_err <= floor {
                stats.converged = true;
                break;
            }
            if it == params.newton_max_iterations || !r_norm.is_finite() {
                break;
            }
            // Inexact Newton: no need to solve below what Newton asks for.
            let pcg_k = PcgParams {
                tol: pcg.tol.max(0.5 * params.newton_tol * r_first / r_norm),
                ..pcg
            };
            let solve = self.newton_solve(&sys, h, lambda, it == 0, &pcg_k, forces, &mut stats);
            stats.newton_iterations += 1;
            stats.cg_iterations += solve.iterations;
            stats.cg_residual = solve.residual;
            let clock = Instant::now();
            self.limit_and_update(h, lambda, forces, &mut stats);
            stats.timings.step_fraction += seconds_since(clock);
        }
        // Commit: v₁ = v₀ + Δv, x₁ = x₀ + h (v₀ + λ Δv).
        for i in 0..sys.x.len() {
            sys.v[i] = self.v0[i] + self.dv[i];
            sys.x[i] = self.x0[i] + h * (self.v0[i] + lambda * self.dv[i]);
        }
        stats.finite = sys
            .x
            .iter()
            .chain(sys.v.iter())
            .all(|p| p.iter().all(|c| c.is_finite()));
        if !stats.finite {
            sys.x.copy_from_slice(&self.x0);
            sys.v.copy_from_slice(&self.v0);
            self.warm.fill(Vec3::zeros());
        }
        stats
    }

    /// Starts Newton inside the force models' domain (see module docs).
    fn safe_start(
        &mut self,
        h: f64,
        lambda: f64,
        fixed: &[bool],
        forces: &dyn ForceModel,
        stats: &mut StepStats,
    ) {
        for (p, v) in self.path.iter_mut().zip(&self.v0) {
            *p = v * h;
        }
        filter(&mut self.path, fixed);
        let alpha = forces.max_step_fraction(&self.x0, &self.path);
        if alpha < 1.0 {
            stats.limited += 1;
            let s = -(1.0 - alpha) / lambda;
            for (dv, v) in self.dv.iter_mut().zip(&self.v0) {
                *dv = v * s;
            }
        }
    }

    /// Evaluation point, total force and residual `r = S (h F − M Δv)`.
    fn evaluate(&mut self, sys: &Dynamics<'_>, h: f64, lambda: f64, forces: &mut dyn ForceModel) {
        for i in 0..self.x0.len() {
            self.v_eval[i] = self.v0[i] + lambda * self.dv[i];
            self.x_eval[i] = self.x0[i] + lambda * h * self.v_eval[i];
            self.f[i] = sys.external[i] + sys.gravity * sys.mass[i];
        }
        forces.add_forces(&self.x_eval, &self.v_eval, &mut self.f);
        for i in 0..self.x0.len() {
            self.r[i] = if sys.fixed[i] {
                Vec3::zeros()
            } else {
                self.f[i] * h - self.dv[i] * sys.mass[i]
            };
        }
    }

    /// Assembles `M − λ h B − λ² h² K` at the evaluation point and solves for δ.
    ///
    /// If PCG meets a non-positive curvature (compressed springs' geometric
    /// stiffness can make the matrix indefinite), the solve is retried with
    /// the mass term scaled by `1 + μ`, μ = 1, 4, 16, 64 (a Levenberg-style
    /// shift: the Newton direction is damped, the residual stays exact).
    #[allow(clippy::too_many_arguments)]
    fn newton_solve(
        &mut self,
        sys: &Dynamics<'_>,
        h: f64,
        lambda: f64,
        first: bool,
        pcg: &PcgParams,
        forces: &mut dyn ForceModel,
        stats: &mut StepStats,
    ) -> SolveStats {
        let (ck, cb) = (-lambda * lambda * h * h, -lambda * h);
        let clock = Instant::now();
        match self.form {
            SystemForm::Edge => {
                self.edge.begin(sys.mass);
                forces.add_scaled_jacobians_edge(
                    &self.x_eval,
                    &self.v_eval,
                    ck,
                    cb,
                    &mut self.edge,
                    &mut self.scratch,
                );
                self.edge.finish();
            }
            SystemForm::BlockSparse => {
                self.a.clear();
                self.a.add_to_diagonal(sys.mass);
                forces.add_scaled_jacobians(
                    &self.x_eval,
                    &self.v_eval,
                    ck,
                    cb,
                    &mut self.a,
                    &mut self.scratch,
                );
            }
        }
        stats.timings.assembly += seconds_since(clock);
        let clock = Instant::now();
        if first {
            self.delta.copy_from_slice(&self.warm);
        } else {
            self.delta.fill(Vec3::zeros());
        }
        let mut solve = self.solve_assembled(sys.fixed, pcg);
        let mut shift = 0.0;
        while solve.indefinite && shift < 64.0 {
            stats.regularized += 1;
            let next = if shift == 0.0 { 1.0 } else { 4.0 * shift };
            for (d, m) in self.diag_scratch.iter_mut().zip(sys.mass) {
                *d = m * (next - shift);
            }
            shift = next;
            match self.form {
                SystemForm::Edge => self.edge.add_to_diagonal(&self.diag_scratch),
                SystemForm::BlockSparse => self.a.add_to_diagonal(&self.diag_scratch),
            }
            self.delta.fill(Vec3::zeros());
            let retry = self.solve_assembled(sys.fixed, pcg);
            solve = SolveStats {
                iterations: solve.iterations + retry.iterations,
                ..retry
            };
        }
        if first {
            self.warm.copy_from_slice(&self.delta);
        }
        stats.timings.pcg += seconds_since(clock);
        solve
    }

    /// Solves the assembled system (of the current form) for `delta`, right-hand side `r`.
    fn solve_assembled(&mut self, fixed: &[bool], pcg: &PcgParams) -> SolveStats {
        match (self.form, self.kernels) {
            (SystemForm::Edge, Kernels::Simd) => {
                self.simd_pcg
                    .solve(&self.edge, &self.r, &mut self.delta, fixed, pcg)
            }
            (SystemForm::Edge, Kernels::Scalar) => {
                self.edge_pcg
                    .solve(&self.edge, &self.r, &mut self.delta, fixed, pcg)
            }
            (SystemForm::BlockSparse, _) => {
                self.pcg
                    .solve(&self.a, &self.r, &mut self.delta, fixed, pcg)
            }
        }
    }

    /// Cuts δ to stay in the domain at both the evaluation and the end point, then `Δv += α δ`.
    fn limit_and_update(
        &mut self,
        h: f64,
        lambda: f64,
        forces: &dyn ForceModel,
        stats: &mut StepStats,
    ) {
        let mut alpha = 1.0f64;
        if lambda > 0.0 {
            for (p, d) in self.path.iter_mut().zip(&self.delta) {
                *p = d * (lambda * lambda * h);
            }
            alpha = alpha.min(forces.max_step_fraction(&self.x_eval, &self.path));
            for i in 0..self.x0.len() {
                // End point x₀ + h (v₀ + λ Δv), reusing x_eval as scratch.
                self.x_eval[i] = self.x0[i] + h * (self.v0[i] + lambda * self.dv[i]);
                self.path[i] = self.delta[i] * (lambda * h);
            }
            alpha = alpha.min(forces.max_step_fraction(&self.x_eval, &self.path));
        }
        if alpha < 1.0 {
            stats.limited += 1;
        }
        for (dv, d) in self.dv.iter_mut().zip(&self.delta) {
            *dv += d * alpha;
        }
    }

    /// Solves `S (−K) S δx = S rhs` at `(x, v)`: the quasi-static stiffness
    /// system, `K = ∂F/∂x` (N/m) of `forces`, `rhs` in N, `out` (m) is both
    /// the warm start and the result; fixed nodes get zero. Allocates nothing.
    /// `−K` must be positive definite on the free nodes (true with held
    /// ends; with free ends rigid motions of the skin are zero modes).
    #[allow(clippy::too_many_arguments)]
    pub fn solve_stiffness(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        fixed: &[bool],
        forces: &mut dyn ForceModel,
        params: &IntegratorParams,
        rhs: &[Vec3],
        out: &mut [Vec3],
    ) -> SolveStats {
        let pcg = PcgParams {
            tol: params.stiffness_tol,
            ..params.pcg()
        };
        match self.form {
            SystemForm::Edge => {
                self.diag_scratch.fill(0.0);
                self.edge.begin(&self.diag_scratch);
                forces.add_scaled_jacobians_edge(
                    x,
                    v,
                    -1.0,
                    0.0,
                    &mut self.edge,
                    &mut self.scratch,
                );
                self.edge.finish();
                match self.kernels {
                    Kernels::Simd => self.simd_pcg.solve(&self.edge, rhs, out, fixed, &pcg),
                    Kernels::Scalar => self.edge_pcg.solve(&self.edge, rhs, out, fixed, &pcg),
                }
            }
            SystemForm::BlockSparse => {
                self.a.clear();
                forces.add_scaled_jacobians(x, v, -1.0, 0.0, &mut self.a, &mut self.scratch);
                self.pcg.solve(&self.a, rhs, out, fixed, &pcg)
            }
        }
    }

    /// `y = A x` (N for `x` in m), `A = −K` the system of the last
    /// [`Self::solve_stiffness`] (the one actually solved, after any retry)
    /// and `x` that solve's result, unfiltered (rows of fixed nodes
    /// included). The SIMD kernels reuse the matrix packed by the solve (and
    /// its start product if the solve ran no iteration); the other forms
    /// multiply their assembled matrix. Allocates nothing.
    ///
    /// # Panics
    /// If `x` or `y` is not of the system's size.
    pub fn stiffness_solution_product(&mut self, x: &[Vec3], y: &mut [Vec3]) {
        match (self.form, self.kernels) {
            (SystemForm::Edge, Kernels::Simd) => {
                assert_eq!(x.len(), y.len());
                self.simd_pcg.solution_product(&self.edge, y);
            }
            (SystemForm::Edge, Kernels::Scalar) => self.edge.mul_vec(x, y),
            (SystemForm::BlockSparse, _) => self.a.mul_vec(x, y),
        }
    }

    /// The last block-sparse system matrix (`M − λhB − λ²h²K` or `−K`)
    /// assembled in [`SystemForm::BlockSparse`].
    pub fn system_matrix(&self) -> &BlockSparse {
        &self.a
    }

    /// The last edge-form system matrix assembled in [`SystemForm::Edge`].
    pub fn edge_matrix(&self) -> &EdgeMatrix {
        &self.edge
    }

    /// The edge-form matrix, mutable: for its index translation (the
    /// active window, [`crate::window`]); the next assembly overwrites its values.
    pub fn edge_matrix_mut(&mut self) -> &mut EdgeMatrix {
        &mut self.edge
    }
}
