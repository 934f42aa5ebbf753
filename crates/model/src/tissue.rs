//! The two-layer tissue of the paper (§3, Fig. 2) as a [`ForceModel`]:
//! linear springs with dampers along the mesh edges, and a nonlinear normal
//! spring with a damper from every surface node to its fixed anchor, plus
//! the layer's tangential (shear) support, a linear tie of each node to its
//! rest position in the rest tangent plane (see [`TissueParams`]).
//!
//! **The normal spring is a column along the rest normal** ("nonlinear
//! springs orthogonal to the surface", paper §3): its length is the node's
//! height above its anchor along the rest normal `n₀`, `h = n₀·(x − a)`, and
//! its force acts along `n₀`. A spring from the node to the anchor point
//! instead turns with the node: compressed, its geometric stiffness
//! `−|f|/l` pushes the node sideways, and under a concentrated load (20 N on
//! three nodes of the cylinder) the node slid round the anchor and settled
//! 26 mm *below* it (`tests/suite/concentrated_load.rs`). The column has no
//! geometric term; shear is the tangential tie's.
//!
//! Parameters are converted once from the resolution-independent
//! [`TissueParams`] (see its docs) to per-spring values; the block indices
//! each spring writes are cached so assembly allocates nothing and searches
//! nothing.

use crate::block_sparse::BlockSparse;
use crate::config::TissueParams;
use crate::edge_matrix::EdgeMatrix;
use crate::force_model::{ForceModel, JacobianScratch};
use crate::integrator::Kernels;
use crate::mesh::{Edge, EdgeKind, SurfaceMesh};
use crate::springs::{
    damper_jacobian, linear_force, normal_energy, normal_force, normal_stiffness,
    spring_force_jacobian,
};
use crate::stencil::StencilLayout;
use crate::step_limit::ColumnLimits;
use crate::tissue_simd::{NormalSpec, SpringSpec, TissueStencil};
use crate::Vec3;
use nalgebra::Matrix3;

/// A linear spring `f = a x` with a damper `c`, between nodes `i` and `j`.
#[derive(Debug, Clone, Copy)]
struct LinearSpring {
    i: usize,
    j: usize,
    rest: f64,
    a: f64,
    c: f64,
    /// Storage indices of blocks (i,i), (i,j), (j,i), (j,j).
    blocks: [usize; 4],
}

/// A nonlinear normal spring `f = x/(a x + b)` with a damper `c`: a column
/// from the anchor along the rest normal, `x = n₀·(x_node − anchor) − rest`.
#[derive(Debug, Clone, Copy)]
struct NormalSpring {
    node: usize,
    anchor: Vec3,
    /// Outward rest normal `n₀` (unit), the column's axis.
    normal: Vec3,
    rest: f64,
    a: f64,
    b: f64,
    c: f64,
    /// Rest position of the node (m).
    rest_position: Vec3,
    /// Tangential stiffness `k_t` (N/m) of the block `k_t (I − n₀ n₀ᵀ)`.
    tangential_k: f64,
    /// Tangential damping `c_t` (N·s/m) of the block `c_t (I − n₀ n₀ᵀ)`.
    tangential_c: f64,
    diag: usize,
}

impl NormalSpring {
    /// Change of the column's length (m, negative in compression) at `x`.
    #[inline]
    fn extension(&self, x: &Vec3) -> f64 {
        self.normal.dot(&(x - self.anchor)) - self.rest
    }

    /// Force on the node (N) at position `x` (m), velocity `v` (m/s): the
    /// column's spring and damper along `n₀`, the tie in the tangent plane.
    #[inline]
    fn force(&self, x: &Vec3, v: &Vec3) -> Vec3 {
        let n = self.normal;
        let u = x - self.rest_position;
        let axial = normal_force(self.a, self.b, self.extension(x)) + self.c * n.dot(v);
        let tangential_u = u - n * n.dot(&u);
        let tangential_v = v - n * n.dot(v);
        -(n * axial) - tangential_u * self.tangential_k - tangential_v * self.tangential_c
    }

    /// `α K + β B` of the node's own block (the negated Jacobians of
    /// [`NormalSpring::force`]) as `p n₀ n₀ᵀ + q I`: `(p, q)`.
    #[inline]
    fn scaled_block(&self, x: &Vec3, alpha: f64, beta: f64) -> (f64, f64) {
        let kn = normal_stiffness(self.a, self.b, self.extension(x));
        let q = alpha * self.tangential_k + beta * self.tangential_c;
        (alpha * kn + beta * self.c - q, q)
    }

    /// The block `p n₀ n₀ᵀ + q I` as a matrix.
    #[inline]
    fn block(&self, (p, q): (f64, f64)) -> Matrix3<f64> {
        self.normal * self.normal.transpose() * p + Matrix3::from_diagonal_element(q)
    }
}

impl NormalSpring {
    /// The constants the SIMD kernels read.
    fn spec(&self) -> NormalSpec {
        NormalSpec {
            anchor: self.anchor,
            rest: self.rest,
            a: self.a,
            b: self.b,
            c: self.c,
            n0: self.normal,
            kt: self.tangential_k,
            ct: self.tangential_c,
            x_rest: self.rest_position,
        }
    }
}

/// `(L₀ (m), a (N/m), c (N·s/m))` of the linear spring on edge `e`: the
/// rest length and the resolution-independent constants of its kind scaled
/// by `g = ½ (A_i + A_j) / L₀²` (see [`TissueParams`]).
fn linear_constants(mesh: &SurfaceMesh, params: &TissueParams, e: &Edge) -> (f64, f64, f64) {
    let (x0, areas) = (mesh.rest_positions(), mesh.areas());
    let rest = (x0[e.j] - x0[e.i]).norm();
    let g = 0.5 * (areas[e.i] + areas[e.j]) / (rest * rest);
    let (a, c) = match e.kind {
        EdgeKind::Structural => (params.structural_stiffness, params.structural_damping),
        EdgeKind::Shear => (params.shear_stiffness, params.shear_damping),
        EdgeKind::Bending => (params.bending_stiffness, params.bending_damping),
    };
    (rest, a * g, c * g)
}

/// Node `k`'s normal spring (its diagonal block at storage index `diag`)
/// and its step limit `(n₀, h_min)`, `margin` the asymptote margin.
fn normal_spring(
    mesh: &SurfaceMesh,
    params: &TissueParams,
    k: usize,
    margin: f64,
    diag: usize,
) -> (NormalSpring, (Vec3, f64)) {
    let (x0, areas) = (mesh.rest_positions(), mesh.areas());
    let anchor = mesh.anchors()[k];
    let n0 = mesh.rest_normals()[k];
    // The anchors lie on the inward rest normal (mesh.rs), so
    // the column's rest height is the node–anchor distance.
    let rest = n0.dot(&(x0[k] - anchor));
    // Layer of rest length L = λ L_ref and stiffness factor φ:
    // p(x) = φ (x/λ) / (normal_a (x/λ) + normal_b), i.e. the
    // reference law at the same strain (a = normal_a/(φA),
    // b = λ normal_b/(φA), asymptote λ b/a < L). The shear tie
    // scales by φ only, not by 1/λ as a layer's G/L would: its
    // calibrated value keeps the pressed skin from sliding
    // sideways (TissueParams), whatever the layer's thickness.
    let (lambda, phi) = (mesh.layer_scales()[k], mesh.stiffness_factors()[k]);
    let asymptote = lambda * params.asymptote();
    let min_length = rest - (1.0 - margin) * asymptote;
    let spring = NormalSpring {
        rest_position: x0[k],
        tangential_k: phi * params.tangential_stiffness * areas[k],
        tangential_c: phi * params.tangential_damping * areas[k],
        node: k,
        anchor,
        normal: n0,
        rest,
        a: params.normal_a / (phi * areas[k]),
        b: lambda * params.normal_b / (phi * areas[k]),
        c: params.normal_damping * areas[k],
        diag,
    };
    (spring, (n0, n0.dot(&anchor) + min_length))
}

/// The tissue's springs and dampers, ready to evaluate.
#[derive(Debug, Clone)]
pub struct TissueForces {
    springs: Vec<LinearSpring>,
    normals: Vec<NormalSpring>,
    /// `(n₀, h_min)` of node `k`'s column: a Newton iterate must keep
    /// `n₀·x ≥ h_min` (m), i.e. the column longer than
    /// `rest − (1 − margin) b/a`. The 32 bytes the step limiter reads,
    /// as structure of arrays.
    limits: ColumnLimits,
    geometric_in_compression: bool,
    /// The springs on the grid stencil, for [`Kernels::Simd`].
    stencil: TissueStencil,
    kernels: Kernels,
}

impl TissueForces {
    /// Builds the springs of `mesh` with `params`; `pattern` must be the
    /// pattern built from `mesh.coupled_pairs()`. `margin ∈ (0, 1)` is the
    /// asymptote margin of the step limiter.
    ///
    /// # Panics
    /// If `pattern` does not contain the mesh's edges.
    pub fn new(
        mesh: &SurfaceMesh,
        params: &TissueParams,
        pattern: &BlockSparse,
        margin: f64,
        geometric_in_compression: bool,
    ) -> Self {
        let index = |r, c| pattern.block_index(r, c).expect("edge in pattern");
        let springs: Vec<LinearSpring> = mesh
            .edges()
            .iter()
            .map(|e| {
                let (rest, a, c) = linear_constants(mesh, params, e);
                LinearSpring {
                    i: e.i,
                    j: e.j,
                    rest,
                    a,
                    c,
                    blocks: [
                        index(e.i, e.i),
                        index(e.i, e.j),
                        index(e.j, e.i),
                        index(e.j, e.j),
                    ],
                }
            })
            .collect();
        let (normals, limits): (Vec<NormalSpring>, Vec<(Vec3, f64)>) = (0..mesh.node_count())
            .map(|k| normal_spring(mesh, params, k, margin, pattern.diagonal_index(k)))
            .unzip();
        let limits = ColumnLimits::new(limits);
        let specs: Vec<SpringSpec> = springs
            .iter()
            .map(|s| (s.i, s.j, s.rest, s.a, s.c))
            .collect();
        let normal_specs: Vec<NormalSpec> = normals.iter().map(NormalSpring::spec).collect();
        let stencil =
            TissueStencil::new(&StencilLayout::from_pattern(pattern), &specs, &normal_specs);
        TissueForces {
            springs,
            limits,
            normals,
            geometric_in_compression,
            stencil,
            kernels: Kernels::default(),
        }
    }

    /// Recomputes every spring's constants from `mesh`, whose topology
    /// (edges, node count) must be the one this was built from, with other
    /// rest geometry: the active window moved over the mesh
    /// ([`crate::window`]). The same constants [`Self::new`] computes.
    /// Allocates nothing.
    ///
    /// # Panics
    /// If `mesh` has another node or edge count.
    pub fn reload(&mut self, mesh: &SurfaceMesh, params: &TissueParams, margin: f64) {
        assert!(
            mesh.edges().len() == self.springs.len() && mesh.node_count() == self.normals.len()
        );
        for (s, e) in self.springs.iter_mut().zip(mesh.edges()) {
            debug_assert!(s.i == e.i && s.j == e.j);
            (s.rest, s.a, s.c) = linear_constants(mesh, params, e);
        }
        for (k, s) in self.normals.iter_mut().enumerate() {
            let limit;
            (*s, limit) = normal_spring(mesh, params, k, margin, s.diag);
            self.limits.set(k, limit);
        }
        self.stencil.reload(
            self.springs.iter().map(|s| (s.rest, s.a, s.c)),
            self.normals.iter().map(NormalSpring::spec),
        );
    }

    /// The kernels of forces and assembly ([`Kernels::Simd`] unless set).
    pub fn kernels(&self) -> Kernels {
        self.kernels
    }

    /// Chooses the kernels of forces and assembly (no allocation).
    pub fn set_kernels(&mut self, kernels: Kernels) {
        self.kernels = kernels;
    }

    /// Whether compressed springs' geometric stiffness goes into `K`.
    pub fn geometric_in_compression(&self) -> bool {
        self.geometric_in_compression
    }

    /// Sets whether compressed springs' geometric stiffness goes into `K`
    /// (without it `−K` of the tissue is positive semi-definite).
    pub fn set_geometric_in_compression(&mut self, on: bool) {
        self.geometric_in_compression = on;
    }

    /// Elastic potential energy (J) of all springs at positions `x` (m).
    /// Infinite if a normal spring is at or past its asymptote.
    pub fn potential_energy(&self, x: &[Vec3]) -> f64 {
        let linear: f64 = self
            .springs
            .iter()
            .map(|s| {
                let e = (x[s.j] - x[s.i]).norm() - s.rest;
                0.5 * s.a * e * e
            })
            .sum();
        let normal: f64 = self
            .normals
            .iter()
            .map(|s| {
                let e = s.extension(&x[s.node]);
                let u = x[s.node] - s.rest_position;
                let tangential = u - s.normal * s.normal.dot(&u);
                if s.a * e + s.b > 0.0 {
                    normal_energy(s.a, s.b, e) + 0.5 * s.tangential_k * tangential.norm_squared()
                } else {
                    f64::INFINITY
                }
            })
            .sum();
        linear + normal
    }

    /// `out += α K w` (N for `α` = 1 and `w` in m), `K = ∂F/∂x` (N/m) of the
    /// tissue at `x` (m), without assembling `K`: spring by spring, the same
    /// blocks as [`ForceModel::add_scaled_jacobians`] with `β = 0` (so the
    /// geometric term in compression follows the same switch). A linear
    /// spring of block `S` adds `S (w_j − w_i)` to node `i` and the opposite
    /// to `j`; a normal spring adds `−(S + k_t) w_k` to its node (SOFA's
    /// `addDForce`).
    pub fn add_stiffness_product(&self, x: &[Vec3], alpha: f64, w: &[Vec3], out: &mut [Vec3]) {
        let geo = self.geometric_in_compression;
        for s in &self.springs {
            add_spring_product(s, x, (alpha, geo), w, out);
        }
        for s in &self.normals {
            let (p, q) = s.scaled_block(&x[s.node], alpha, 0.0);
            let w = w[s.node];
            out[s.node] -= s.normal * (p * s.normal.dot(&w)) + w * q;
        }
    }

    /// Largest ratio, over nodes, of the normal spring's compression to its
    /// asymptote `b/a` (dimensionless; ≥ 1 means a node crossed it).
    pub fn max_asymptote_ratio(&self, x: &[Vec3]) -> f64 {
        self.normals
            .iter()
            .map(|s| -s.extension(&x[s.node]) * s.a / s.b)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// `out += α K w` of one linear spring: `S u` on node `i` and `−S u` on
/// `j`, `S u = (a − g)(d·u) d + g u`, `u = w_j − w_i` (nothing for a
/// spring of zero length).
#[inline(always)]
fn add_spring_product(
    s: &LinearSpring,
    x: &[Vec3],
    (alpha, geo): (f64, bool),
    w: &[Vec3],
    out: &mut [Vec3],
) {
    let Some((d, g)) = spring_direction(s, x, geo) else {
        return;
    };
    let u = w[s.j] - w[s.i];
    let su = (d * ((s.a - g) * d.dot(&u)) + u * g) * alpha;
    out[s.i] += su;
    out[s.j] -= su;
}

/// Force on node `i` of a linear spring and its damper (N):
/// `f_i = (a e + c ė) d`, spring and damper along the same direction
/// (zero for a spring of zero length).
#[inline(always)]
fn linear_spring_force(s: &LinearSpring, x: &[Vec3], v: &[Vec3]) -> Vec3 {
    let delta = x[s.j] - x[s.i];
    let l = delta.norm();
    if l <= f64::MIN_POSITIVE {
        return Vec3::zeros();
    }
    let rate = (v[s.j] - v[s.i]).dot(&delta) / l;
    delta * ((linear_force(s.a, l - s.rest) + s.c * rate) / l)
}

/// A linear spring's unit direction `d = (x_j − x_i)/l` and geometric
/// stiffness `g = f/l` (N/m; 0 in compression unless `geo`), `f = a (l − L₀)`
/// (paper §3, `f(x) = a x`); `None` for a spring of zero length.
#[inline(always)]
fn spring_direction(s: &LinearSpring, x: &[Vec3], geo: bool) -> Option<(Vec3, f64)> {
    let delta = x[s.j] - x[s.i];
    let l = delta.norm();
    if l <= f64::MIN_POSITIVE {
        return None;
    }
    let f = linear_force(s.a, l - s.rest);
    Some((delta / l, if f < 0.0 && !geo { 0.0 } else { f / l }))
}

/// Adds a linear spring's edge term `α S + β c d dᵀ` to `a`:
/// `p = α (a − g) + β c`, `q = α g`, `g = f/l` (0 in compression unless `geo`).
#[inline(always)]
fn add_spring_term(
    s: &LinearSpring,
    x: &[Vec3],
    (alpha, beta, geo): (f64, f64, bool),
    a: &mut EdgeMatrix,
) {
    let Some((d, g)) = spring_direction(s, x, geo) else {
        return;
    };
    let p = alpha * (s.a - g) + beta * s.c;
    // (i, j) is a mesh edge, in the side matrix's pattern.
    let written = a.add_spring(s.i, s.j, &d, p, alpha * g);
    debug_assert!(written.is_ok());
}

impl ForceModel for TissueForces {
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        if self.kernels == Kernels::Simd {
            self.stencil.add_forces(x, v, f);
            for &e in self.stencil.leftover() {
                let s = &self.springs[e];
                let fi = linear_spring_force(s, x, v);
                f[s.i] += fi;
                f[s.j] -= fi;
            }
            return;
        }
        // The mesh lists a node's springs together: node i's force stays
        // in a register while its group lasts (no store-to-load chain).
        let mut row = usize::MAX;
        let mut acc = Vec3::zeros();
        for s in &self.springs {
            if s.i != row {
                if row != usize::MAX {
                    f[row] += acc;
                }
                row = s.i;
                acc = Vec3::zeros();
            }
            let fi = linear_spring_force(s, x, v);
            acc += fi;
            f[s.j] -= fi;
        }
        if row != usize::MAX {
            f[row] += acc;
        }
        for s in &self.normals {
            f[s.node] += s.force(&x[s.node], &v[s.node]);
        }
    }

    /// Direct assembly: one block `α S + β c d dᵀ` per spring into `a`.
    fn add_scaled_jacobians(
        &mut self,
        x: &[Vec3],
        _v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut BlockSparse,
        _scratch: &mut JacobianScratch,
    ) {
        let geo = self.geometric_in_compression;
        for s in &self.springs {
            let Some((d, g)) = spring_direction(s, x, geo) else {
                continue;
            };
            // α S + β D with S = (a − g) d dᵀ + g I and D = c d dᵀ.
            let ddt = d * d.transpose();
            let block =
                ddt * (alpha * (s.a - g) + beta * s.c) + Matrix3::from_diagonal_element(alpha * g);
            let [ii, ij, ji, jj] = s.blocks;
            a.add_at(ii, &-block);
            a.add_at(jj, &-block);
            a.add_at(ij, &block);
            a.add_at(ji, &block);
        }
        for s in &self.normals {
            let block = s.block(s.scaled_block(&x[s.node], alpha, beta));
            a.add_at(s.diag, &-block);
        }
    }

    /// Streaming edge-form assembly: one `(d, p, q)` per spring, in mesh
    /// order (`α S + β c d dᵀ`: `p = α (a − g) + β c`, `q = α g`), then one
    /// diagonal block per normal spring.
    fn add_scaled_jacobians_edge(
        &mut self,
        x: &[Vec3],
        _v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut EdgeMatrix,
        _scratch: &mut JacobianScratch,
    ) {
        let geo = self.geometric_in_compression;
        if self.kernels == Kernels::Simd && a.stencil_layout() == self.stencil.layout() {
            let (classes, diag) = a.stencil_mut();
            self.stencil.assemble(x, (alpha, beta, geo), classes, diag);
            for &e in self.stencil.leftover() {
                add_spring_term(&self.springs[e], x, (alpha, beta, geo), a);
            }
            return;
        }
        for s in &self.springs {
            add_spring_term(s, x, (alpha, beta, geo), a);
        }
        for s in &self.normals {
            let block = s.block(s.scaled_block(&x[s.node], alpha, beta));
            a.add_diagonal(s.node, &-block);
        }
    }

    fn add_jacobians(&mut self, x: &[Vec3], _v: &[Vec3], k: &mut BlockSparse, b: &mut BlockSparse) {
        let geo = self.geometric_in_compression;
        for s in &self.springs {
            let (_, stiff) =
                spring_force_jacobian(&x[s.i], &x[s.j], s.rest, |e| (s.a * e, s.a), geo);
            let damp = damper_jacobian(&x[s.i], &x[s.j], s.c);
            let [ii, ij, ji, jj] = s.blocks;
            k.add_at(ii, &-stiff);
            k.add_at(jj, &-stiff);
            k.add_at(ij, &stiff);
            k.add_at(ji, &stiff);
            b.add_at(ii, &-damp);
            b.add_at(jj, &-damp);
            b.add_at(ij, &damp);
            b.add_at(ji, &damp);
        }
        for s in &self.normals {
            k.add_at(s.diag, &-s.block(s.scaled_block(&x[s.node], 1.0, 0.0)));
            b.add_at(s.diag, &-s.block(s.scaled_block(&x[s.node], 0.0, 1.0)));
        }
    }

    /// Keeps every normal column longer than `rest − (1 − margin) b/a` along
    /// the straight path from `x` to `x + dx` ([`ColumnLimits`], on this
    /// model's kernels).
    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        self.limits.max_step_fraction(x, dx, self.kernels)
    }

    /// [`TissueForces::add_stiffness_product`] (the springs' blocks as the
    /// edge assembly writes them with `β = 0`); with the SIMD kernels the
    /// classes' springs and the normal springs go through the stencil's
    /// product kernel, the springs left over through the scalar code.
    fn add_jacobian_product(
        &mut self,
        x: &[Vec3],
        alpha: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) -> bool {
        let geo = self.geometric_in_compression;
        if self.kernels != Kernels::Simd {
            self.add_stiffness_product(x, alpha, w, out);
            return true;
        }
        self.stencil.add_stiffness_product(x, w, (alpha, geo), out);
        for &e in self.stencil.leftover() {
            add_spring_product(&self.springs[e], x, (alpha, geo), w, out);
        }
        true
    }
}
