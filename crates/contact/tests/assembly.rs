//! The contact models' direct scaled-Jacobian assembly (issue 16: without
//! it every Newton iteration assembled the whole pattern twice) against the
//! separate assembly of `K` and `B` it replaces, and the matrix-free local
//! stiffness against the assembled tissue matrix.

use echothigh_contact::{
    ContactParams, ContactSet, ContactSpring, LocalStiffness, Probe, ProbeContact,
};
use echothigh_model::{
    BlockSparse, ForceModel, JacobianScratch, ModelConfig, NoExtraForce, ThighModel, Vec3,
};

/// The default thigh pressed 10 mm by the probe at its top, and the contact.
fn pressed() -> (ThighModel, ProbeContact) {
    let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let top = model.config().thigh.semi_axis_y;
    for i in 1..=20 {
        let depth = 0.010 * f64::from(i) / 20.0;
        let pose = Probe::exam_pose(Vec3::new(0.0, top - depth, 0.0));
        assert!(pc.advance(&mut model, &pose, 0.01).0.finite);
    }
    (model, pc)
}

/// `|fl(a₀ + Σ αt_j + βu_j) − (a₀ + α fl(Σ t_j) + β fl(Σ u_j))|`: both
/// are sums of at most `terms + 3` rounded terms, so they differ entry by
/// entry by at most `2 γ_{terms+3} (|a₀| + |α||K| + |β||B|)` (Higham §3.1);
/// the terms of one entry share a sign (`k̂k̂ᵀ` times non-negative weights),
/// so `|K|` and `|B|` are the sums of their magnitudes.
fn assert_same_to_rounding(
    direct: &BlockSparse,
    old: &BlockSparse,
    start: &BlockSparse,
    (alpha, k): (f64, &BlockSparse),
    (beta, b): (f64, &BlockSparse),
    terms: usize,
) {
    let t = (terms + 3) as f64;
    let gamma = t * f64::EPSILON / (1.0 - t * f64::EPSILON);
    let (d, o, s, kd, bd) = (
        direct.to_dense(),
        old.to_dense(),
        start.to_dense(),
        k.to_dense(),
        b.to_dense(),
    );
    let mut worst: f64 = 0.0;
    for i in 0..d.len() {
        let bound =
            2.0 * gamma * (s[i].abs() + alpha.abs() * kd[i].abs() + beta.abs() * bd[i].abs());
        assert!(
            (d[i] - o[i]).abs() <= bound,
            "entry {i}: {} vs {} (bound {bound})",
            d[i],
            o[i]
        );
        worst = worst.max((d[i] - s[i]).abs());
    }
    assert!(worst > 0.0, "the contact must have added something");
}

#[test]
fn penalty_contact_direct_assembly_equals_the_separate_jacobians() {
    let (model, mut pc) = pressed();
    let (x, v) = (model.positions().to_vec(), model.velocities().to_vec());
    let contact = pc.contact_mut();
    contact.prepare(&x, &v, 0.01);
    let samples = contact.sample_surfaces().iter().flatten().count();
    assert!(samples > 0);
    // A start with the tissue in it, as in a Newton iteration.
    let mut start = model.pattern().clone();
    start.add_to_diagonal(model.masses());
    let mut scratch = JacobianScratch::new(model.pattern());
    let (alpha, beta) = (-1e-4, -1e-2); // −λ²h², −λh at h = 10 ms
    let mut direct = start.clone();
    contact.add_scaled_jacobians(&x, &v, alpha, beta, &mut direct, &mut scratch);
    let (mut k, mut b) = (model.pattern().clone(), model.pattern().clone());
    contact.add_jacobians(&x, &v, &mut k, &mut b);
    let mut old = start.clone();
    old.add_scaled(alpha, &k, beta, &b);
    assert_same_to_rounding(&direct, &old, &start, (alpha, &k), (beta, &b), samples);
}

#[test]
fn contact_set_direct_assembly_equals_the_separate_jacobians() {
    let (model, mut pc) = pressed();
    let (x, v) = (model.positions().to_vec(), model.velocities().to_vec());
    let mut set = contact_set(&model, &mut pc);
    assert!(!set.springs.is_empty());
    let start = model.pattern().clone();
    let mut scratch = JacobianScratch::new(model.pattern());
    let mut direct = start.clone();
    set.add_scaled_jacobians(&x, &v, -1.0, 0.0, &mut direct, &mut scratch);
    let (mut k, mut b) = (model.pattern().clone(), model.pattern().clone());
    set.add_jacobians(&x, &v, &mut k, &mut b);
    let mut old = start.clone();
    old.add_scaled(-1.0, &k, 0.0, &b);
    let n = set.springs.len();
    assert_same_to_rounding(&direct, &old, &start, (-1.0, &k), (0.0, &b), n);
}

/// The contact springs of the probe's current contact.
fn contact_set(model: &ThighModel, pc: &mut ProbeContact) -> ContactSet {
    let (x, v) = (model.positions(), model.velocities());
    let contact = pc.contact_mut();
    contact.prepare(x, v, 0.0);
    let mut set = ContactSet::with_capacity(model.node_count());
    set.reset(contact.direction());
    let c = contact.params().stiffness * contact.samples().1;
    contact.for_each_contact(x, v, |s, _| {
        set.springs.push(ContactSpring {
            nodes: s.nodes,
            beta: s.beta,
            blocks: *contact.triangle_blocks(s.triangle),
            c,
        })
    });
    set
}

/// The local stiffness with the matrix-free `K w` equals the one from the
/// assembled tissue matrix (the old path, `k = −Σ k̂·(K w)_m` over the free
/// contact nodes) to rounding: each `(K w)_m` within `2 γ₅₂ ‖K‖∞ ‖w‖∞`
/// (see the model's matrix-free test), so `k` within that times the number
/// of contact nodes (the fixed nodes' term is computed identically).
#[test]
fn local_stiffness_matrix_free_equals_the_assembled_product() {
    let (mut model, mut pc) = pressed();
    let mut set = contact_set(&model, &mut pc);
    assert!(!set.springs.is_empty());
    let mut local = LocalStiffness::new(&model);
    let (k_new, stats) = local.compute(&mut model, &mut set);
    assert!(stats.converged && k_new > 0.0);
    let w = local.node_sensitivity().to_vec();
    let n = model.node_count();
    let (mut k, mut b) = (model.pattern().clone(), model.pattern().clone());
    model.jacobians(&mut NoExtraForce, &mut k, &mut b);
    let mut kw = vec![Vec3::zeros(); n];
    k.mul_vec(&w, &mut kw);
    let mut nodes: Vec<usize> = set.springs.iter().flat_map(|s| s.nodes).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let dir = set.direction;
    let mut k_old: f64 = nodes
        .iter()
        .filter(|&&m| !model.fixed()[m])
        .map(|&m| -kw[m].dot(&dir))
        .sum();
    for s in &set.springs {
        let stretch: f64 = s
            .nodes
            .iter()
            .zip(&s.beta)
            .map(|(&m, &b)| b * dir.dot(&w[m]))
            .sum();
        for (&m, &b) in s.nodes.iter().zip(&s.beta) {
            if model.fixed()[m] {
                k_old += s.c * b * (1.0 - stretch);
            }
        }
    }
    let dense = k.to_dense();
    let norm_k = (0..dense.nrows())
        .map(|r| dense.row(r).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let norm_w = w.iter().map(|v| v.amax()).fold(0.0, f64::max);
    let gamma = 52.0 * f64::EPSILON / (1.0 - 52.0 * f64::EPSILON);
    // Plus the rounding of the sum itself over the nodes (γ_n |k|).
    let tol = nodes.len() as f64 * 2.0 * gamma * norm_k * norm_w
        + 2.0 * nodes.len() as f64 * f64::EPSILON * k_old.abs();
    assert!(
        (k_new - k_old).abs() <= tol,
        "k {k_new} vs {k_old} N/m (bound {tol})"
    );
}
