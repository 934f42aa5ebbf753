//! The fused block-Jacobi PCG of [`crate::EdgePcg`] on SIMD kernels
//! (issue 18): the same algorithm, Dirichlet filter, preconditioner, warm
//! start and stop test, hence the same iterates in exact arithmetic, with
//! the vectors in structure-of-arrays form and the matrix repacked as a
//! grid stencil ([`StencilMatrix`]). Per iteration:
//!
//! 1. nodes: `p = z + β p` ([`update_direction`]);
//! 2. nodes: `q = A p` pulled through the stencil, with `pᵀ A p`
//!    ([`stencil_product`]), then the leftover springs, rank-one and side
//!    terms one by one ([`add_edge_product`], [`EdgeMatrix::add_coupling_product`]);
//! 3. nodes: `x += α p`, `r −= α q`, `z = P⁻¹ r`, `rᵀ r`, `rᵀ z` ([`update`]).

use crate::edge_matrix::EdgeMatrix;
use crate::node_vectors::add_edge_product;
use crate::pcg::{PcgParams, Preconditioner, SolveStats};
use crate::stencil::{Soa3, StencilLayout, StencilMatrix};
use crate::stencil_kernels::{stencil_product, update, update_direction, Update};
use crate::stencil_setup::{start, Start};
use crate::Vec3;

/// Scratch memory and the repacked matrix of the SIMD conjugate gradient.
#[derive(Debug, Clone)]
pub struct SimdPcg {
    arch: pulp::Arch,
    m: StencilMatrix,
    x: Soa3,
    r: Soa3,
    z: Soa3,
    p: Soa3,
    q: Soa3,
    inv: [Vec<f64>; 9],
    free: Vec<f64>,
    /// True while `q = A x` for the last solve's `x` (no iteration ran):
    /// [`Self::solution_product`] then copies `q` instead of a product.
    q_is_ax: bool,
}

impl SimdPcg {
    /// Scratch for `layout`'s nodes, with room for `leftovers` springs
    /// outside the stencil's classes (allocates once).
    pub fn new(layout: &StencilLayout, leftovers: usize) -> Self {
        let z = vec![0.0; layout.len()];
        SimdPcg {
            arch: pulp::Arch::new(),
            m: StencilMatrix::new(layout, leftovers),
            x: Soa3::new(layout),
            r: Soa3::new(layout),
            z: Soa3::new(layout),
            p: Soa3::new(layout),
            q: Soa3::new(layout),
            inv: std::array::from_fn(|_| z.clone()),
            free: z,
            q_is_ax: false,
        }
    }

    /// Number of nodes.
    pub fn n(&self) -> usize {
        self.m.layout().n()
    }

    /// The matrix as last repacked (tests, diagnostics).
    pub fn stencil(&self) -> &StencilMatrix {
        &self.m
    }

    /// `y = A x` through the SIMD kernels (repacks `a`; tests and single
    /// products).
    ///
    /// # Panics
    /// If a length differs from [`Self::n`].
    pub fn mul_vec(&mut self, a: &EdgeMatrix, x: &[Vec3], y: &mut [Vec3]) {
        assert!(x.len() == self.n() && y.len() == self.n());
        self.q_is_ax = false;
        self.m.pack(a);
        self.p.load(x);
        self.product(a);
        self.q.store(y);
    }

    /// `y = A x` (N for `x` in m) for the matrix `a` and the solution `x`
    /// of the last [`Self::solve`] with `a`, through the matrix as packed
    /// by that solve (no repacking). If the solve ran no iteration (the
    /// warm start met the tolerance), its start product `A x` is copied
    /// instead of recomputed. Rows of fixed nodes are included (unfiltered
    /// product). Allocates nothing.
    ///
    /// # Panics
    /// If `y.len()` differs from [`Self::n`].
    pub fn solution_product(&mut self, a: &EdgeMatrix, y: &mut [Vec3]) {
        assert_eq!(y.len(), self.n());
        if !self.q_is_ax {
            for (p, x) in self.p.c.iter_mut().zip(&self.x.c) {
                p.copy_from_slice(x);
            }
            self.product(a);
            self.q_is_ax = true;
        }
        self.q.store(y);
    }

    /// `q = A p`, returning `pᵀ A p`.
    fn product(&mut self, a: &EdgeMatrix) -> f64 {
        let classes = match a.stencil() {
            Some(own) if self.m.external => own,
            _ => &self.m.classes[..],
        };
        let mut quad = stencil_product(self.arch, &self.m, classes, &self.p, &mut self.q);
        quad += add_edge_product(&self.m.leftover, &self.p, &mut self.q);
        quad + a.add_coupling_product(&self.p, &mut self.q)
    }

    /// Solves `S A S x = S b` for `x` (warm-started from `x`), `S` zeroing
    /// the nodes with `fixed[i]` (their `x[i]` is set to zero); `A` must be
    /// symmetric positive definite on the free nodes. Same contract and
    /// statistics as [`crate::EdgePcg::solve`]. Allocates nothing.
    ///
    /// # Panics
    /// If the lengths of `b`, `x`, `fixed` and the matrix differ from [`Self::n`].
    pub fn solve(
        &mut self,
        a: &EdgeMatrix,
        b: &[Vec3],
        x: &mut [Vec3],
        fixed: &[bool],
        params: &PcgParams,
    ) -> SolveStats {
        let n = self.n();
        assert!(a.n() == n && b.len() == n && x.len() == n && fixed.len() == n);
        self.m.pack(a);
        let pad = self.m.layout().pad();
        let jacobi = params.preconditioner == Preconditioner::BlockJacobi;
        // Start: x filtered, q = A x, r = S (b − q), z = P⁻¹ r, p = 0.
        for (k, (xk, &f)) in x.iter_mut().zip(fixed).enumerate() {
            if f {
                *xk = Vec3::zeros();
            }
            self.free[pad + k] = if f { 0.0 } else { 1.0 };
        }
        self.p.load(x);
        self.product(a);
        self.q_is_ax = true;
        std::mem::swap(&mut self.x, &mut self.p);
        self.p.clear();
        self.r.load(b);
        let (b2, rr, rz) = start(
            self.arch,
            Start {
                pad,
                rounded: self.m.layout().rounded(),
                jacobi,
                diag: &self.m.diag,
                free: &self.free,
                q: &self.q,
                r: &mut self.r,
                z: &mut self.z,
                inv: &mut self.inv,
            },
        );
        let b_norm = b2.sqrt();
        if b_norm == 0.0 {
            x.fill(Vec3::zeros());
            self.x.clear();
            self.q_is_ax = false;
            return SolveStats {
                converged: true,
                ..SolveStats::default()
            };
        }
        let target = params.tol * b_norm;
        let mut r_norm = rr.sqrt();
        let mut stats = SolveStats::default();
        if r_norm > target {
            self.iterate(a, params, target, rz, &mut r_norm, &mut stats);
        } else {
            stats.converged = true;
        }
        stats.residual = r_norm / b_norm;
        self.x.store(x);
        stats
    }

    /// The iterations from `p = 0`, `rᵀz = rz`, until `|r| ≤ target` or the cap.
    fn iterate(
        &mut self,
        a: &EdgeMatrix,
        params: &PcgParams,
        target: f64,
        mut rz: f64,
        r_norm: &mut f64,
        stats: &mut SolveStats,
    ) {
        let (pad, rounded) = (self.m.layout().pad(), self.m.layout().rounded());
        // The products below overwrite q = A x.
        self.q_is_ax = false;
        let mut beta = 0.0;
        while stats.iterations < params.max_iterations {
            update_direction(self.arch, &self.z, &mut self.p, beta, pad);
            let curvature = self.product(a);
            if curvature.is_nan() || curvature <= 0.0 {
                stats.indefinite = true;
                break;
            }
            let alpha = rz / curvature;
            let (rr, rz_new) = update(
                self.arch,
                Update {
                    pad,
                    rounded,
                    alpha,
                    p: &self.p,
                    q: &self.q,
                    free: &self.free,
                    inv: &self.inv,
                    x: &mut self.x,
                    r: &mut self.r,
                    z: &mut self.z,
                },
            );
            stats.iterations += 1;
            *r_norm = rr.sqrt();
            if *r_norm <= target {
                stats.converged = true;
                break;
            }
            beta = rz_new / rz;
            rz = rz_new;
        }
    }
}
