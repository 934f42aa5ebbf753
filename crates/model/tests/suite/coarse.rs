//! The two-level preconditioner trial (issue 18, `coarse.rs`): its coarse
//! matrix is the Galerkin product `Pᵀ S A S P` and its correction is
//! `P A_c⁻¹ Pᵀ r`, both against dense linear algebra on a small thigh; and
//! a conjugate gradient preconditioned with it solves the system.

use crate::common;

use echothigh_model::{
    BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, Kernels, PcgParams, Preconditioner,
    SimdPcg, Soa3, StencilLayout, SurfaceMesh, TissueForces, TissueParams, TwoLevel, Vec3,
};
use nalgebra::{DMatrix, DVector};

/// A 16 × 9 thigh's Newton matrix `M + α K + β B` at a perturbed state
/// (the default step's α, β), assembled with `kernels` (the SIMD kernels
/// leave the grid springs in stencil classes, the scalar ones as edge
/// terms), plus two contact rank-one terms, the second past the capacity
/// of one (into the side matrix): every kind of term the coarse assembly
/// reads. The first ring is held.
fn system(kernels: Kernels) -> (SurfaceMesh, BlockSparse, EdgeMatrix, Vec<bool>) {
    let config = common::small_config(16, 9);
    let mesh = SurfaceMesh::new(&config.thigh).unwrap();
    let pattern = BlockSparse::from_pairs(mesh.node_count(), mesh.coupled_pairs());
    let n = mesh.node_count();
    let mut tissue = TissueForces::new(&mesh, &TissueParams::default(), &pattern, 0.05, false);
    tissue.set_kernels(kernels);
    let mass: Vec<f64> = mesh
        .areas()
        .iter()
        .map(|a| a * config.tissue.areal_density)
        .collect();
    let x: Vec<Vec3> = mesh
        .rest_positions()
        .iter()
        .zip(common::perturbation(n, 0.004, 7))
        .map(|(x, d)| x + d)
        .collect();
    let v = common::perturbation(n, 0.2, 8);
    let mut scratch = JacobianScratch::new(&pattern);
    let mut edge = EdgeMatrix::new(&pattern, 1);
    edge.begin(&mass);
    tissue.add_scaled_jacobians_edge(&x, &v, -1e-4, -1e-2, &mut edge, &mut scratch);
    let k = Vec3::new(0.1, -0.99, 0.05).normalize();
    let (t1, t2) = (mesh.triangles()[n / 2], mesh.triangles()[n / 2 + 3]);
    edge.add_rank_one(t1, [0.2, 0.3, 0.5], &k, 4e-1).unwrap();
    edge.add_rank_one(t2, [0.6, 0.1, 0.3], &k, 1e-1).unwrap();
    edge.finish();
    let fixed = (0..n).map(|k| k < mesh.n_theta()).collect();
    (mesh, pattern, edge, fixed)
}

/// `A` as a dense matrix (column by column through the edge-form product).
fn dense(a: &EdgeMatrix) -> DMatrix<f64> {
    let n = a.n();
    let mut m = DMatrix::zeros(3 * n, 3 * n);
    let (mut e, mut y) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
    for col in 0..3 * n {
        e.fill(Vec3::zeros());
        e[col / 3][col % 3] = 1.0;
        a.mul_vec(&e, &mut y);
        for (row, v) in y.iter().flat_map(|v| v.iter()).enumerate() {
            m[(row, col)] = *v;
        }
    }
    m
}

/// The coarse correction of a residual equals `P (Pᵀ S A S P)⁻¹ Pᵀ r`
/// formed densely, for both assembly paths and patches of 2 and 3 lines.
///
/// Tolerance: both sides solve the same SPD system of `N = 3 n_c`
/// unknowns in f64 (banded against dense Cholesky); each has a relative
/// error ≤ `c N ε κ(A_c)` (Higham, Accuracy and Stability, Thm 10.4, with
/// `c ≈ 3`), so they agree to `2 · 3 N ε κ` of `|y|`, `κ` computed here.
#[test]
fn coarse_correction_is_the_galerkin_solve() {
    for kernels in [Kernels::Scalar, Kernels::Simd] {
        let (mesh, pattern, a, fixed) = system(kernels);
        let n = mesh.node_count();
        let full = dense(&a);
        for patch in [2, 3] {
            let mut two = TwoLevel::new(mesh.n_theta(), mesh.n_z(), patch, &pattern);
            let nc = two.coarse_nodes();
            let mut p = DMatrix::zeros(3 * n, 3 * nc);
            for k in (0..n).filter(|&k| !fixed[k]) {
                for c in 0..3 {
                    p[(3 * k + c, 3 * two.coarse_of(k) + c)] = 1.0;
                }
            }
            let mut ac = p.transpose() * &full * &p;
            for c in 0..nc {
                if (0..n).all(|k| fixed[k] || two.coarse_of(k) != c) {
                    for r in 0..3 {
                        ac[(3 * c + r, 3 * c + r)] = 1.0;
                    }
                }
            }
            two.factor(&a, &fixed).expect("SPD coarse matrix");
            let eig = ac.clone().symmetric_eigenvalues();
            let kappa = eig.max() / eig.min();
            let tol = 2.0 * 3.0 * (3 * nc) as f64 * f64::EPSILON * kappa;

            let layout = StencilLayout::from_pattern(&pattern);
            let pad = layout.pad();
            let mut r: Vec<Vec3> = common::perturbation(n, 1.0, 9 + patch as u64);
            for (rk, &f) in r.iter_mut().zip(&fixed) {
                if f {
                    *rk = Vec3::zeros();
                }
            }
            let mut free = vec![0.0; layout.len()];
            for (k, &f) in fixed.iter().enumerate() {
                free[pad + k] = if f { 0.0 } else { 1.0 };
            }
            let (mut rs, mut zs) = (Soa3::new(&layout), Soa3::new(&layout));
            rs.load(&r);
            let share = two.apply(&rs, &mut zs, &free, pad);
            let mut z = vec![Vec3::zeros(); n];
            zs.store(&mut z);

            let rv = DVector::from_iterator(3 * n, r.iter().flat_map(|v| v.iter().copied()));
            let rc = p.transpose() * &rv;
            let yc = ac.clone().cholesky().expect("SPD").solve(&rc);
            let want = &p * &yc;
            let got = DVector::from_iterator(3 * n, z.iter().flat_map(|v| v.iter().copied()));
            let err = (&got - &want).norm() / want.norm();
            assert!(err <= tol, "{kernels:?}, patch {patch}: {err:e} > {tol:e}");
            let share_want = rc.dot(&yc);
            assert!(
                (share - share_want).abs() <= tol * share_want,
                "{kernels:?}, patch {patch}: rᵀPA_c⁻¹Pᵀr {share} against {share_want}"
            );
        }
    }
}

/// CG with the two-level preconditioner solves `S A S x = S b`: its
/// reported residual meets the tolerance, and so does the true residual
/// `|S (b − A x)|` recomputed here, up to the drift between CG's updated
/// and the true residual (≤ 10 ε |A| |x| per iteration, far below 1e-8 of
/// `|b|` here, so the bound is `tol + 1e-8`).
#[test]
fn two_level_pcg_solves_the_system() {
    let (mesh, pattern, a, fixed) = system(Kernels::Simd);
    let n = mesh.node_count();
    let b: Vec<Vec3> = common::perturbation(n, 1.0, 11);
    let params = PcgParams {
        tol: 1e-9,
        max_iterations: 500,
        preconditioner: Preconditioner::BlockJacobi,
    };
    let layout = StencilLayout::from_pattern(&pattern);
    for patch in [None, Some(2), Some(4)] {
        let mut pcg = SimdPcg::new(&layout, a.edges().len());
        pcg.set_coarse(patch.map(|p| TwoLevel::new(mesh.n_theta(), mesh.n_z(), p, &pattern)));
        let mut x = vec![Vec3::zeros(); n];
        let stats = pcg.solve(&a, &b, &mut x, &fixed, &params);
        assert!(
            stats.converged && stats.residual <= params.tol,
            "{patch:?}: {stats:?}"
        );
        let mut ax = vec![Vec3::zeros(); n];
        a.mul_vec(&x, &mut ax);
        let (mut res, mut bn) = (0.0, 0.0);
        for k in (0..n).filter(|&k| !fixed[k]) {
            res += (b[k] - ax[k]).norm_squared();
            bn += b[k].norm_squared();
        }
        let rel = (res / bn).sqrt();
        assert!(rel <= params.tol + 1e-8, "{patch:?}: true residual {rel:e}");
    }
}
