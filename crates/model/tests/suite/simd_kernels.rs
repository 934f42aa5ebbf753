//! The SIMD kernels (issue 18) against the scalar edge-form path: the same
//! stencil classes the grid has, the same products to rounding, the same
//! PCG solves and the same trajectories, each to a bound derived from
//! floating-point rounding or from the solvers' own tolerances.
//!
//! The kernels sum the same terms as the scalar code in another order and
//! round each `a·b + c` once (FMA) instead of twice; either way a sum of `T`
//! rounded terms is within `γ_T Σ|terms|` of the exact one (Higham,
//! Accuracy and Stability, §3.1: one rounding per operation is the worst
//! case, FMA only removes roundings), so two evaluations differ by at most
//! `2 γ_T Σ|terms|`.

use crate::common;

use echothigh_model::{
    BlockSparse, EdgeMatrix, EdgePcg, ForceModel, JacobianScratch, Kernels, NoExtraForce,
    PcgParams, Preconditioner, SimdPcg, StencilLayout, SurfaceMesh, TissueForces, TissueParams,
    Vec3,
};

/// `γ_T = T ε / (1 − T ε)`.
fn gamma(terms: usize) -> f64 {
    let t = terms as f64;
    t * f64::EPSILON / (1.0 - t * f64::EPSILON)
}

/// A small thigh at a perturbed state, its tissue's Newton matrix
/// `M + α K + β B` (α, β of the default step) in edge form, plus two
/// contact samples (rank-one terms).
struct Setup {
    mesh: SurfaceMesh,
    pattern: BlockSparse,
    edge: EdgeMatrix,
    mass: Vec<f64>,
}

fn setup(n_theta: usize, n_z: usize) -> Setup {
    setup_with(n_theta, n_z, Kernels::Scalar)
}

/// As [`setup`], the tissue assembling with `kernels` (scalar: every
/// spring arrives as an edge term, and the SIMD PCG repacks them).
fn setup_with(n_theta: usize, n_z: usize, kernels: Kernels) -> Setup {
    let config = common::small_config(n_theta, n_z);
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
        .zip(common::perturbation(n, 0.004, 41))
        .map(|(x, d)| x + d)
        .collect();
    let v = common::perturbation(n, 0.2, 42);
    let mut scratch = JacobianScratch::new(&pattern);
    let mut edge = EdgeMatrix::new(&pattern, n);
    edge.begin(&mass);
    tissue.add_scaled_jacobians_edge(&x, &v, -1e-4, -1e-2, &mut edge, &mut scratch);
    let k = Vec3::new(0.1, -0.99, 0.05).normalize();
    let (t1, t2) = (mesh.triangles()[n / 2], mesh.triangles()[n / 2 + 1]);
    edge.add_rank_one(t1, [0.2, 0.3, 0.5], &k, 4e-1).unwrap();
    edge.add_rank_one(t2, [0.6, 0.1, 0.3], &k, 1e-1).unwrap();
    edge.finish();
    Setup {
        mesh,
        pattern,
        edge,
        mass,
    }
}

/// On the grid the classes are its six spring offsets (around +1, +2;
/// along +n_θ, +2n_θ; across n_θ ± 1) and what is left over are the
/// springs across the θ seam of offset n_θ − 2 (two per ring) and
/// 2n_θ − 1 (one per ring but the last): the other seam springs fill the
/// slots their family leaves empty.
#[test]
fn the_grid_springs_fall_into_six_classes() {
    let (nt, nz) = (24, 11);
    let s = setup(nt, nz);
    let layout = StencilLayout::from_pattern(&s.pattern);
    assert_eq!(layout.offsets(), &[1, 2, nt - 1, nt, nt + 1, 2 * nt]);
    let mut pcg = SimdPcg::new(&layout, s.edge.edges().len());
    let n = s.mesh.node_count();
    let mut y = vec![Vec3::zeros(); n];
    pcg.mul_vec(&s.edge, &vec![Vec3::zeros(); n], &mut y);
    assert_eq!(pcg.stencil().leftover.len(), 2 * nz + (nz - 1));
    let in_classes: usize = pcg
        .stencil()
        .classes
        .iter()
        .map(|c| {
            c.p.iter()
                .zip(&c.q)
                .filter(|(p, q)| **p != 0.0 || **q != 0.0)
                .count()
        })
        .sum();
    assert_eq!(
        in_classes + pcg.stencil().leftover.len(),
        s.edge.edges().len()
    );
}

/// `y = A w` through the SIMD kernels equals the scalar edge-form product
/// to rounding, row by row: `|Δy_i| ≤ 2 γ_T Σ_j |A_ij| |w_j|` with `T`
/// the row's block products of three terms each (a wrong or missing
/// stencil term is of the size of the bound's sum, not of γ_T times it).
#[test]
fn simd_product_equals_the_scalar_product() {
    for (nt, nz) in [(24, 11), (7, 5), (48, 21)] {
        let s = setup(nt, nz);
        let n = s.mesh.node_count();
        let reference = s.edge.to_block_sparse(&s.pattern).unwrap();
        let w = common::perturbation(n, 0.003, 43);
        let mut y_ref = vec![Vec3::zeros(); n];
        s.edge.mul_vec(&w, &mut y_ref);
        let mut pcg = SimdPcg::new(&StencilLayout::from_pattern(&s.pattern), n * 8);
        let mut y = vec![Vec3::zeros(); n];
        pcg.mul_vec(&s.edge, &w, &mut y);
        let longest = (0..n).map(|i| reference.row(i).0.len()).max().unwrap();
        let g = 2.0 * gamma(3 * (longest + 6));
        for i in 0..n {
            let (cols, blocks) = reference.row(i);
            let mut bound = Vec3::zeros();
            for (&j, m) in cols.iter().zip(blocks) {
                bound += m.abs() * w[j].abs();
            }
            for r in 0..3 {
                assert!(
                    (y[i][r] - y_ref[i][r]).abs() <= g * bound[r],
                    "{nt}×{nz} row {i}[{r}]: {} vs {}",
                    y[i][r],
                    y_ref[i][r]
                );
            }
        }
    }
}

/// The SIMD tissue assembly (springs written by stencil class, diagonal
/// blocks from the classes and the normal springs) gives the scalar
/// assembly's matrix, entry by entry, within `2 γ_{T+16} · 3 s_i`, where
/// `s_i = m_i + ‖D_i − m_i I‖ + Σ_j ‖A_ij‖` (max-entry norms) is row
/// `i`'s scale: each of the ≤ T terms of an entry is computed with at most
/// 16 roundings relative to its spring's block (`l − L₀` loses its
/// relative precision near rest, but its absolute error `ε l` costs
/// `ε a l / l` on `g`, of the block's size), and a spring's coefficients
/// are bounded by three times its block's largest entry. A missing,
/// doubled or mis-signed term is of the size of `s_i` itself.
#[test]
fn simd_assembly_equals_the_scalar_assembly() {
    for (nt, nz) in [(24, 11), (7, 5)] {
        let scalar = setup_with(nt, nz, Kernels::Scalar);
        let simd = setup_with(nt, nz, Kernels::Simd);
        assert!(simd.edge.stencil().is_some() && scalar.edge.stencil().is_none());
        let a = scalar.edge.to_block_sparse(&scalar.pattern).unwrap();
        let b = simd.edge.to_block_sparse(&simd.pattern).unwrap();
        let n = scalar.mesh.node_count();
        let longest = (0..n).map(|i| a.row(i).0.len()).max().unwrap();
        let g = 2.0 * gamma(longest + 2 + 16);
        let mut largest = 0.0f64;
        for i in 0..n {
            let (cols, blocks) = a.row(i);
            let scale: f64 = scalar.mass[i] + blocks.iter().map(|m| m.amax()).sum::<f64>();
            for ((&j, x), y) in cols.iter().zip(blocks).zip(b.row(i).1) {
                let diff = (x - y).amax();
                largest = largest.max(diff / scale);
                assert!(
                    diff <= g * 3.0 * scale,
                    "{nt}×{nz} block ({i}, {j}): {diff:e} > {:e}",
                    g * 3.0 * scale
                );
            }
        }
        println!("{nt}×{nz}: largest relative difference {largest:e}");
    }
}

/// The SIMD PCG and the scalar fused PCG solve the same system: both meet
/// the tolerance, in the same number of iterations (±1: rounding may move
/// a residual across the threshold), and their solutions differ by at
/// most what two solutions within the tolerance can, `|Δx| ≤ 2 tol |b| /
/// m_min` (`A ⪰ M ⪰ m_min I`: the compressed springs' geometric term is
/// off and the rank-one terms are positive); fixed nodes stay at zero.
#[test]
fn simd_pcg_solves_like_the_scalar_pcg() {
    let s = setup(24, 11);
    let n = s.mesh.node_count();
    let fixed = s.mesh.fixed();
    let rhs = common::perturbation(n, 1.0, 44);
    for preconditioner in [Preconditioner::BlockJacobi, Preconditioner::None] {
        let params = PcgParams {
            tol: 1e-8,
            max_iterations: 500,
            preconditioner,
        };
        let (mut x_ref, mut x_new) = (vec![Vec3::zeros(); n], common::perturbation(n, 0.01, 45));
        let mut warm = x_new.clone();
        let a = EdgePcg::new(n).solve(&s.edge, &rhs, &mut x_ref, fixed, &params);
        let mut pcg = SimdPcg::new(&StencilLayout::from_pattern(&s.pattern), n);
        // Twice: the second solve must not see the first one's scratch.
        pcg.solve(&s.edge, &rhs, &mut warm, fixed, &params);
        x_new.fill(Vec3::zeros());
        let b = pcg.solve(&s.edge, &rhs, &mut x_new, fixed, &params);
        assert!(a.converged && b.converged, "{a:?} {b:?}");
        assert!(a.iterations.abs_diff(b.iterations) <= 1, "{a:?} {b:?}");
        assert!(b.iterations > 5, "a real solve: {b:?}");
        let b_norm = rhs
            .iter()
            .zip(fixed)
            .filter(|(_, &f)| !f)
            .map(|(v, _)| v.norm_squared())
            .sum::<f64>()
            .sqrt();
        let m_min = s.mass.iter().copied().fold(f64::INFINITY, f64::min);
        let dx = x_ref
            .iter()
            .zip(&x_new)
            .map(|(a, b)| (a - b).norm_squared())
            .sum::<f64>()
            .sqrt();
        assert!(dx <= 2.0 * params.tol * b_norm / m_min, "{dx:e}");
        for (x, &f) in x_new.iter().zip(fixed) {
            assert!(!f || *x == Vec3::zeros());
        }
    }
}

/// 150 steps of a 0–12 N press at 2 Hz with the default integrator, SIMD
/// against scalar kernels: each step's Newton stops at `newton_tol` of its
/// first residual, so each path's step is within `newton_tol · |Δx₁|` of
/// the exact implicit step (`|Δx₁|` the first Newton update, at most the
/// step's motion); the two differ by at most twice that per step, and
/// over the run (damped dynamics, no growth) by the sum of
/// `2 newton_tol · max_i |x₁ − x₀|` over the steps. (Rounding alone,
/// `γ_T` times the condition number of the Newton matrix, ~1e-13 relative
/// here, is far inside it.)
#[test]
fn simd_trajectory_matches_the_scalar_path() {
    let config = common::small_config(24, 11);
    let mut a = common::model(&config);
    let mut b = common::model(&config);
    assert_eq!(a.kernels(), Kernels::Simd);
    b.set_kernels(Kernels::Scalar);
    let tol = config.integrator.newton_tol;
    let (mut bound, mut worst) = (0.0, 0.0f64);
    let (mut same_counts, steps) = (0, 150);
    for step in 0..steps {
        let t = step as f64 * 0.01;
        let load = 12.0 * 0.5 * (1.0 - (std::f64::consts::TAU * 2.0 * t).cos());
        common::press_top(&mut a, load);
        common::press_top(&mut b, load);
        let before = a.positions().to_vec();
        let sa = a.step(0.01, &mut NoExtraForce);
        let sb = b.step(0.01, &mut NoExtraForce);
        assert!(sa.converged && sb.converged);
        same_counts += usize::from(sa.cg_iterations == sb.cg_iterations);
        let moved = before
            .iter()
            .zip(a.positions())
            .map(|(p, q)| (p - q).amax())
            .fold(0.0, f64::max);
        bound += 2.0 * tol * moved;
        let gap = a
            .positions()
            .iter()
            .zip(b.positions())
            .map(|(p, q)| (p - q).amax())
            .fold(0.0, f64::max);
        worst = worst.max(gap);
        assert!(gap <= bound, "step {step}: {gap:e} > {bound:e}");
    }
    assert!(same_counts >= steps * 9 / 10, "{same_counts} of {steps}");
    println!("largest gap {worst:e} m (bound {bound:e} m)");
}
