//! The stiffness solve's warm start checked without assembly (issue 18,
//! [`ThighModel::solve_stiffness_with_product`]): the assembly may be
//! skipped only when the warm start meets PCG's own stop test
//! `|S(b − A w̃)| ≤ tol |S b|` for `A = −K` at the current state, which is
//! what keeps the contact crate's bound `|k(w̃) − k*| ≤ tol |b| |S(w* − 1)|`.
//! The residuals here come from an independently assembled block-sparse
//! `K` ([`ThighModel::jacobians`]), neither the matrix-free product nor the
//! edge form.

use crate::common;

use echothigh_model::{
    BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, Kernels, NoExtraForce, SystemForm,
    ThighModel, Vec3,
};

/// `|S(b − A w)| / |S b|` with `A = −K` of the tissue assembled block-sparse.
fn relative_residual(m: &mut ThighModel, rhs: &[Vec3], w: &[Vec3]) -> f64 {
    let n = m.node_count();
    let (mut k, mut b) = (m.pattern().clone(), m.pattern().clone());
    m.jacobians(&mut NoExtraForce, &mut k, &mut b);
    let mut kw = vec![Vec3::zeros(); n];
    k.mul_vec(w, &mut kw);
    let (mut b2, mut r2) = (0.0, 0.0);
    for i in (0..n).filter(|&i| !m.fixed()[i]) {
        b2 += rhs[i].norm_squared();
        // b − A w = b + K w.
        r2 += (rhs[i] + kw[i]).norm_squared();
    }
    (r2 / b2).sqrt()
}

/// A press that ramps, holds and releases: some warm starts meet the test,
/// others must not. Each call is checked against the independent residual
/// of its warm start: the skip taken only if that residual meets the
/// tolerance (1e-9 relative slack for the two products' rounding), never
/// when it exceeds it, and every result meets the tolerance.
#[test]
fn the_assembly_is_skipped_only_when_the_warm_start_meets_the_tolerance() {
    for (form, kernels) in [
        (SystemForm::Edge, Kernels::Simd),
        (SystemForm::Edge, Kernels::Scalar),
        (SystemForm::BlockSparse, Kernels::Simd),
    ] {
        let mut m = common::model(&common::small_config(24, 11));
        m.set_system_form(form);
        m.set_kernels(kernels);
        check_skips(&mut m);
    }
}

/// Runs the press on `m` (see the test above).
fn check_skips(m: &mut ThighModel) {
    let tol = m.config().integrator.stiffness_tol;
    let n = m.node_count();
    let top = common::top_node(m);
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[top] = -m.mesh().rest_normals()[top] * 100.0;
    let (mut w, mut aw, mut kw) = (
        vec![Vec3::zeros(); n],
        vec![Vec3::zeros(); n],
        vec![Vec3::zeros(); n],
    );
    let (mut skipped, mut refused) = (0, 0);
    for i in 0..80 {
        let load = match i {
            0..=19 => 0.4 * i as f64,
            20..=59 => 8.0,
            _ => 0.0,
        };
        common::press_top(m, load);
        m.step(0.01, &mut NoExtraForce);
        let mut start = w.clone();
        for (s, &f) in start.iter_mut().zip(m.fixed()) {
            if f {
                *s = Vec3::zeros();
            }
        }
        let before = relative_residual(m, &rhs, &start);
        let s = m.solve_stiffness_with_product(&mut NoExtraForce, &rhs, &mut w, &mut aw);
        assert!(s.converged, "step {i}: {s:?}");
        let after = relative_residual(m, &rhs, &w);
        assert!(after <= tol * (1.0 + 1e-9), "step {i}: residual {after:e}");
        if m.stiffness_unassembled() {
            skipped += 1;
            assert!(
                before <= tol * (1.0 + 1e-9),
                "step {i}: skipped the assembly with a warm start at {before:e} > tol {tol:e}"
            );
            assert_eq!(w, start, "step {i}: a skip returns the warm start");
            assert_eq!(s.iterations, 0);
            assert!(
                (s.residual - before).abs() <= 1e-9 * tol,
                "step {i}: {s:?} vs {before:e}"
            );
            // The product handed back is A w at the current state.
            m.tissue_stiffness_product(&w, &mut kw);
            let scale = kw.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let gap = aw
                .iter()
                .zip(&kw)
                .map(|(a, k)| (a + k).norm())
                .fold(0.0, f64::max);
            assert!(gap <= 1e-12 * scale, "step {i}: |A w + K w| = {gap:e}");
        } else if before > tol * (1.0 + 1e-9) {
            refused += 1;
            assert!(s.iterations > 0, "step {i}: {s:?}");
        }
    }
    assert!(
        skipped > 10 && refused > 3,
        "{skipped} skips, {refused} refusals"
    );
}

/// A model that cannot multiply without assembling (the trait's default):
/// the stiffness solve must then always assemble.
struct Opaque;

impl ForceModel for Opaque {
    fn add_forces(&mut self, _x: &[Vec3], _v: &[Vec3], _f: &mut [Vec3]) {}
    fn add_jacobians(&mut self, _: &[Vec3], _: &[Vec3], _: &mut BlockSparse, _: &mut BlockSparse) {}
    fn add_scaled_jacobians_edge(
        &mut self,
        _: &[Vec3],
        _: &[Vec3],
        _: f64,
        _: f64,
        _: &mut EdgeMatrix,
        _: &mut JacobianScratch,
    ) {
    }
}

#[test]
fn a_model_without_a_matrix_free_product_is_always_assembled() {
    let mut m = common::model(&common::small_config(24, 11));
    common::press_top(&mut m, 8.0);
    for _ in 0..5 {
        m.step(0.01, &mut NoExtraForce);
    }
    let n = m.node_count();
    let top = common::top_node(&m);
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[top] = -m.mesh().rest_normals()[top];
    let (mut w, mut aw) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
    for pass in 0..4 {
        let s = m.solve_stiffness_with_product(&mut NoExtraForce, &rhs, &mut w, &mut aw);
        assert!(s.converged);
        // Pass 0 iterates, pass 1 meets the test assembled, then skips.
        assert_eq!(m.stiffness_unassembled(), pass >= 2, "pass {pass}");
    }
    for pass in 0..3 {
        let s = m.solve_stiffness_with_product(&mut Opaque, &rhs, &mut w, &mut aw);
        assert!(s.converged && s.iterations == 0, "pass {pass}: {s:?}");
        assert!(!m.stiffness_unassembled(), "pass {pass}");
    }
}
