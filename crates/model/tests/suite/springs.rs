//! The spring laws (paper §3) and their Jacobians against finite differences.

use crate::common;

use echothigh_model::springs::{
    damper_force, damper_jacobian, linear_force, normal_energy, normal_force, normal_stiffness,
    spring_force, spring_force_jacobian,
};
use echothigh_model::{NoExtraForce, Vec3};
use nalgebra::Matrix3;

/// Central-difference Jacobian `∂f_i/∂x_j` of `force(xj)` (3×3).
fn fd_jacobian(force: impl Fn(&Vec3) -> Vec3, xj: &Vec3, step: f64) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for c in 0..3 {
        let mut p = *xj;
        let mut m = *xj;
        p[c] += step;
        m[c] -= step;
        j.set_column(c, &((force(&p) - force(&m)) / (2.0 * step)));
    }
    j
}

fn rel_err(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (a - b).norm() / b.norm().max(1e-300)
}

#[test]
fn linear_spring_force_and_jacobian_match_finite_differences() {
    let (a, rest) = (350.0, 0.012);
    let xi = Vec3::new(0.001, -0.002, 0.003);
    let xj = Vec3::new(0.0152, 0.0031, -0.0024); // stretched, off-axis
    let law = |e: f64| (linear_force(a, e), a);
    let (f, s) = spring_force_jacobian(&xi, &xj, rest, law, true);
    // Force: a (l − L₀) along d.
    let l = (xj - xi).norm();
    assert!((f - (xj - xi) / l * a * (l - rest)).norm() < 1e-12);
    let fd = fd_jacobian(|x| spring_force(&xi, x, rest, |e| a * e), &xj, 1e-7);
    let err = rel_err(&s, &fd);
    assert!(err < 1e-6, "relative error {err}");
    // Compressed spring too (geometric term negative).
    let xc = xi + (xj - xi) * 0.5;
    let (_, sc) = spring_force_jacobian(&xi, &xc, rest, law, true);
    let fdc = fd_jacobian(|x| spring_force(&xi, x, rest, |e| a * e), &xc, 1e-7);
    assert!(rel_err(&sc, &fdc) < 1e-6, "{}", rel_err(&sc, &fdc));
}

#[test]
fn normal_spring_force_and_jacobian_match_finite_differences() {
    // Per-node values of the default tissue for a 1.4e-4 m² node.
    let area = 1.4e-4;
    let (a, b) = (5.0e-5 / area, 1.5e-6 / area);
    let rest = 0.040;
    let anchor = Vec3::new(0.0, 0.030, 0.0);
    // Compressed by 20 mm (2/3 of the 30 mm asymptote), slightly tilted.
    let x = anchor + Vec3::new(0.003, 0.0198, -0.001);
    let law = |e: f64| (normal_force(a, b, e), normal_stiffness(a, b, e));
    let (f, s) = spring_force_jacobian(&x, &anchor, rest, law, true);
    let fd = fd_jacobian(
        |y| spring_force(&x, y, rest, |e| normal_force(a, b, e)),
        &anchor,
        1e-8,
    );
    let err = rel_err(&s, &fd);
    assert!(err < 1e-6, "relative error {err}");
    // Compression pushes the node away from the anchor: f_i points from anchor to node.
    assert!(f.dot(&(x - anchor)) > 0.0);
    // Scalar law: derivative and energy by finite differences.
    for e in [-0.025, -0.01, 0.0, 0.004] {
        let step = 1e-7;
        let df = (normal_force(a, b, e + step) - normal_force(a, b, e - step)) / (2.0 * step);
        assert!((df - normal_stiffness(a, b, e)).abs() < 1e-6 * df.abs());
        let de = (normal_energy(a, b, e + step) - normal_energy(a, b, e - step)) / (2.0 * step);
        let fe = normal_force(a, b, e);
        assert!(
            (de - fe).abs() < 1e-6 * fe.abs().max(1e-3),
            "e={e}: {de} vs {fe}"
        );
    }
    // Stiffening: the force grows without bound towards the asymptote b/a.
    let asym = b / a;
    assert!(
        normal_force(a, b, -0.999 * asym).abs() > 100.0 * normal_force(a, b, -0.5 * asym).abs()
    );
}

#[test]
fn damper_force_and_jacobian_are_consistent() {
    let xi = Vec3::new(0.0, 0.0, 0.0);
    let xj = Vec3::new(0.01, 0.005, 0.0);
    let (vi, vj) = (Vec3::new(0.1, -0.2, 0.3), Vec3::new(-0.05, 0.1, 0.2));
    let c = 0.7;
    let f = damper_force(&xi, &xj, &vi, &vj, c);
    // Linear in v: f = B_ij (v_j − v_i).
    let b = damper_jacobian(&xi, &xj, c);
    assert!((f - b * (vj - vi)).norm() < 1e-14);
    // Dissipative: power on the pair ≤ 0.
    assert!(f.dot(&vi) - f.dot(&vj) <= 0.0);
}

/// The assembled tissue K = ∂F/∂x of a whole deformed mesh against finite
/// differences of the assembled force (exact tangent: geometric terms kept).
#[test]
fn assembled_tissue_stiffness_matches_finite_differences() {
    let mut config = common::small_config(8, 4);
    config.integrator.geometric_stiffness_in_compression = true;
    let mut m = common::model(&config);
    let n = m.node_count();
    let x: Vec<Vec3> = m
        .rest_positions()
        .iter()
        .zip(common::perturbation(n, 0.004, 7))
        .map(|(x, d)| x + d)
        .collect();
    let v = vec![Vec3::zeros(); n];
    m.set_state(&x, &v);
    let mut k = m.pattern().clone();
    let mut b = m.pattern().clone();
    m.jacobians(&mut NoExtraForce, &mut k, &mut b);
    let dense = k.to_dense();
    let free: Vec<usize> = (0..n).filter(|&i| !m.fixed()[i]).collect();
    let mut f_plus = vec![Vec3::zeros(); n];
    let mut f_minus = vec![Vec3::zeros(); n];
    let step = 1e-7;
    let mut max_err: f64 = 0.0;
    for &j in &free {
        for c in 0..3 {
            let mut xp = x.clone();
            xp[j][c] += step;
            m.set_state(&xp, &v);
            m.forces(&mut NoExtraForce, &mut f_plus);
            xp[j][c] -= 2.0 * step;
            m.set_state(&xp, &v);
            m.forces(&mut NoExtraForce, &mut f_minus);
            for &i in &free {
                for r in 0..3 {
                    let fd = (f_plus[i][r] - f_minus[i][r]) / (2.0 * step);
                    let an = dense[(3 * i + r, 3 * j + c)];
                    max_err = max_err.max((fd - an).abs());
                }
            }
        }
    }
    let scale = dense.amax();
    assert!(
        max_err < 1e-6 * scale,
        "max abs error {max_err} vs scale {scale}"
    );
    // Symmetric.
    assert!((&dense - dense.transpose()).amax() < 1e-9 * scale);
}

/// The tissue's direct assembly of `α K + β B` (one block per spring) equals
/// the separate assembly of `K` and `B` combined.
#[test]
fn direct_scaled_assembly_matches_separate_jacobians() {
    use echothigh_model::{
        BlockSparse, ForceModel, JacobianScratch, SurfaceMesh, TissueForces, TissueParams,
    };
    let config = common::small_config(10, 5);
    let mesh = SurfaceMesh::new(&config.thigh).unwrap();
    let pattern = BlockSparse::from_pairs(mesh.node_count(), mesh.coupled_pairs());
    let n = mesh.node_count();
    let x: Vec<Vec3> = mesh
        .rest_positions()
        .iter()
        .zip(common::perturbation(n, 0.005, 21))
        .map(|(x, d)| x + d)
        .collect();
    let v = common::perturbation(n, 0.2, 22);
    for geo in [false, true] {
        let mut tissue = TissueForces::new(&mesh, &TissueParams::default(), &pattern, 0.05, geo);
        let (alpha, beta) = (-1.3e-4, -0.011);
        let mut scratch = JacobianScratch::new(&pattern);
        let mut direct = pattern.clone();
        tissue.add_scaled_jacobians(&x, &v, alpha, beta, &mut direct, &mut scratch);
        let (mut k, mut b) = (pattern.clone(), pattern.clone());
        tissue.add_jacobians(&x, &v, &mut k, &mut b);
        let mut combined = pattern.clone();
        combined.add_scaled(alpha, &k, beta, &b);
        let diff = (direct.to_dense() - combined.to_dense()).amax();
        assert!(
            diff < 1e-12 * combined.to_dense().amax(),
            "geo {geo}: {diff}"
        );
    }
}

/// A pressed, perturbed state at rest (v = 0) and a direction `w` (m) zero
/// on the held nodes.
fn pressed_state(
    config: &echothigh_model::ModelConfig,
) -> (echothigh_model::ThighModel, Vec<Vec3>) {
    let mut m = common::model(config);
    common::press_top(&mut m, 8.0);
    for _ in 0..20 {
        m.step(0.01, &mut NoExtraForce);
    }
    let n = m.node_count();
    let x: Vec<Vec3> = m
        .positions()
        .iter()
        .zip(common::perturbation(n, 0.002, 31))
        .map(|(x, d)| x + d)
        .collect();
    m.set_state(&x, &vec![Vec3::zeros(); n]);
    let mut w = common::perturbation(n, 1.0, 32);
    for (wi, &f) in w.iter_mut().zip(m.fixed()) {
        if f {
            *wi = Vec3::zeros();
        }
    }
    (m, w)
}

/// The matrix-free `K w` equals the assembled `K` times `w` to rounding, with
/// and without the compressed springs' geometric term.
#[test]
fn matrix_free_stiffness_product_matches_the_assembled_matrix() {
    for geo in [false, true] {
        let mut config = common::small_config(16, 7);
        config.integrator.geometric_stiffness_in_compression = geo;
        let (mut m, w) = pressed_state(&config);
        let n = m.node_count();
        let mut free_product = vec![Vec3::zeros(); n];
        m.tissue_stiffness_product(&w, &mut free_product);
        let (mut k, mut b) = (m.pattern().clone(), m.pattern().clone());
        m.jacobians(&mut NoExtraForce, &mut k, &mut b);
        let mut assembled = vec![Vec3::zeros(); n];
        k.mul_vec(&w, &mut assembled);
        // Each entry of either product is a sum of ≤ 52 rounded terms (13
        // blocks of a row × 3 columns, and the ≤ 13 springs accumulated in a
        // diagonal block), each ≤ |K|∞ |w|∞ in the row's sum: the two differ
        // by at most 2 γ₅₂ ‖K‖∞ ‖w‖∞ (Higham, Accuracy and Stability, §3.1).
        let dense = k.to_dense();
        let norm_k = (0..dense.nrows())
            .map(|r| dense.row(r).iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let norm_w = w.iter().map(|v| v.amax()).fold(0.0, f64::max);
        let gamma = 52.0 * f64::EPSILON / (1.0 - 52.0 * f64::EPSILON);
        let tol = 2.0 * gamma * norm_k * norm_w;
        let diff = free_product
            .iter()
            .zip(&assembled)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        assert!(diff <= tol, "geo {geo}: {diff} N > {tol} N");
        assert!(norm_k * norm_w > 0.0);
    }
}

/// The matrix-free `K w` is the directional derivative of the force: central
/// differences `(F(x + εw) − F(x − εw)) / 2ε` (exact tangent: geometric
/// terms kept; v = 0, so the dampers' ∂F/∂x, omitted from K, vanish).
#[test]
fn matrix_free_stiffness_product_matches_finite_differences() {
    let mut config = common::small_config(16, 7);
    config.integrator.geometric_stiffness_in_compression = true;
    let (mut m, w) = pressed_state(&config);
    let n = m.node_count();
    let x = m.positions().to_vec();
    let v = vec![Vec3::zeros(); n];
    let mut product = vec![Vec3::zeros(); n];
    m.tissue_stiffness_product(&w, &mut product);
    let eps = 1e-7; // m along a direction of max-norm ≤ 1
    let shifted = |s: f64| -> Vec<Vec3> { x.iter().zip(&w).map(|(x, w)| x + w * s).collect() };
    let (mut f_plus, mut f_minus) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
    m.set_state(&shifted(eps), &v);
    m.forces(&mut NoExtraForce, &mut f_plus);
    m.set_state(&shifted(-eps), &v);
    m.forces(&mut NoExtraForce, &mut f_minus);
    let scale = product.iter().map(|p| p.amax()).fold(0.0, f64::max);
    let err = product
        .iter()
        .zip(f_plus.iter().zip(&f_minus))
        .map(|(p, (a, b))| (p - (a - b) / (2.0 * eps)).amax())
        .fold(0.0, f64::max);
    // Truncation ε² |F'''| / 6 is ~1e-14 of |K w| here; rounding of the
    // forces (|F| ≲ 10 N, ε_mach |F| / ε ≈ 2e-8 N) against |K w| ≳ 1e2 N
    // leaves ~1e-10 relative: 1e-6 is the same bound as the assembled test.
    assert!(err < 1e-6 * scale, "max error {err} N vs |K w| {scale} N");
}
