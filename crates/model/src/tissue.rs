//! The two-layer tissue of the paper (§3, Fig. 2) as a [`ForceModel`]:
//! linear springs with dampers along the mesh edges, and a nonlinear normal
//! spring with a damper from every surface node to its fixed anchor, plus
//! the layer's tangential (shear) support, a linear tie of each node to its
//! rest position in the rest tangent plane (see [`TissueParams`]).
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
use crate::mesh::{EdgeKind, SurfaceMesh};
use crate::springs::{
    damper_force, damper_jacobian, linear_force, normal_energy, normal_force, normal_stiffness,
    spring_force, spring_force_jacobian,
};
use crate::stencil::StencilLayout;
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

/// A nonlinear normal spring `f = x/(a x + b)` with a damper `c`, node → anchor.
#[derive(Debug, Clone, Copy)]
struct NormalSpring {
    node: usize,
    anchor: Vec3,
    rest: f64,
    a: f64,
    b: f64,
    c: f64,
    /// Rest position of the node (m).
    rest_position: Vec3,
    /// Tangential stiffness block `k_t (I − n₀ n₀ᵀ)` (N/m).
    tangential_k: Matrix3<f64>,
    /// Tangential damping block `c_t (I − n₀ n₀ᵀ)` (N·s/m).
    tangential_c: Matrix3<f64>,
    /// Smallest length allowed to a Newton iterate: `rest − (1 − margin) b/a`.
    min_length: f64,
    diag: usize,
}

/// The tissue's springs and dampers, ready to evaluate.
#[derive(Debug, Clone)]
pub struct TissueForces {
    springs: Vec<LinearSpring>,
    normals: Vec<NormalSpring>,
    /// `(anchor, min_length)` of node `k`'s normal spring (m): the 32 bytes
    /// the step limiter reads, apart from the 248-byte spring.
    limits: Vec<(Vec3, f64)>,
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
        let x0 = mesh.rest_positions();
        let areas = mesh.areas();
        let index = |r, c| pattern.block_index(r, c).expect("edge in pattern");
        let springs = mesh
            .edges()
            .iter()
            .map(|e| {
                let rest = (x0[e.j] - x0[e.i]).norm();
                let g = 0.5 * (areas[e.i] + areas[e.j]) / (rest * rest);
                let (a, c) = match e.kind {
                    EdgeKind::Structural => {
                        (params.structural_stiffness, params.structural_damping)
                    }
                    EdgeKind::Shear => (params.shear_stiffness, params.shear_damping),
                    EdgeKind::Bending => (params.bending_stiffness, params.bending_damping),
                };
                LinearSpring {
                    i: e.i,
                    j: e.j,
                    rest,
                    a: a * g,
                    c: c * g,
                    blocks: [
                        index(e.i, e.i),
                        index(e.i, e.j),
                        index(e.j, e.i),
                        index(e.j, e.j),
                    ],
                }
            })
            .collect();
        let normals = (0..mesh.node_count())
            .map(|k| {
                let anchor = mesh.anchors()[k];
                let rest = (x0[k] - anchor).norm();
                let n0 = mesh.rest_normals()[k];
                let tangent = Matrix3::identity() - n0 * n0.transpose();
                // Layer of rest length L = λ L_ref and stiffness factor φ:
                // p(x) = φ (x/λ) / (normal_a (x/λ) + normal_b), i.e. the
                // reference law at the same strain (a = normal_a/(φA),
                // b = λ normal_b/(φA), asymptote λ b/a < L). The shear tie
                // scales by φ only, not by 1/λ as a layer's G/L would: it is
                // what keeps a compressed normal spring from buckling
                // sideways (its geometric stiffness −|f|/l), and the
                // calibrated value is the least that does (TissueParams);
                // weaker, a 50 N press on a 62 mm layer slid the node
                // around its anchor.
                let (lambda, phi) = (mesh.layer_scales()[k], mesh.stiffness_factors()[k]);
                let asymptote = lambda * params.asymptote();
                let shear = phi;
                NormalSpring {
                    rest_position: x0[k],
                    tangential_k: tangent * (shear * params.tangential_stiffness * areas[k]),
                    tangential_c: tangent * (shear * params.tangential_damping * areas[k]),
                    node: k,
                    anchor,
                    rest,
                    a: params.normal_a / (phi * areas[k]),
                    b: lambda * params.normal_b / (phi * areas[k]),
                    c: params.normal_damping * areas[k],
                    min_length: rest - (1.0 - margin) * asymptote,
                    diag: pattern.diagonal_index(k),
                }
            })
            .collect::<Vec<NormalSpring>>();
        debug_assert!(normals.iter().enumerate().all(|(k, s)| s.node == k));
        let springs: Vec<LinearSpring> = springs;
        let specs: Vec<SpringSpec> = springs
            .iter()
            .map(|s| (s.i, s.j, s.rest, s.a, s.c))
            .collect();
        let normal_specs: Vec<NormalSpec> = normals
            .iter()
            .map(|s| {
                let phi = mesh.stiffness_factors()[s.node];
                NormalSpec {
                    anchor: s.anchor,
                    rest: s.rest,
                    a: s.a,
                    b: s.b,
                    c: s.c,
                    n0: mesh.rest_normals()[s.node],
                    kt: phi * params.tangential_stiffness * areas[s.node],
                    ct: phi * params.tangential_damping * areas[s.node],
                    x_rest: s.rest_position,
                }
            })
            .collect();
        let stencil =
            TissueStencil::new(&StencilLayout::from_pattern(pattern), &specs, &normal_specs);
        TissueForces {
            springs,
            limits: normals.iter().map(|s| (s.anchor, s.min_length)).collect(),
            normals,
            geometric_in_compression,
            stencil,
            kernels: Kernels::default(),
        }
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
                let e = (x[s.node] - s.anchor).norm() - s.rest;
                let u = x[s.node] - s.rest_position;
                if s.a * e + s.b > 0.0 {
                    normal_energy(s.a, s.b, e) + 0.5 * u.dot(&(s.tangential_k * u))
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
            let delta = x[s.j] - x[s.i];
            let l = delta.norm();
            if l <= f64::MIN_POSITIVE {
                continue;
            }
            let d = delta / l;
            let f = linear_force(s.a, l - s.rest);
            let g = if f < 0.0 && !geo { 0.0 } else { f / l };
            // S u = (a − g) (d·u) d + g u, u = w_j − w_i.
            let u = w[s.j] - w[s.i];
            let su = (d * ((s.a - g) * d.dot(&u)) + u * g) * alpha;
            out[s.i] += su;
            out[s.j] -= su;
        }
        for s in &self.normals {
            let law = |e| (normal_force(s.a, s.b, e), normal_stiffness(s.a, s.b, e));
            let (_, stiff) = spring_force_jacobian(&x[s.node], &s.anchor, s.rest, law, geo);
            out[s.node] -= (stiff + s.tangential_k) * (w[s.node] * alpha);
        }
    }

    /// Largest ratio, over nodes, of the normal spring's compression to its
    /// asymptote `b/a` (dimensionless; ≥ 1 means a node crossed it).
    pub fn max_asymptote_ratio(&self, x: &[Vec3]) -> f64 {
        self.normals
            .iter()
            .map(|s| (s.rest - (x[s.node] - s.anchor).norm()) * s.a / s.b)
            .fold(f64::NEG_INFINITY, f64::max)
    }
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

/// Adds a linear spring's edge term `α S + β c d dᵀ` to `a`:
/// `p = α (a − g) + β c`, `q = α g`, `g = f/l` (0 in compression unless `geo`).
#[inline(always)]
fn add_spring_term(
    s: &LinearSpring,
    x: &[Vec3],
    (alpha, beta, geo): (f64, f64, bool),
    a: &mut EdgeMatrix,
) {
    let delta = x[s.j] - x[s.i];
    let l = delta.norm();
    if l <= f64::MIN_POSITIVE {
        return;
    }
    let d = delta / l;
    let f = linear_force(s.a, l - s.rest);
    let g = if f < 0.0 && !geo { 0.0 } else { f / l };
    let p = alpha * (s.a - g) + beta * s.c;
    // (i, j) is a mesh edge, in the side matrix's pattern.
    let written = a.add_spring(s.i, s.j, &d, p, alpha * g);
    debug_assert!(written.is_ok());
}

/// Largest `α ∈ [0, 1]` with `|p + s d| ≥ l_min` for all `s ∈ [0, α]`.
fn path_fraction(p: &Vec3, d: &Vec3, l_min: f64) -> f64 {
    let dd = d.norm_squared();
    if dd == 0.0 {
        return 1.0;
    }
    let pd = p.dot(d);
    let c = p.norm_squared() - l_min * l_min;
    if pd >= 0.0 {
        return 1.0; // moving away from the anchor: the length grows
    }
    if c <= 0.0 {
        return 0.0; // at the limit and moving inward
    }
    let disc = pd * pd - dd * c;
    if disc < 0.0 {
        return 1.0; // the path passes beside the forbidden ball
    }
    // Smaller root of dd s² + 2 pd s + c = 0, in the stable form.
    let s = c / (-pd + disc.sqrt());
    s.min(1.0)
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
        let zero = Vec3::zeros();
        for s in &self.normals {
            let k = s.node;
            f[k] += spring_force(&x[k], &s.anchor, s.rest, |e| normal_force(s.a, s.b, e))
                + damper_force(&x[k], &s.anchor, &v[k], &zero, s.c)
                - s.tangential_k * (x[k] - s.rest_position)
                - s.tangential_c * v[k];
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
            let delta = x[s.j] - x[s.i];
            let l = delta.norm();
            if l <= f64::MIN_POSITIVE {
                continue;
            }
            let d = delta / l;
            let f = linear_force(s.a, l - s.rest);
            let g = if f < 0.0 && !geo { 0.0 } else { f / l };
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
            let law = |e| (normal_force(s.a, s.b, e), normal_stiffness(s.a, s.b, e));
            let (_, stiff) = spring_force_jacobian(&x[s.node], &s.anchor, s.rest, law, geo);
            let damp = damper_jacobian(&x[s.node], &s.anchor, s.c);
            let block = (stiff + s.tangential_k) * alpha + (damp + s.tangential_c) * beta;
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
            let law = |e| (normal_force(s.a, s.b, e), normal_stiffness(s.a, s.b, e));
            let (_, stiff) = spring_force_jacobian(&x[s.node], &s.anchor, s.rest, law, geo);
            let damp = damper_jacobian(&x[s.node], &s.anchor, s.c);
            let block = (stiff + s.tangential_k) * alpha + (damp + s.tangential_c) * beta;
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
            let law = |e| (normal_force(s.a, s.b, e), normal_stiffness(s.a, s.b, e));
            let (_, stiff) = spring_force_jacobian(&x[s.node], &s.anchor, s.rest, law, geo);
            k.add_at(s.diag, &-(stiff + s.tangential_k));
            b.add_at(
                s.diag,
                &-(damper_jacobian(&x[s.node], &s.anchor, s.c) + s.tangential_c),
            );
        }
    }

    /// Keeps every normal spring longer than `rest − (1 − margin) b/a` along
    /// the straight path from `x` to `x + dx`.
    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        self.limits
            .iter()
            .zip(x.iter().zip(dx))
            .map(|((anchor, min_length), (x, dx))| path_fraction(&(x - anchor), dx, *min_length))
            .fold(1.0, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::path_fraction;
    use crate::Vec3;

    #[test]
    fn path_fraction_stops_on_the_limit_sphere() {
        // From 0.04 m straight towards the anchor, limit at 0.01 m: s = 0.75 of 0.04.
        let p = Vec3::new(0.0, 0.04, 0.0);
        let d = Vec3::new(0.0, -0.04, 0.0);
        assert!((path_fraction(&p, &d, 0.01) - 0.75).abs() < 1e-12);
        assert_eq!(path_fraction(&p, &(d * 0.5), 0.01), 1.0);
        assert_eq!(path_fraction(&p, &(-d), 0.01), 1.0);
        // Passing beside the ball.
        let side = Vec3::new(1.0, -0.04, 0.0);
        assert_eq!(path_fraction(&Vec3::new(-0.5, 0.04, 0.0), &side, 0.01), 1.0);
    }
}
