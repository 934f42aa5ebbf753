//! The edge-form system (issue 18) against the block-sparse reference:
//! same matrix entries, same products, same PCG solves and the same
//! trajectories, each to a bound derived from floating-point rounding or
//! from the solvers' own tolerances.

use crate::common;

use echothigh_model::{
    BlockSparse, EdgeMatrix, EdgePcg, ForceModel, JacobianScratch, Kernels, NoExtraForce, Pcg,
    PcgParams, Preconditioner, SurfaceMesh, SystemForm, TissueForces, TissueParams, Vec3,
};

/// `γ_T = T ε / (1 − T ε)` (Higham, Accuracy and Stability, §3.1): the
/// relative error bound of a sum of `T` rounded terms.
fn gamma(terms: usize) -> f64 {
    let t = terms as f64;
    t * f64::EPSILON / (1.0 - t * f64::EPSILON)
}

/// A small thigh at a perturbed state: mesh, pattern, tissue, masses, x, v.
struct Setup {
    pattern: BlockSparse,
    tissue: TissueForces,
    mass: Vec<f64>,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    fixed: Vec<bool>,
    triangles: Vec<[usize; 3]>,
}

fn setup(geometric_in_compression: bool) -> Setup {
    let config = common::small_config(24, 11);
    let mesh = SurfaceMesh::new(&config.thigh).unwrap();
    let pattern = BlockSparse::from_pairs(mesh.node_count(), mesh.coupled_pairs());
    let n = mesh.node_count();
    let mut tissue = TissueForces::new(
        &mesh,
        &TissueParams::default(),
        &pattern,
        0.05,
        geometric_in_compression,
    );
    // The scalar kernels compute each spring's block as the block-sparse
    // assembly does (the bounds below count summation order only); the
    // SIMD kernels are checked against them in tests/suite/simd_kernels.rs.
    tissue.set_kernels(Kernels::Scalar);
    let mass = mesh
        .areas()
        .iter()
        .map(|a| a * config.tissue.areal_density)
        .collect();
    let x = mesh
        .rest_positions()
        .iter()
        .zip(common::perturbation(n, 0.004, 31))
        .map(|(x, d)| x + d)
        .collect();
    Setup {
        pattern,
        tissue,
        mass,
        x,
        v: common::perturbation(n, 0.2, 32),
        fixed: mesh.fixed().to_vec(),
        triangles: mesh.triangles().to_vec(),
    }
}

/// `α, β` of the default step: `−λ²h²`, `−λh` with λ = 1, h = 10 ms.
const ALPHA: f64 = -1e-4;
const BETA: f64 = -1e-2;

/// Assembles `M + α K + β B` of the tissue both ways.
fn both(s: &mut Setup) -> (EdgeMatrix, BlockSparse) {
    let mut scratch = JacobianScratch::new(&s.pattern);
    let mut edge = EdgeMatrix::new(&s.pattern, s.mass.len());
    edge.begin(&s.mass);
    s.tissue
        .add_scaled_jacobians_edge(&s.x, &s.v, ALPHA, BETA, &mut edge, &mut scratch);
    edge.finish();
    let mut reference = s.pattern.clone();
    reference.clear();
    reference.add_to_diagonal(&s.mass);
    s.tissue
        .add_scaled_jacobians(&s.x, &s.v, ALPHA, BETA, &mut reference, &mut scratch);
    (edge, reference)
}

/// The longest row of the pattern (blocks): the terms of any entry are at
/// most the mass, the normal spring and one per edge of the row.
fn terms(pattern: &BlockSparse) -> usize {
    (0..pattern.n())
        .map(|i| pattern.row(i).0.len())
        .max()
        .unwrap()
        + 2
}

/// Entry by entry, the edge form's matrix equals the block-sparse one to
/// rounding: both sum the same `T` terms in another order, so they differ
/// by at most `2 γ_T Σ|terms|`. An off-diagonal entry is one term; a
/// diagonal entry's terms are the mass, the normal spring's block
/// `N = D − m I + Σ E` and the `−E` of its edges, so `Σ|terms| ≤
/// 2 (|D| + m + Σ_j |A_ij|)` with the off-diagonal blocks `A_ij = E`.
#[test]
fn edge_matrix_equals_the_block_sparse_matrix() {
    for geo in [false, true] {
        let mut s = setup(geo);
        let (edge, reference) = both(&mut s);
        let converted = edge.to_block_sparse(&s.pattern).unwrap();
        let g = 2.0 * gamma(terms(&s.pattern));
        let mut changed = 0.0f64;
        for i in 0..s.pattern.n() {
            let (cols, new_blocks) = converted.row(i);
            let (_, old_blocks) = reference.row(i);
            let mut abs_sum = nalgebra::Matrix3::<f64>::zeros();
            for (&j, b) in cols.iter().zip(old_blocks) {
                if j != i {
                    abs_sum += b.abs();
                }
            }
            for ((&j, a), b) in cols.iter().zip(new_blocks).zip(old_blocks) {
                for r in 0..3 {
                    for c in 0..3 {
                        let bound = if j == i {
                            let m = if r == c { s.mass[i] } else { 0.0 };
                            2.0 * g * (b[(r, c)].abs() + m + abs_sum[(r, c)])
                        } else {
                            g * b[(r, c)].abs()
                        };
                        let diff = (a[(r, c)] - b[(r, c)]).abs();
                        assert!(
                            diff <= bound,
                            "geo {geo} block ({i}, {j}) [{r},{c}]: {diff:e} > {bound:e}"
                        );
                        changed = changed.max(b[(r, c)].abs());
                    }
                }
            }
        }
        assert!(changed > 0.0);
    }
}

/// A force model known only through block-sparse assembly (the trait's
/// default path, the side matrix): a stiff coupling between two nodes of
/// a mesh edge and a diagonal spring on each.
struct Coupler {
    i: usize,
    j: usize,
}

impl ForceModel for Coupler {
    fn add_forces(&mut self, _x: &[Vec3], _v: &[Vec3], _f: &mut [Vec3]) {}
    fn add_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        k: &mut BlockSparse,
        b: &mut BlockSparse,
    ) {
        let s = nalgebra::Matrix3::new(300.0, 10.0, 0.0, 10.0, 200.0, 5.0, 0.0, 5.0, 100.0);
        k.add_block(self.i, self.j, &s).unwrap();
        k.add_block(self.j, self.i, &s).unwrap();
        k.add_diagonal(self.i, &(-2.0 * s));
        k.add_diagonal(self.j, &(-2.0 * s));
        b.add_diagonal(self.i, &(-s * 0.01));
    }
}

/// Tissue, two contact-like rank-one terms and a side-matrix model: the
/// edge form's product equals the block-sparse product of the same matrix
/// (`to_block_sparse`) to rounding, `|Δy_i| ≤ 2 γ_T Σ_j |A_ij| |x_j|`
/// (each row a sum of at most `T` block products of 3 terms), with the
/// rank-one terms kept or sent to the side matrix; and the returned
/// `xᵀ(A − D)x` is that quadratic form.
#[test]
fn edge_product_equals_the_block_sparse_product() {
    let mut s = setup(true);
    let n = s.mass.len();
    let (a, b) = (s.pattern.row(40).0[0], 40);
    let (tri, tri2) = (s.triangles[100], s.triangles[101]);
    let k = Vec3::new(0.1, -0.99, 0.05).normalize();
    let w = common::perturbation(n, 0.003, 33);
    for capacity in [n, 0] {
        let mut scratch = JacobianScratch::new(&s.pattern);
        let mut edge = EdgeMatrix::new(&s.pattern, capacity);
        edge.begin(&s.mass);
        s.tissue
            .add_scaled_jacobians_edge(&s.x, &s.v, ALPHA, BETA, &mut edge, &mut scratch);
        edge.add_rank_one(tri, [0.2, 0.3, 0.5], &k, -4e3).unwrap();
        edge.add_rank_one(tri2, [0.6, 0.1, 0.3], &k, -1e3).unwrap();
        Coupler { i: a, j: b }.add_scaled_jacobians_edge(
            &s.x,
            &s.v,
            ALPHA,
            BETA,
            &mut edge,
            &mut scratch,
        );
        edge.finish();
        assert_eq!(edge.rank_one_terms().len(), capacity.min(2));
        assert!(edge.side().is_some());
        let reference = edge.to_block_sparse(&s.pattern).unwrap();
        let mut y_ref = vec![Vec3::zeros(); n];
        reference.mul_vec(&w, &mut y_ref);
        let mut y = vec![Vec3::zeros(); n];
        edge.mul_vec(&w, &mut y);
        // Rows of the side matrix, the edges and the rank-one terms: at
        // most three products per block.
        let g = 2.0 * gamma(3 * (terms(&s.pattern) + 6));
        for i in 0..n {
            let (cols, blocks) = reference.row(i);
            let mut bound = Vec3::zeros();
            for (&j, m) in cols.iter().zip(blocks) {
                bound += m.abs() * w[j].abs();
            }
            for r in 0..3 {
                assert!(
                    (y[i][r] - y_ref[i][r]).abs() <= g * bound[r],
                    "capacity {capacity}, row {i}: {} vs {}",
                    y[i][r],
                    y_ref[i][r]
                );
            }
        }
        // xᵀ(A − D)x against its definition from the product.
        let mut off = vec![Vec3::zeros(); n];
        let quad = edge.add_off_diagonal_product(&w, &mut off);
        let direct: f64 = w.iter().zip(&off).map(|(a, b)| a.dot(b)).sum();
        let scale: f64 = w.iter().zip(&off).map(|(a, b)| a.abs().dot(&b.abs())).sum();
        assert!((quad - direct).abs() <= 4.0 * gamma(3 * n) * scale);
    }
}

/// The fused PCG and the reference PCG solve the same system: both meet
/// the tolerance, in the same number of iterations (±1: rounding may move
/// a residual across the threshold), and their solutions differ by at
/// most what two solutions within the tolerance can: `|Δx| ≤ 2 tol |b| /
/// m_min` (with the compressed springs' geometric term off, `−αK − βB` is
/// positive semi-definite and `A ⪰ M ⪰ m_min I`).
#[test]
fn fused_pcg_solves_like_the_reference() {
    let mut s = setup(false);
    let (edge, reference) = both(&mut s);
    let n = s.mass.len();
    let rhs: Vec<Vec3> = common::perturbation(n, 1.0, 34);
    for preconditioner in [Preconditioner::BlockJacobi, Preconditioner::None] {
        let params = PcgParams {
            tol: 1e-8,
            max_iterations: 500,
            preconditioner,
        };
        let (mut x_ref, mut x_new) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        let a = Pcg::new(n).solve(&reference, &rhs, &mut x_ref, &s.fixed, &params);
        let b = EdgePcg::new(n).solve(&edge, &rhs, &mut x_new, &s.fixed, &params);
        assert!(a.converged && b.converged, "{a:?} {b:?}");
        assert!(a.iterations.abs_diff(b.iterations) <= 1, "{a:?} {b:?}");
        assert!(b.iterations > 5, "a real solve: {b:?}");
        let b_norm = rhs
            .iter()
            .zip(&s.fixed)
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
        for (x, &f) in x_new.iter().zip(&s.fixed) {
            assert!(!f || *x == Vec3::zeros());
        }
    }
}

/// 150 steps of a 0–12 N press at 2 Hz, with the default integrator, in
/// both forms: the trajectories agree. Each step's Newton stops at
/// `newton_tol` of its first residual, so each form's step is within
/// `newton_tol · |Δx₁|` of the exact implicit step (`|Δx₁|` the first
/// Newton update, at most the step's motion); two such steps differ by at
/// most twice that, and over the run (damped dynamics, no growth) the
/// sum of `2 newton_tol · max_i |x₁ − x₀|` over the steps bounds the gap.
#[test]
fn edge_form_trajectory_matches_the_reference() {
    let config = common::small_config(24, 11);
    let mut a = common::model(&config);
    let mut b = common::model(&config);
    b.set_system_form(SystemForm::BlockSparse);
    assert_eq!(a.system_form(), SystemForm::Edge);
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
    // Same Krylov iterates in exact arithmetic: the counts agree nearly always.
    assert!(same_counts >= steps * 9 / 10, "{same_counts} of {steps}");
    println!("largest gap {worst:e} m (bound {bound:e} m)");
}
