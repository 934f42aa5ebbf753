//! Preconditioned conjugate gradient on a [`BlockSparse`] system, with
//! Dirichlet nodes removed by filtering (Baraff & Witkin 1998, §5.3: the
//! projection `S` zeroes the fixed nodes' components of every residual and
//! search direction, so they never move).
//!
//! The paper (§3) solves Eq. 1 by conjugate gradient; the preconditioner is
//! block-Jacobi (the inverse of each node's 3×3 diagonal block), the start is
//! the caller's `x` (warm start), and the stop test is the relative residual
//! `|b − A x| ≤ tol · |b|` on the filtered system, or an iteration cap.

use crate::block_sparse::BlockSparse;
use crate::Vec3;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// Preconditioner of the conjugate gradient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preconditioner {
    /// Plain conjugate gradient.
    None,
    /// Inverse of each node's 3×3 diagonal block.
    BlockJacobi,
}

/// Stopping rule and preconditioner of one solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcgParams {
    /// Relative residual tolerance (dimensionless).
    pub tol: f64,
    /// Iteration cap.
    pub max_iterations: u32,
    /// Preconditioner.
    pub preconditioner: Preconditioner,
}

/// What one linear solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SolveStats {
    /// Conjugate-gradient iterations (matrix–vector products after the first).
    pub iterations: u32,
    /// Final relative residual `|b − A x| / |b|` (0 if `b = 0`).
    pub residual: f64,
    /// True if the tolerance was met.
    pub converged: bool,
    /// True if a non-positive curvature `pᵀ A p ≤ 0` was met (matrix not SPD
    /// on the free nodes); the solve stopped there with the iterate so far.
    pub indefinite: bool,
}

/// Scratch memory of the conjugate gradient for systems of `n` nodes.
#[derive(Debug, Clone)]
pub struct Pcg {
    r: Vec<Vec3>,
    z: Vec<Vec3>,
    p: Vec<Vec3>,
    q: Vec<Vec3>,
    inv_diag: Vec<Matrix3<f64>>,
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

fn filter(v: &mut [Vec3], fixed: &[bool]) {
    for (vi, &f) in v.iter_mut().zip(fixed) {
        if f {
            *vi = Vec3::zeros();
        }
    }
}

/// The block-Jacobi inverse of a diagonal block `d`: the closed-form
/// inverse of its symmetric part if that is positive definite (Sylvester's
/// criterion), else scalar Jacobi on `|diagonal|` (1 where it is zero).
pub(crate) fn block_jacobi_inverse(d: &Matrix3<f64>) -> Matrix3<f64> {
    let m = (d + d.transpose()) * 0.5;
    let spd = m[(0, 0)] > 0.0
        && m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)] > 0.0
        && m.determinant() > 0.0;
    match m.try_inverse() {
        Some(inv) if spd => inv,
        _ => Matrix3::from_diagonal(&d.diagonal().map(|v| {
            if v.abs() > 0.0 {
                1.0 / v.abs()
            } else {
                1.0
            }
        })),
    }
}

impl Pcg {
    /// Scratch for `n` nodes (allocates once).
    pub fn new(n: usize) -> Self {
        Pcg {
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

    /// Solves `S A S x = S b` for `x` (warm-started from `x`), where `S`
    /// zeroes the nodes with `fixed[i]`: their `x[i]` is set to zero.
    /// `A` must be symmetric positive definite on the free nodes.
    /// Allocates nothing.
    ///
    /// # Panics
    /// If the lengths of `b`, `x`, `fixed` and the matrix differ from [`Self::n`].
    pub fn solve(
        &mut self,
        a: &BlockSparse,
        b: &[Vec3],
        x: &mut [Vec3],
        fixed: &[bool],
        params: &PcgParams,
    ) -> SolveStats {
        let n = self.n();
        assert!(a.n() == n && b.len() == n && x.len() == n && fixed.len() == n);
        self.prepare_preconditioner(a, fixed, params.preconditioner);
        filter(x, fixed);
        // r = S (b − A x)
        a.mul_vec(x, &mut self.q);
        for i in 0..n {
            self.r[i] = if fixed[i] {
                Vec3::zeros()
            } else {
                b[i] - self.q[i]
            };
        }
        let b_norm = b
            .iter()
            .zip(fixed)
            .filter(|(_, &f)| !f)
            .map(|(v, _)| v.norm_squared())
            .sum::<f64>()
            .sqrt();
        if b_norm == 0.0 {
            x.fill(Vec3::zeros());
            return SolveStats {
                converged: true,
                ..SolveStats::default()
            };
        }
        let target = params.tol * b_norm;
        let mut r_norm = dot(&self.r, &self.r).sqrt();
        let mut stats = SolveStats::default();
        if r_norm <= target {
            stats.residual = r_norm / b_norm;
            stats.converged = true;
            return stats;
        }
        self.precondition();
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        while stats.iterations < params.max_iterations {
            a.mul_vec(&self.p, &mut self.q);
            filter(&mut self.q, fixed);
            let curvature = dot(&self.p, &self.q);
            if curvature.is_nan() || curvature <= 0.0 {
                stats.indefinite = true;
                break;
            }
            let alpha = rz / curvature;
            for ((xi, ri), (pi, qi)) in x
                .iter_mut()
                .zip(self.r.iter_mut())
                .zip(self.p.iter().zip(&self.q))
            {
                *xi += alpha * pi;
                *ri -= alpha * qi;
            }
            stats.iterations += 1;
            r_norm = dot(&self.r, &self.r).sqrt();
            if r_norm <= target {
                stats.converged = true;
                break;
            }
            self.precondition();
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + beta * self.p[i];
            }
        }
        stats.residual = r_norm / b_norm;
        stats
    }

    /// Inverts the diagonal blocks (block-Jacobi) or sets identities.
    fn prepare_preconditioner(&mut self, a: &BlockSparse, fixed: &[bool], kind: Preconditioner) {
        for (i, inv) in self.inv_diag.iter_mut().enumerate() {
            *inv = match kind {
                Preconditioner::None => Matrix3::identity(),
                Preconditioner::BlockJacobi if fixed[i] => Matrix3::zeros(),
                Preconditioner::BlockJacobi => {
                    block_jacobi_inverse(&a.values()[a.diagonal_index(i)])
                }
            };
        }
    }

    /// `z = P⁻¹ r` (fixed nodes have zero rows in `P⁻¹`, and `r` is filtered).
    fn precondition(&mut self) {
        for ((z, inv), r) in self.z.iter_mut().zip(&self.inv_diag).zip(&self.r) {
            *z = inv * r;
        }
    }
}
