//! The contact models' direct scaled-Jacobian assembly (issue 16: without
//! it every Newton iteration assembled the whole pattern twice) against the
//! separate assembly of `K` and `B` it replaces, and the matrix-free local
//! stiffness against the assembled tissue matrix.

use echothigh_contact::{
    ContactParams, ContactSet, ContactSpring, LocalStiffness, Probe, ProbeContact,
};
use echothigh_model::{
    BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, ModelConfig, NoExtraForce, SystemForm,
    ThighModel, Vec3,
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

/// `model`'s start matrix `diag` (kg) plus `f`'s edge-form assembly, as a
/// block-sparse matrix, with the rank-one terms kept (`capacity` large) or
/// sent to the side matrix (`capacity` 0).
fn edge_assembled(
    model: &ThighModel,
    f: &mut dyn ForceModel,
    (alpha, beta): (f64, f64),
    diag: &[f64],
    capacity: usize,
) -> BlockSparse {
    let (x, v) = (model.positions(), model.velocities());
    let mut edge = EdgeMatrix::new(model.pattern(), capacity);
    let mut scratch = JacobianScratch::new(model.pattern());
    edge.begin(diag);
    f.add_scaled_jacobians_edge(x, v, alpha, beta, &mut edge, &mut scratch);
    edge.finish();
    assert_eq!(edge.side().is_some(), capacity == 0);
    edge.to_block_sparse(model.pattern()).unwrap()
}

/// The edge form's rank-one contact terms (issue 18) are the penalty
/// contact's and the contact set's blocks, to the same rounding bound as
/// the direct assembly, kept as rank-one terms or sent to the side matrix.
#[test]
fn edge_form_contact_terms_equal_the_separate_jacobians() {
    let (model, mut pc) = pressed();
    let (x, v) = (model.positions().to_vec(), model.velocities().to_vec());
    let mut set = contact_set(&model, &mut pc);
    let contact = pc.contact_mut();
    contact.prepare(&x, &v, 0.01);
    let samples = contact.sample_surfaces().iter().flatten().count();
    let mut start = model.pattern().clone();
    start.add_to_diagonal(model.masses());
    let (alpha, beta) = (-1e-4, -1e-2);
    let (mut k, mut b) = (model.pattern().clone(), model.pattern().clone());
    contact.add_jacobians(&x, &v, &mut k, &mut b);
    let mut old = start.clone();
    old.add_scaled(alpha, &k, beta, &b);
    for capacity in [model.node_count(), 0] {
        let edge = edge_assembled(&model, contact, (alpha, beta), model.masses(), capacity);
        assert_same_to_rounding(&edge, &old, &start, (alpha, &k), (beta, &b), samples);
    }
    let zero = model.pattern().clone();
    let (mut k, mut b) = (model.pattern().clone(), model.pattern().clone());
    set.add_jacobians(&x, &v, &mut k, &mut b);
    let mut old = zero.clone();
    old.add_scaled(-1.0, &k, 0.0, &b);
    let none = vec![0.0; model.node_count()];
    let n = set.springs.len();
    for capacity in [model.node_count(), 0] {
        let edge = edge_assembled(&model, &mut set, (-1.0, 0.0), &none, capacity);
        assert_same_to_rounding(&edge, &old, &zero, (-1.0, &k), (0.0, &b), n);
    }
}

/// With the probe (contact forces, rank-one terms and the stiffness
/// queries), the edge form follows the block-sparse reference: 60 steps
/// pressing to 8 mm. Each form's Newton stops within `newton_tol` of its
/// step's first update (at most the step's motion), so the trajectories
/// may part by at most `2 newton_tol Σ max|Δx|` over the steps. The two
/// stiffness solves each leave a residual `|r| ≤ stiffness_tol |C1|`, which
/// moves `k = 1ᵀC(1 − w)` by `1ᵀC(T + C)⁻¹r`; with `C ⪯ T + C` this is of
/// the order of `stiffness_tol · 1ᵀC1` (the rigid stiffness), and the test
/// asks `|Δk| ≤ 2 stiffness_tol · 1ᵀC1` (an order-of-magnitude bound: the
/// measured gap is at rounding level, ~1e-12 N/m).
#[test]
fn edge_form_with_contact_matches_the_reference() {
    let config = ModelConfig::default();
    let top = config.thigh.semi_axis_y;
    let mut models = [
        ThighModel::new(&config).unwrap(),
        ThighModel::new(&config).unwrap(),
    ];
    models[1].set_system_form(SystemForm::BlockSparse);
    let mut pcs = [
        ProbeContact::new(&models[0], Probe::default(), ContactParams::default()).unwrap(),
        ProbeContact::new(&models[1], Probe::default(), ContactParams::default()).unwrap(),
    ];
    let (mut bound, mut worst_k) = (0.0, 0.0f64);
    for i in 1..=60 {
        let depth = 0.008 * f64::from(i.min(40)) / 40.0;
        let pose = Probe::exam_pose(Vec3::new(0.0, top - depth, 0.0));
        let before = models[0].positions().to_vec();
        let a = pcs[0].step(&mut models[0], &pose, 0.01);
        let b = pcs[1].step(&mut models[1], &pose, 0.01);
        assert!(a.physics.converged && b.physics.converged);
        let moved = before
            .iter()
            .zip(models[0].positions())
            .map(|(p, q)| (p - q).amax())
            .fold(0.0, f64::max);
        bound += 2.0 * config.integrator.newton_tol * moved;
        let gap = models[0]
            .positions()
            .iter()
            .zip(models[1].positions())
            .map(|(p, q)| (p - q).amax())
            .fold(0.0, f64::max);
        assert!(gap <= bound, "step {i}: {gap:e} > {bound:e}");
        let rigid = pcs[0].contact().params().stiffness
            * pcs[0].contact().samples().1
            * a.query.stiffness_springs as f64;
        let dk = (a.sample.stiffness - b.sample.stiffness).abs();
        assert!(
            dk <= 2.0 * config.integrator.stiffness_tol * rigid,
            "step {i}: k {} vs {} N/m",
            a.sample.stiffness,
            b.sample.stiffness
        );
        worst_k = worst_k.max(dk);
        assert_eq!(a.sample.in_contact, b.sample.in_contact);
    }
    assert!(
        pcs[0]
            .contact()
            .wrench(models[0].positions(), models[0].velocities())
            .samples
            > 0
    );
    println!("largest |Δk| {worst_k:e} N/m");
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
