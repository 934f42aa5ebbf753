//! The physical model of the thigh (paper §3): mesh, tissue, state,
//! external forces and the implicit integrator, stepped as a short list of
//! named stages.

use crate::block_sparse::BlockSparse;
use crate::config::{ConfigError, ModelConfig};
use crate::force_model::{ForceModel, SumForce};
use crate::integrator::{filter, Dynamics, ImplicitEuler, Kernels, StepStats, SystemForm};
use crate::mesh::SurfaceMesh;
use crate::pcg::SolveStats;
use crate::tissue::TissueForces;
use crate::window::{ActiveWindow, MeshState};
use crate::Vec3;

/// Mechanical energy of the model (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    /// `½ Σ m v²`.
    pub kinetic: f64,
    /// Elastic energy of all springs (infinite past a normal spring's asymptote).
    pub elastic: f64,
    /// `−Σ m g·x` (zero without gravity).
    pub gravitational: f64,
}

impl Energy {
    /// Sum of the three terms.
    pub fn total(&self) -> f64 {
        self.kinetic + self.elastic + self.gravitational
    }
}

/// The thigh: owns mesh, parameters, state, external forces and scratch.
#[derive(Debug, Clone)]
pub struct ThighModel {
    config: ModelConfig,
    mesh: SurfaceMesh,
    tissue: TissueForces,
    integrator: ImplicitEuler,
    pattern: BlockSparse,
    mass: Vec<f64>,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    external: Vec<Vec3>,
    time: f64,
    last: StepStats,
    /// The last [`Self::solve_stiffness_with_product`] needed no iteration:
    /// the next warm start is then tried without assembling.
    stiffness_warm_hit: bool,
    /// The last [`Self::solve_stiffness_with_product`] assembled nothing.
    stiffness_unassembled: bool,
    /// The active window, if `integrator.window.enabled` (issue 18).
    window: Option<ActiveWindow>,
}

impl ThighModel {
    /// Validates `config` (errors name the key) and builds the model at rest.
    pub fn new(config: &ModelConfig) -> Result<Self, ConfigError> {
        config.validate("")?;
        let mesh = SurfaceMesh::new(&config.thigh)?;
        let pattern = BlockSparse::from_pairs(mesh.node_count(), mesh.coupled_pairs());
        let ip = &config.integrator;
        let tissue = TissueForces::new(
            &mesh,
            &config.tissue,
            &pattern,
            ip.asymptote_margin,
            ip.geometric_stiffness_in_compression,
        );
        let mass = mesh
            .areas()
            .iter()
            .map(|a| a * config.tissue.areal_density)
            .collect();
        let n = mesh.node_count();
        let window = if ip.window.enabled {
            Some(ActiveWindow::new(&mesh, config)?)
        } else {
            None
        };
        Ok(ThighModel {
            window,
            config: config.clone(),
            integrator: ImplicitEuler::new(&pattern),
            x: mesh.rest_positions().to_vec(),
            v: vec![Vec3::zeros(); n],
            external: vec![Vec3::zeros(); n],
            mesh,
            tissue,
            pattern,
            mass,
            time: 0.0,
            last: StepStats::default(),
            stiffness_warm_hit: false,
            stiffness_unassembled: false,
        })
    }

    /// Advances the model by `h` (s) with the tissue forces plus `extra`
    /// (e.g. the probe contact) and the external forces: implicit Euler,
    /// Eq. 1 (see [`crate::integrator`]). With the active window placed
    /// ([`Self::set_focus`]) only its core is integrated, the rest held
    /// ([`crate::window`]). Allocates nothing.
    pub fn step(&mut self, h: f64, extra: &mut dyn ForceModel) -> StepStats {
        if let Some(window) = self.window.as_mut().filter(|w| w.is_placed()) {
            let state = MeshState {
                mesh: &self.mesh,
                x: &mut self.x,
                v: &mut self.v,
                mass: &self.mass,
                external: &self.external,
                gravity: Vec3::from(self.config.tissue.gravity),
            };
            let stats = window.step(state, h, &self.config.integrator, extra);
            if stats.finite {
                self.time += h;
            }
            self.last = stats;
            return stats;
        }
        let mut forces = SumForce::new(&mut self.tissue, extra);
        let sys = Dynamics {
            x: &mut self.x,
            v: &mut self.v,
            mass: &self.mass,
            fixed: self.mesh.fixed(),
            external: &self.external,
            gravity: Vec3::from(self.config.tissue.gravity),
        };
        let mut stats = self
            .integrator
            .step(sys, h, &self.config.integrator, &mut forces);
        // The extra model's share becomes a stage of its own.
        stats.timings.move_to_contact(&forces.second_timings);
        if stats.finite {
            self.time += h;
        }
        self.last = stats;
        stats
    }

    /// Where the probe is (m, its reference point): the active window, if
    /// configured, follows it (re-centring with hysteresis, see
    /// [`crate::window`]); without a window nothing happens. Call it before
    /// each [`Self::step`] (the contact driver does). Allocates nothing.
    pub fn set_focus(&mut self, p: &Vec3) {
        if let Some(w) = self.window.as_mut() {
            w.follow(&self.mesh, p, &mut self.v, &self.mass);
        }
    }

    /// The active window, if `integrator.window.enabled`.
    pub fn window(&self) -> Option<&ActiveWindow> {
        self.window.as_ref()
    }

    /// Solves `(−∂F/∂x) δx = rhs` at the current state, tissue + `extra`,
    /// Dirichlet-filtered: `rhs` in N, `out` in m (warm start and result).
    /// Contact uses it for the quasi-static local stiffness (a Schur
    /// complement: `k = 1 / (nᵀ (−K)⁻¹ n)` for a unit load pattern `n`).
    /// Allocates nothing. If `−K` is indefinite (compressed springs'
    /// geometric stiffness), the solve is redone without that term and the
    /// returned stats have `indefinite = true` (the result is then the
    /// compliance of the positive-definite part).
    ///
    /// # Panics
    /// If `rhs` or `out` is not of length [`Self::node_count`].
    pub fn solve_stiffness(
        &mut self,
        extra: &mut dyn ForceModel,
        rhs: &[Vec3],
        out: &mut [Vec3],
    ) -> SolveStats {
        self.stiffness_unassembled = false;
        let full = self.tissue.geometric_in_compression();
        let mut stats = self.stiffness_solve(extra, rhs, out);
        if stats.indefinite && full {
            // Compressed springs made −K indefinite: drop their geometric
            // term (−K of the tissue is then positive semi-definite).
            self.tissue.set_geometric_in_compression(false);
            out.fill(Vec3::zeros());
            let retry = self.stiffness_solve(extra, rhs, out);
            self.tissue.set_geometric_in_compression(true);
            stats = SolveStats {
                iterations: stats.iterations + retry.iterations,
                ..retry
            };
            stats.indefinite = true;
        }
        stats
    }

    /// [`Self::solve_stiffness`], then `product = A out` (N) with `A` the
    /// system it solved (`−K` of tissue + `extra`, Dirichlet rows included,
    /// unfiltered). Allocates nothing.
    ///
    /// **Warm start without assembly** (issue 18). While the probe holds,
    /// the previous solution usually meets the tolerance as it is, and the
    /// solve's cost is then all set-up: assembling `A`, packing it, its
    /// preconditioner, one product. So when the last call ran no iteration,
    /// this one first evaluates `A w̃` of the filtered warm start `w̃`
    /// matrix-free ([`ForceModel::add_jacobian_product`], tissue then
    /// `extra`) and applies the solver's own stop test, `|S(b − A w̃)| ≤
    /// tol |S b|` (`tol` = `integrator.stiffness_tol`). If it holds, `w̃` is
    /// returned with that product and nothing is assembled: this is the
    /// solve's own answer, the one PCG gives when its start meets the test
    /// (same operator, `A` at the current state; the product differs from
    /// the assembled one by rounding only), so the contact crate's bound
    /// `|k(w̃) − k*| ≤ tol |b| |S(w* − 1)|` holds unchanged. If it fails,
    /// or a model cannot multiply without assembling, the solve runs as
    /// usual (the matrix-free product, about one assembly's cost, is then
    /// lost; the next call assembles directly until a solve needs no
    /// iteration again). [`Self::stiffness_unassembled`] tells which way
    /// the last call went.
    ///
    /// Otherwise `product` comes, with the SIMD kernels, from a product
    /// through the matrix the solve packed, or the solve's own start
    /// product if it ran no iteration; far cheaper than a matrix-free `K w`
    /// of the tissue ([`Self::tissue_stiffness_product`]).
    ///
    /// # Panics
    /// If `rhs`, `out` or `product` is not of length [`Self::node_count`].
    pub fn solve_stiffness_with_product(
        &mut self,
        extra: &mut dyn ForceModel,
        rhs: &[Vec3],
        out: &mut [Vec3],
        product: &mut [Vec3],
    ) -> SolveStats {
        assert!(product.len() == self.x.len() && rhs.len() == self.x.len());
        self.stiffness_unassembled = false;
        if self.stiffness_warm_hit {
            if let Some(residual) = self.unassembled_start(extra, rhs, out, product) {
                self.stiffness_unassembled = true;
                return SolveStats {
                    converged: true,
                    residual,
                    ..SolveStats::default()
                };
            }
        }
        let stats = self.solve_stiffness(extra, rhs, out);
        self.integrator.stiffness_solution_product(out, product);
        self.stiffness_warm_hit = stats.converged && stats.iterations == 0 && !stats.indefinite;
        stats
    }

    /// True if the last [`Self::solve_stiffness_with_product`] returned its
    /// warm start checked matrix-free, with no assembly.
    pub fn stiffness_unassembled(&self) -> bool {
        self.stiffness_unassembled
    }

    /// Filters `w` (fixed nodes to zero), sets `product = A w` matrix-free
    /// and returns `|S(b − A w)| / |S b|` if PCG's stop test accepts `w`
    /// as it is (`None` if not, if `|S b| = 0`, or if a model cannot
    /// multiply without assembling).
    fn unassembled_start(
        &mut self,
        extra: &mut dyn ForceModel,
        rhs: &[Vec3],
        w: &mut [Vec3],
        product: &mut [Vec3],
    ) -> Option<f64> {
        let fixed = self.mesh.fixed();
        filter(w, fixed);
        product.fill(Vec3::zeros());
        // A = −∂F/∂x: α = −1.
        let x = &self.x;
        if !(self.tissue.add_jacobian_product(x, -1.0, w, product)
            && extra.add_jacobian_product(x, -1.0, w, product))
        {
            return None;
        }
        let (mut b2, mut r2) = (0.0, 0.0);
        for ((b, q), &f) in rhs.iter().zip(product.iter()).zip(fixed) {
            if !f {
                b2 += b.norm_squared();
                r2 += (b - q).norm_squared();
            }
        }
        let (b_norm, r_norm) = (b2.sqrt(), r2.sqrt());
        // PCG's own test (NaN fails it).
        (b_norm > 0.0 && r_norm <= self.config.integrator.stiffness_tol * b_norm)
            .then(|| r_norm / b_norm)
    }

    fn stiffness_solve(
        &mut self,
        extra: &mut dyn ForceModel,
        rhs: &[Vec3],
        out: &mut [Vec3],
    ) -> SolveStats {
        let mut forces = SumForce::new(&mut self.tissue, extra);
        self.integrator.solve_stiffness(
            &self.x,
            &self.v,
            self.mesh.fixed(),
            &mut forces,
            &self.config.integrator,
            rhs,
            out,
        )
    }

    /// Total force on every node at the current state (N): tissue + `extra`
    /// + external + gravity; fixed nodes included (their reaction).
    pub fn forces(&mut self, extra: &mut dyn ForceModel, f: &mut [Vec3]) {
        let g = Vec3::from(self.config.tissue.gravity);
        for ((fi, e), m) in f.iter_mut().zip(&self.external).zip(&self.mass) {
            *fi = e + g * *m;
        }
        self.tissue.add_forces(&self.x, &self.v, f);
        extra.add_forces(&self.x, &self.v, f);
    }

    /// Assembles `K = ∂F/∂x` (N/m) and `B = ∂F/∂v` (N·s/m) of tissue +
    /// `extra` at the current state into `k` and `b` (cleared first; both of
    /// the pattern of [`Self::pattern`]).
    pub fn jacobians(
        &mut self,
        extra: &mut dyn ForceModel,
        k: &mut BlockSparse,
        b: &mut BlockSparse,
    ) {
        k.clear();
        b.clear();
        self.tissue.add_jacobians(&self.x, &self.v, k, b);
        extra.add_jacobians(&self.x, &self.v, k, b);
    }

    /// `out = K w` (N), `K = ∂F/∂x` (N/m) of the tissue alone at the current
    /// state, `w` in m, matrix-free (nothing assembled, nothing allocated):
    /// what the local stiffness query needs after its solve.
    ///
    /// # Panics
    /// If `w` or `out` is not of length [`Self::node_count`].
    pub fn tissue_stiffness_product(&self, w: &[Vec3], out: &mut [Vec3]) {
        assert!(w.len() == self.x.len() && out.len() == self.x.len());
        out.fill(Vec3::zeros());
        self.tissue.add_stiffness_product(&self.x, 1.0, w, out);
    }

    /// The matrix form of the Newton systems ([`SystemForm::Edge`] unless set).
    pub fn system_form(&self) -> SystemForm {
        self.integrator.system_form()
    }

    /// Chooses the matrix form of the Newton and stiffness systems
    /// ([`SystemForm::BlockSparse`] is the reference implementation, for
    /// same-run comparisons and tests).
    pub fn set_system_form(&mut self, form: SystemForm) {
        self.integrator.set_system_form(form);
    }

    /// The kernels of the edge-form system ([`Kernels::Simd`] unless set).
    pub fn kernels(&self) -> Kernels {
        self.integrator.kernels()
    }

    /// Chooses the kernels of the edge-form system ([`Kernels::Scalar`] is
    /// the previous implementation, for same-run comparisons and tests).
    pub fn set_kernels(&mut self, kernels: Kernels) {
        self.integrator.set_kernels(kernels);
        self.tissue.set_kernels(kernels);
        if let Some(w) = self.window.as_mut() {
            w.set_kernels(kernels);
        }
    }

    /// Back to rest: rest positions, zero velocities, zero external forces, time 0.
    pub fn reset(&mut self) {
        self.x.copy_from_slice(self.mesh.rest_positions());
        self.v.fill(Vec3::zeros());
        self.external.fill(Vec3::zeros());
        self.integrator.reset();
        if let Some(w) = self.window.as_mut() {
            w.reset();
        }
        self.time = 0.0;
        self.last = StepStats::default();
    }

    /// Sets positions (m) and velocities (m/s); fixed nodes keep their rest
    /// position and zero velocity. Lengths must equal [`Self::node_count`].
    ///
    /// # Panics
    /// On a length mismatch.
    pub fn set_state(&mut self, x: &[Vec3], v: &[Vec3]) {
        self.x.copy_from_slice(x);
        self.v.copy_from_slice(v);
        for (i, &f) in self.mesh.fixed().iter().enumerate() {
            if f {
                self.x[i] = self.mesh.rest_positions()[i];
            }
        }
        filter(&mut self.v, self.mesh.fixed());
    }

    /// Energy at the current state (J).
    pub fn energy(&self) -> Energy {
        let g = Vec3::from(self.config.tissue.gravity);
        let mut e = Energy {
            elastic: self.tissue.potential_energy(&self.x),
            ..Energy::default()
        };
        for ((x, v), m) in self.x.iter().zip(&self.v).zip(&self.mass) {
            e.kinetic += 0.5 * m * v.norm_squared();
            e.gravitational -= m * g.dot(x);
        }
        e
    }

    /// Largest ratio of a normal spring's compression to its asymptote `b/a`
    /// (< 1 always while the limiter holds; ≤ 1 − margin after Newton updates).
    pub fn max_asymptote_ratio(&self) -> f64 {
        self.tissue.max_asymptote_ratio(&self.x)
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.x.len()
    }

    /// Current positions (m).
    pub fn positions(&self) -> &[Vec3] {
        &self.x
    }

    /// Current velocities (m/s).
    pub fn velocities(&self) -> &[Vec3] {
        &self.v
    }

    /// Rest positions (m).
    pub fn rest_positions(&self) -> &[Vec3] {
        self.mesh.rest_positions()
    }

    /// Anchors of the normal springs (m).
    pub fn anchors(&self) -> &[Vec3] {
        self.mesh.anchors()
    }

    /// Lumped node masses (kg).
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Dirichlet flags (held nodes).
    pub fn fixed(&self) -> &[bool] {
        self.mesh.fixed()
    }

    /// External forces (N), constant over a step; set them before [`Self::step`].
    pub fn external_forces(&self) -> &[Vec3] {
        &self.external
    }

    /// External forces (N), mutable.
    pub fn external_forces_mut(&mut self) -> &mut [Vec3] {
        &mut self.external
    }

    /// The surface mesh (rest geometry, areas, normals, triangles, grid indices).
    pub fn mesh(&self) -> &SurfaceMesh {
        &self.mesh
    }

    /// The configuration the model was built with.
    pub fn config(&self) -> &ModelConfig {
        &self.config
    }

    /// The block pattern of `K` and `B` (values zero); clone it to assemble
    /// matrices for this model.
    pub fn pattern(&self) -> &BlockSparse {
        &self.pattern
    }

    /// Simulated time (s): the sum of the successful steps.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Statistics of the last step.
    pub fn last_stats(&self) -> StepStats {
        self.last
    }
}
