//! The penalty contact's damper-onset cap (issue 18): Eq. 2's damper acts on
//! the penetration only (`ḋ ≤ d/h`), so the force on a sample entering
//! within a step rises continuously from zero, and the Jacobians of the
//! capped branch are the force's derivatives.
//!
//! The motion: every node of the default thigh at rest translated by `t`
//! towards the probe (`x = x₀ − t k̂`) in one backward-Euler step of
//! `h = 1 ms` from rest (`v = (x − x₀)/h`), the probe's face held `gap` above
//! the skin's top. Each face sample's depth is then `d_j = d₀_j + t` and its
//! rate `ḋ_j = t/h`: the first sample touches at `t* = −max_j d₀_j`, at the
//! rate `t*/h`.

use echothigh_contact::{ContactParams, PenaltyContact, Probe};
use echothigh_model::{BlockSparse, ForceModel, ModelConfig, ThighModel, Vec3};

const H: f64 = 1e-3;

/// The contact with the face `gap` (m) above the rest skin's top, its
/// surfaces found at rest for a step of `H`, and the rest positions.
fn setup(gap: f64) -> (ThighModel, PenaltyContact, Vec<Vec3>) {
    let model = ThighModel::new(&ModelConfig::default()).unwrap();
    let top = model.config().thigh.semi_axis_y;
    let mut contact = PenaltyContact::new(&model, Probe::default(), ContactParams::default());
    contact.set_probe(
        Probe::exam_pose(Vec3::new(0.0, top + gap, 0.0)),
        Vec3::zeros(),
    );
    let x0 = model.positions().to_vec();
    let v0 = vec![Vec3::zeros(); x0.len()];
    contact.prepare(&x0, &v0, H);
    (model, contact, x0)
}

/// Positions and velocities after the translation `t` (m) in one step.
fn moved(contact: &PenaltyContact, x0: &[Vec3], t: f64) -> (Vec<Vec3>, Vec<Vec3>) {
    let u = -contact.direction() * t;
    (x0.iter().map(|x| x + u).collect(), vec![u / H; x0.len()])
}

/// Total contact force on the tissue along `k̂` (N) at `(x, v)`.
fn force(contact: &mut PenaltyContact, x: &[Vec3], v: &[Vec3]) -> f64 {
    let mut f = vec![Vec3::zeros(); x.len()];
    contact.add_forces(x, v, &mut f);
    let k = contact.direction();
    f.iter().map(|f| f.dot(&k)).sum()
}

#[test]
fn the_force_of_an_entering_sample_rises_from_zero() {
    let gap = 1e-4;
    let (_, mut contact, x0) = setup(gap);
    let top = contact
        .sample_surfaces()
        .iter()
        .flatten()
        .map(|s| s.height)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(top.is_finite(), "surfaces under the face");
    let touch = -top;
    // The faceted surface lies at or below its highest node, the skin's top.
    assert!(touch >= gap - 1e-12, "first touch {touch} m, gap {gap} m");
    let eps = 1e-9;
    let (xa, va) = moved(&contact, &x0, touch - eps);
    let (xb, vb) = moved(&contact, &x0, touch + eps);
    let before = force(&mut contact, &xa, &va);
    let after = force(&mut contact, &xb, &vb);
    assert_eq!(before, 0.0, "no sample penetrates before the touch");
    // Continuous onset: each sample entering within ±ε of t* (at most all
    // of them) carries at most a_j (λ_c + μ_c/h) · 2ε. Eq. 2's damper
    // alone would push each with a_j μ_c t*/h ≈ 8e-3 N at the touch (a_j =
    // 4e-6 m², μ_c = 2e4 N·s/m³, t* = 0.1 mm, h = 1 ms), 1e3 times more than
    // the whole face's bound here (100 samples: 5.6e-5 N).
    let (samples, area) = contact.samples();
    let p = contact.params();
    let bound = samples.len() as f64 * area * (p.stiffness + p.damping / H) * 2.0 * eps;
    assert!(
        after <= bound,
        "force {after:e} N just after the touch (continuous onset: ≤ {bound:e} N)"
    );
}

/// Per node along `k̂`: `(A u)_m · k̂` for `A` the matrix and `u = −k̂` on
/// every node.
fn along_k(a: &BlockSparse, k: &Vec3, n: usize) -> Vec<f64> {
    let u = vec![-k; n];
    let mut y = vec![Vec3::zeros(); n];
    a.mul_vec(&u, &mut y);
    y.iter().map(|y| y.dot(k)).collect()
}

/// `∂F/∂x` and `∂F/∂v` against central differences of the force, moving
/// the positions only and the velocities only, with entering samples in the
/// capped branch (`∂F/∂v = 0` there, `∂F/∂x` with `λ_c + μ_c/h`) and
/// penetrating ones outside it. The force is piecewise linear in `x` and in
/// `v` (lagged geometry) and no sample changes branch within ±ε (checked),
/// so the difference is exact up to rounding: each node's force, ≤ a few N,
/// carries ~1e-16 of it, divided by 2ε = 2e-8 m (or 2e-5 m/s): ≤ 1e-7 N/m,
/// against entries of a_j (λ_c + μ_c/h) ≈ 280 N/m per sample.
#[test]
fn the_capped_branch_jacobians_are_the_force_derivatives() {
    let (model, mut contact, x0) = setup(1e-4);
    let k = contact.direction();
    let n = x0.len();
    // The nodes 0.3 mm towards the face (0.1 mm above the skin's top), having
    // moved 0.1 mm in the step: the step started 0.2 mm towards the face, so
    // the samples within ~4 mm of the crest penetrated at its start (their
    // skin drops less than 0.1 mm there; uncapped, damped) and those out to
    // ~5.6 mm entered within it (capped).
    let (x, _) = moved(&contact, &x0, 3e-4);
    let (_, v) = moved(&contact, &x0, 1e-4);
    let (mut kmat, mut bmat) = (model.pattern().clone(), model.pattern().clone());
    contact.add_jacobians(&x, &v, &mut kmat, &mut bmat);
    let (kx, bv) = (along_k(&kmat, &k, n), along_k(&bmat, &k, n));
    let branches = |contact: &PenaltyContact, x: &[Vec3], v: &[Vec3]| {
        let (mut capped, mut damped) = (0, 0);
        for s in contact.sample_surfaces().iter().flatten() {
            if let Some(c) = contact.sample_contact(s, x, v) {
                capped += usize::from(c.onset);
                damped += usize::from(!c.onset && !c.clamped);
            }
        }
        (capped, damped)
    };
    let (capped, damped) = branches(&contact, &x, &v);
    assert!(capped > 0 && damped > 0, "{capped} capped, {damped} damped");
    let per_node = |contact: &mut PenaltyContact, x: &[Vec3], v: &[Vec3]| {
        let mut f = vec![Vec3::zeros(); n];
        contact.add_forces(x, v, &mut f);
        f.iter().map(|f| f.dot(&k)).collect::<Vec<f64>>()
    };
    for (eps, moving_x) in [(1e-8, true), (1e-5, false)] {
        let shift = |y: &[Vec3], s: f64| y.iter().map(|p| p - k * s).collect::<Vec<_>>();
        for sign in [1.0, -1.0] {
            let (xs, vs) = if moving_x {
                (shift(&x, sign * eps), v.clone())
            } else {
                (x.clone(), shift(&v, sign * eps))
            };
            assert_eq!(
                branches(&contact, &xs, &vs),
                (capped, damped),
                "a sample changed branch within ±ε"
            );
        }
        let (fp, fm) = if moving_x {
            (
                per_node(&mut contact, &shift(&x, eps), &v),
                per_node(&mut contact, &shift(&x, -eps), &v),
            )
        } else {
            (
                per_node(&mut contact, &x, &shift(&v, eps)),
                per_node(&mut contact, &x, &shift(&v, -eps)),
            )
        };
        let exact = if moving_x { &kx } else { &bv };
        for m in 0..n {
            let fd = (fp[m] - fm[m]) / (2.0 * eps);
            assert!(
                (fd - exact[m]).abs() <= 1e-6 * (1.0 + exact[m].abs()),
                "node {m}, {}: difference {fd} N/m, Jacobian {} N/m",
                if moving_x { "∂F/∂x" } else { "∂F/∂v" },
                exact[m]
            );
        }
    }
}
