//! Preconditioned conjugate gradient on an [`EdgeMatrix`], fused into three
//! passes per iteration (issue 18). The algorithm, the Dirichlet filter, the
//! block-Jacobi preconditioner, the warm start and the stop test are those
//! of [`crate::pcg::Pcg`] (Baraff & Witkin 1998, §5.3), and so are the
//! iterates in exact arithmetic; only the order of the vector work differs:
//!
//! 1. nodes: `p = z + β p`, `q = D p`, `Σ pᵀ D p`;
//! 2. edges (and rank-one and side terms): `q += (A − D) p` and
//!    `pᵀ (A − D) p` (for a spring `2 p_iᵀ E p_j`), so that the curvature
//!    `pᵀ A p` needs no pass of its own;
//! 3. nodes: `x += α p`, `r −= α q`, `z = P⁻¹ r`, `rᵀ r`, `rᵀ z`.
//!
//! Fixed nodes have `p_i = 0` (their `r` and `z` are zero), so
//! `pᵀ A p = pᵀ S A S p` without filtering `q`.

use crate::edge_matrix::EdgeMatrix;
use crate::pcg::{block_jacobi_inverse, PcgParams, Preconditioner, SolveStats};
use crate::Vec3;
use nalgebra::Matrix3;

/// Scratch memory of the fused conjugate gradient for `n` nodes.
#[derive(Debug, Clone)]
pub struct EdgePcg {
    r: Vec<Vec3>,
    z: Vec<Vec3>,
    p: Vec<Vec3>,
    q: Vec<Vec3>,
    inv_diag: Vec<Matrix3<f64>>,
}

impl EdgePcg {
    /// Scratch for `n` nodes (allocates once).
    pub fn new(n: usize) -> Self {
        EdgePcg {
            r: vec![Vec3::zeros(); n],
            z: vec![Vec3::zeros(); n],
            p: vec![Vec3::zeros(); n],
            q: vec![Vec3::zeros(); n],
            inv_diag: vec![Matrix3::identity(); n],
        }
    }

    /// Number of nodes this scratch is sized for.
    pub fn n(&self) -> usize {
        self.r.len()
    }

    /// Solves `S A S x = S b` for `x` (warm-started from `x`), `S` zeroing
    /// the nodes with `fixed[i]` (their `x[i]` is set to zero); `A` must be
    /// symmetric positive definite on the free nodes. Same contract and
    /// statistics as [`crate::Pcg::solve`]. Allocates nothing.
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
        let diag = a.diagonal();
        let jacobi = params.preconditioner == Preconditioner::BlockJacobi;
        // Start: x filtered, q = A x, r = S (b − q), z = P⁻¹ r, p = z.
        for i in 0..n {
            if fixed[i] {
                x[i] = Vec3::zeros();
            }
            self.q[i] = diag[i] * x[i];
        }
        a.add_off_diagonal_product(x, &mut self.q);
        let (mut b2, mut rr, mut rz) = (0.0, 0.0, 0.0);
        for i in 0..n {
            if fixed[i] {
                self.inv_diag[i] = Matrix3::zeros();
                self.r[i] = Vec3::zeros();
                self.z[i] = Vec3::zeros();
            } else {
                self.inv_diag[i] = if jacobi {
                    block_jacobi_inverse(&diag[i])
                } else {
                    Matrix3::identity()
                };
                let r = b[i] - self.q[i];
                let z = self.inv_diag[i] * r;
                b2 += b[i].norm_squared();
                rr += r.norm_squared();
                rz += r.dot(&z);
                self.r[i] = r;
                self.z[i] = z;
            }
            self.p[i] = Vec3::zeros();
        }
        let b_norm = b2.sqrt();
        if b_norm == 0.0 {
            x.fill(Vec3::zeros());
            return SolveStats {
                converged: true,
                ..SolveStats::default()
            };
        }
        let target = params.tol * b_norm;
        let mut r_norm = rr.sqrt();
        let mut stats = SolveStats::default();
        if r_norm <= target {
            stats.residual = r_norm / b_norm;
            stats.converged = true;
            return stats;
        }
        // p = z + β p with p = 0: the first direction is z.
        let mut beta = 0.0;
        while stats.iterations < params.max_iterations {
            // Pass 1: p = z + β p, q = D p.
            let mut curvature = 0.0;
            for (((p, q), z), d) in self.p.iter_mut().zip(&mut self.q).zip(&self.z).zip(diag) {
                *p = z + beta * *p;
                *q = d * *p;
                curvature += p.dot(q);
            }
            // Pass 2: the edges.
            curvature += a.add_off_diagonal_product(&self.p, &mut self.q);
            if curvature.is_nan() || curvature <= 0.0 {
                stats.indefinite = true;
                break;
            }
            let alpha = rz / curvature;
            // Pass 3: update, precondition, dot products.
            let (mut rr, mut rz_new) = (0.0, 0.0);
            for i in 0..n {
                if fixed[i] {
                    continue;
                }
                x[i] += alpha * self.p[i];
                let r = self.r[i] - alpha * self.q[i];
                let z = self.inv_diag[i] * r;
                rr += r.norm_squared();
                rz_new += r.dot(&z);
                self.r[i] = r;
                self.z[i] = z;
            }
            stats.iterations += 1;
            r_norm = rr.sqrt();
            if r_norm <= target {
                stats.converged = true;
                break;
            }
            beta = rz_new / rz;
            rz = rz_new;
        }
        stats.residual = r_norm / b_norm;
        stats
    }
}
