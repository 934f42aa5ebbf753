//! Static equilibrium under a constant nodal load: the implicit integrator
//! (PCG inside) settles on the solution of `K Δx = f` computed with faer's
//! sparse Cholesky (Newton iterations on the static residual, each a
//! Cholesky solve of the assembled −K on the free nodes).

use crate::common;

use echothigh_model::{NoExtraForce, ThighModel, Vec3};
use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

/// One static Newton update with faer: solves `(−K) Δx = F` on the free nodes.
fn cholesky_update(m: &mut ThighModel) -> f64 {
    let n = m.node_count();
    let free: Vec<usize> = (0..n).filter(|&i| !m.fixed()[i]).collect();
    let mut slot = vec![usize::MAX; n];
    for (s, &i) in free.iter().enumerate() {
        slot[i] = s;
    }
    let mut k = m.pattern().clone();
    let mut b = m.pattern().clone();
    m.jacobians(&mut NoExtraForce, &mut k, &mut b);
    let mut triplets = Vec::new();
    for &i in &free {
        let (cols, blocks) = k.row(i);
        for (&j, blk) in cols.iter().zip(blocks) {
            if slot[j] == usize::MAX {
                continue;
            }
            for r in 0..3 {
                for c in 0..3 {
                    triplets.push(Triplet::new(3 * slot[i] + r, 3 * slot[j] + c, -blk[(r, c)]));
                }
            }
        }
    }
    let dim = 3 * free.len();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(dim, dim, &triplets)
        .expect("valid triplets");
    let llt = a.sp_cholesky(faer::Side::Lower).expect("−K is SPD");
    let mut f = vec![Vec3::zeros(); n];
    m.forces(&mut NoExtraForce, &mut f);
    let rhs = Mat::<f64>::from_fn(dim, 1, |r, _| f[free[r / 3]][r % 3]);
    let dx = llt.solve(&rhs);
    let mut x = m.positions().to_vec();
    for (s, &i) in free.iter().enumerate() {
        for c in 0..3 {
            x[i][c] += dx[(3 * s + c, 0)];
        }
    }
    let v = vec![Vec3::zeros(); n];
    m.set_state(&x, &v);
    free.iter()
        .map(|&i| f[i].norm_squared())
        .sum::<f64>()
        .sqrt()
}

#[test]
fn settles_on_the_sparse_cholesky_equilibrium() {
    // On the elliptic cylinder and on the patient's leg (issue 12).
    for leg in [false, true] {
        settles(leg);
    }
}

fn settles(leg: bool) {
    let mut config = common::small_config_on(16, 7, leg);
    config.integrator.cg_tol = 1e-12;
    config.integrator.newton_tol = 1e-10;
    config.integrator.newton_floor = 1e-16;
    // The reference Newton uses the same SPD tangent (compressed springs'
    // geometric term dropped: with it −K is indefinite under this load);
    // the residual is exact, so it converges (linearly) to the equilibrium.
    let ref_config = config.clone();

    let load = 15.0; // N on three nodes: several mm, in the nonlinear range
    let mut reference = common::model(&ref_config);
    common::press_top(&mut reference, load);
    let mut residual = f64::INFINITY;
    for _ in 0..500 {
        residual = cholesky_update(&mut reference);
        if residual < 1e-13 {
            break;
        }
    }
    assert!(
        residual < 1e-11,
        "static Newton did not converge: {residual}"
    );

    let mut dynamic = common::model(&config);
    common::press_top(&mut dynamic, load);
    for _ in 0..600 {
        let s = dynamic.step(0.05, &mut NoExtraForce);
        assert!(s.finite);
    }
    let rest = dynamic.rest_positions();
    let disp_ref: f64 = reference
        .positions()
        .iter()
        .zip(rest)
        .map(|(x, r)| (x - r).norm_squared())
        .sum::<f64>()
        .sqrt();
    let diff: f64 = reference
        .positions()
        .iter()
        .zip(dynamic.positions())
        .map(|(a, b)| (a - b).norm_squared())
        .sum::<f64>()
        .sqrt();
    let top = common::top_node(&dynamic);
    let depth = (rest[top] - dynamic.positions()[top]).norm();
    assert!(depth > 0.004, "load too small to be nonlinear: {depth} m");
    assert!(
        diff < 1e-6 * disp_ref,
        "relative difference {}",
        diff / disp_ref
    );
}

/// `solve_stiffness` gives the quasi-static compliance: the displacement
/// under a small extra load `ε n` at equilibrium, divided by ε.
#[test]
fn solve_stiffness_matches_the_static_response_to_a_small_load() {
    for leg in [false, true] {
        compliance_matches(leg);
    }
}

fn compliance_matches(leg: bool) {
    let mut config = common::small_config_on(16, 7, leg);
    // On the leg the layer is thicker than the reference (λ ≈ 1.6 at the
    // top node) and its shear tie softer by 1/λ, so the compressed springs'
    // geometric stiffness |f|/l, which the default tangent omits, is ~3 % of
    // the transverse support there (|f| ≈ 2 N, l ≈ 0.06 m, k_t A / λ ≈
    // 1e3 N/m): past this test's 2 %. With the term kept the tangent is the
    // exact Jacobian, which is what this test checks on the leg.
    config.integrator.geometric_stiffness_in_compression = leg;
    config.integrator.cg_tol = 1e-12;
    config.integrator.newton_tol = 1e-12;
    config.integrator.newton_floor = 1e-16;
    let mut m = common::model(&config);
    common::press_top(&mut m, 6.0); // a pre-loaded (stiffened) state
    for _ in 0..40 {
        m.step(1.0, &mut NoExtraForce); // h = 1 s: backward Euler ≈ static Newton
    }
    let n = m.node_count();
    let top = common::top_node(&m);
    let normal = m.mesh().rest_normals()[top];
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[top] = -normal; // 1 N inward
    let mut compliance = vec![Vec3::zeros(); n];
    let s = m.solve_stiffness(&mut NoExtraForce, &rhs, &mut compliance);
    assert!(s.converged && !s.indefinite, "{s:?}");
    let before = m.positions().to_vec();
    let eps = 1e-3; // N
    m.external_forces_mut()[top] -= normal * eps;
    for _ in 0..40 {
        m.step(1.0, &mut NoExtraForce);
    }
    let mut worst: f64 = 0.0;
    let scale = compliance.iter().map(|c| c.norm()).fold(0.0, f64::max);
    for i in 0..n {
        let fd = (m.positions()[i] - before[i]) / eps;
        worst = worst.max((fd - compliance[i]).norm());
    }
    // The tangent omits compressed springs' geometric terms: a small model error.
    assert!(worst < 0.02 * scale, "compliance error {worst} vs {scale}");
    // Local stiffness k = 1 / (nᵀ (−K)⁻¹ n) is positive and sensible (N/m).
    let k = 1.0 / (-normal).dot(&compliance[top]);
    assert!(k > 100.0 && k < 1e5, "{k}");
}

/// Regression (issue 16): an absolute position tolerance (1e-6 m) judged
/// before any solve let a step end wherever the residual force fell below
/// `1e-6 m · m_i / h²` ≈ 1.4e-5 N per node on the default mesh, 14 % of
/// this load, and a load under that never moved its node at all. On the
/// shipped defaults the node must settle on the static displacement that
/// faer's Cholesky gives.
#[test]
fn small_load_moves_its_node_by_the_static_amount_on_the_shipped_defaults() {
    let config = echothigh_model::ModelConfig::default();
    let mut dynamic = common::model(&config);
    let top = common::top_node(&dynamic);
    let load = 1e-4; // N, inward along the rest normal
    let normal = dynamic.mesh().rest_normals()[top];
    dynamic.external_forces_mut()[top] = -normal * load;
    let mut reference = dynamic.clone();
    // Converged to 1e-8 of the load: the reference is then within
    // 1e-12 N / k_min ≈ 2e-14 m of the equilibrium (k_min below), far under
    // the tolerance; the forces' own rounding is ≈ 5e-14 N.
    let mut residual = f64::INFINITY;
    for _ in 0..20 {
        residual = cholesky_update(&mut reference);
        if residual < 1e-8 * load {
            break;
        }
    }
    assert!(
        residual < 1e-8 * load,
        "static Newton did not converge: {residual} N"
    );

    // Every node's time constant (damper over spring, ≤ ~10 ms at the
    // defaults) is far under the 3 s simulated.
    let h = config.integrator.time_step;
    for _ in 0..300 {
        assert!(dynamic.step(h, &mut NoExtraForce).finite);
    }
    let rest = dynamic.rest_positions()[top];
    let u_ref = (reference.positions()[top] - rest).dot(&-normal);
    let u = (dynamic.positions()[top] - rest).dot(&-normal);

    // What the floor lets through: a step may stop where every free node's
    // residual is below `floor · max|x|∞ · m_i / h²` (N, per component), a
    // force of norm ≤ √(3 n) times the largest; −K at rest is ≥ the
    // smallest node's normal or tangential spring (the membrane's part is
    // semi-definite at rest), so the position error is ≤ that norm over it.
    let ip = &config.integrator;
    let tp = &config.tissue;
    let free: Vec<usize> = (0..dynamic.node_count())
        .filter(|&i| !dynamic.fixed()[i])
        .collect();
    let size = dynamic
        .rest_positions()
        .iter()
        .map(|x| x.amax())
        .fold(0.0, f64::max);
    let m_max = free
        .iter()
        .map(|&i| dynamic.masses()[i])
        .fold(0.0, f64::max);
    let force = (3.0 * free.len() as f64).sqrt() * ip.newton_floor * size * m_max / (h * h);
    let k_min = free
        .iter()
        .map(|&i| dynamic.mesh().areas()[i] * (1.0 / tp.normal_b).min(tp.tangential_stiffness))
        .fold(f64::INFINITY, f64::min);
    let tol = force / k_min;
    assert!(
        tol < 1e-2 * u_ref,
        "the bound {tol} m must resolve {u_ref} m"
    );
    assert!(
        (u - u_ref).abs() <= tol,
        "moved {u} m, static {u_ref} m, tolerance {tol} m"
    );
}

/// `solve_stiffness_with_product` returns `A w` of the system it solved:
/// with no extra model `A = −K` of the tissue, so the product must equal
/// the matrix-free `−K w` ([`ThighModel::tissue_stiffness_product`]) to
/// rounding, in every matrix form and kernel, both after an iterating
/// solve and after one whose warm start already met the tolerance (the
/// SIMD kernels then hand back the solve's start product). Rounding bound:
/// each of the ~10 terms of a row is a product of a spring's stiffness and
/// `|w|`, so the two sums differ by a few `ε · Σ|terms|` ≤ `1e-12 · |K|·|w|`.
#[test]
fn stiffness_solution_product_equals_the_matrix_free_product() {
    use echothigh_model::{Kernels, SystemForm};
    for (form, kernels) in [
        (SystemForm::Edge, Kernels::Simd),
        (SystemForm::Edge, Kernels::Scalar),
        (SystemForm::BlockSparse, Kernels::Simd),
    ] {
        let mut m = common::model(&common::small_config(24, 11));
        m.set_system_form(form);
        m.set_kernels(kernels);
        common::press_top(&mut m, 8.0);
        for _ in 0..5 {
            m.step(0.01, &mut NoExtraForce);
        }
        let n = m.node_count();
        let top = common::top_node(&m);
        let mut rhs = vec![Vec3::zeros(); n];
        rhs[top] = -m.mesh().rest_normals()[top];
        let mut w = vec![Vec3::zeros(); n];
        let (mut aw, mut kw) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        for pass in 0..2 {
            // Pass 0 iterates from zero; pass 1 starts at the solution.
            let s = m.solve_stiffness_with_product(&mut NoExtraForce, &rhs, &mut w, &mut aw);
            assert!(s.converged, "{form:?} {kernels:?}: {s:?}");
            assert_eq!(s.iterations == 0, pass == 1, "{form:?} {kernels:?}: {s:?}");
            m.tissue_stiffness_product(&w, &mut kw);
            let scale = kw.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let gap = aw
                .iter()
                .zip(&kw)
                .map(|(a, k)| (a + k).norm())
                .fold(0.0, f64::max);
            assert!(
                gap <= 1e-12 * scale,
                "{form:?} {kernels:?} pass {pass}: |A w + K w| = {gap:e}, |K w| = {scale:e}"
            );
        }
    }
}
