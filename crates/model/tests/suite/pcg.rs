//! The preconditioned conjugate gradient on random SPD block systems and on
//! the thigh's own matrix.

use crate::common;

use echothigh_model::{
    BlockSparse, ForceModel, NoExtraForce, Pcg, PcgParams, Preconditioner, Vec3,
};
use nalgebra::Matrix3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random SPD block matrix: random "springs" `R Rᵀ` on random pairs
/// (a PSD Laplacian-like sum) plus random SPD diagonal blocks.
fn random_spd(n: usize, pairs: usize, rng: &mut ChaCha8Rng) -> BlockSparse {
    let edges: Vec<(usize, usize)> = (0..pairs)
        .map(|_| (rng.gen_range(0..n), rng.gen_range(0..n)))
        .filter(|(i, j)| i != j)
        .collect();
    let mut a = BlockSparse::from_pairs(n, edges.iter().copied());
    let rand3 = |rng: &mut ChaCha8Rng| Matrix3::from_fn(|_, _| rng.gen_range(-1.0..1.0));
    for &(i, j) in &edges {
        let r = rand3(rng);
        let s = r * r.transpose() * rng.gen_range(0.1..100.0);
        a.add_block(i, i, &s).unwrap();
        a.add_block(j, j, &s).unwrap();
        a.add_block(i, j, &-s).unwrap();
        a.add_block(j, i, &-s).unwrap();
    }
    for i in 0..n {
        let r = rand3(rng);
        let d = r * r.transpose() + Matrix3::identity() * rng.gen_range(0.01..1.0);
        a.add_diagonal(i, &d);
    }
    a
}

fn residual(a: &BlockSparse, x: &[Vec3], b: &[Vec3], fixed: &[bool]) -> f64 {
    let mut ax = vec![Vec3::zeros(); x.len()];
    a.mul_vec(x, &mut ax);
    let num: f64 = (0..x.len())
        .filter(|&i| !fixed[i])
        .map(|i| (b[i] - ax[i]).norm_squared())
        .sum();
    let den: f64 = (0..x.len())
        .filter(|&i| !fixed[i])
        .map(|i| b[i].norm_squared())
        .sum();
    (num / den).sqrt()
}

#[test]
fn solves_random_spd_block_systems_to_tolerance() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for trial in 0..20 {
        let n = rng.gen_range(5..200);
        let a = random_spd(n, 3 * n, &mut rng);
        let b: Vec<Vec3> = common::perturbation(n, 1.0, trial);
        let fixed: Vec<bool> = (0..n).map(|i| trial % 2 == 1 && i % 7 == 0).collect();
        for pre in [Preconditioner::None, Preconditioner::BlockJacobi] {
            let params = PcgParams {
                tol: 1e-10,
                max_iterations: 10_000,
                preconditioner: pre,
            };
            let mut x = common::perturbation(n, 1.0, 100 + trial); // arbitrary warm start
            let stats = Pcg::new(n).solve(&a, &b, &mut x, &fixed, &params);
            assert!(
                stats.converged && !stats.indefinite,
                "trial {trial} {pre:?}: {stats:?}"
            );
            let r = residual(&a, &x, &b, &fixed);
            assert!(r <= 1e-10 * (1.0 + 1e-6), "trial {trial}: residual {r}");
            assert!(
                (r - stats.residual).abs() < 1e-9,
                "reported {} vs {r}",
                stats.residual
            );
            assert!(x
                .iter()
                .zip(&fixed)
                .all(|(v, &f)| !f || *v == Vec3::zeros()));
        }
    }
}

#[test]
fn warm_start_from_the_solution_takes_no_iteration() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let n = 50;
    let a = random_spd(n, 150, &mut rng);
    let b = common::perturbation(n, 1.0, 9);
    let fixed = vec![false; n];
    let params = PcgParams {
        tol: 1e-8,
        max_iterations: 1000,
        preconditioner: Preconditioner::BlockJacobi,
    };
    let mut pcg = Pcg::new(n);
    let mut x = vec![Vec3::zeros(); n];
    let first = pcg.solve(&a, &b, &mut x, &fixed, &params);
    assert!(first.iterations > 5);
    let again = pcg.solve(&a, &b, &mut x, &fixed, &params);
    assert_eq!(again.iterations, 0);
}

/// A penalty-like stiff normal support on a patch of nodes (what a probe in
/// contact adds): `F = −k_c ((x − x_rest)·n) n`, diagonal blocks only.
struct StiffPatch {
    nodes: Vec<usize>,
    normals: Vec<Vec3>,
    rest: Vec<Vec3>,
    k_c: f64,
}

impl ForceModel for StiffPatch {
    fn add_forces(&mut self, x: &[Vec3], _v: &[Vec3], f: &mut [Vec3]) {
        for (q, &i) in self.nodes.iter().enumerate() {
            let n = self.normals[q];
            f[i] -= n * (self.k_c * (x[i] - self.rest[q]).dot(&n));
        }
    }
    fn add_jacobians(
        &mut self,
        _x: &[Vec3],
        _v: &[Vec3],
        k: &mut BlockSparse,
        _b: &mut BlockSparse,
    ) {
        for (q, &i) in self.nodes.iter().enumerate() {
            let n = self.normals[q];
            k.add_diagonal(i, &(n * n.transpose() * -self.k_c));
        }
    }
}

#[test]
fn block_jacobi_beats_no_preconditioner_on_the_thigh_matrix() {
    let mut m = common::model(&common::small_config(32, 14));
    common::press_top(&mut m, 10.0);
    for _ in 0..5 {
        m.step(0.01, &mut NoExtraForce);
    }
    let top = common::top_node(&m);
    let (it, iz) = m.mesh().grid_index(top);
    let nodes: Vec<usize> = (0..3)
        .flat_map(|d| (0..2).map(move |e| (d, e)))
        .map(|(d, e)| m.mesh().node_index(it + d, iz + e))
        .collect();
    let mut contact = StiffPatch {
        normals: nodes.iter().map(|&i| m.mesh().rest_normals()[i]).collect(),
        rest: nodes.iter().map(|&i| m.positions()[i]).collect(),
        nodes,
        k_c: 1.0e5,
    };
    // The Newton matrix M − h B − h² K of the loaded state, with the patch.
    let h = 0.01;
    let mut k = m.pattern().clone();
    let mut b = m.pattern().clone();
    m.jacobians(&mut contact, &mut k, &mut b);
    let mut a = m.pattern().clone();
    a.set_combination(-h * h, &k, -h, &b, m.masses());
    let n = m.node_count();
    let rhs = common::perturbation(n, 1.0, 4);
    let count = |pre| {
        let params = PcgParams {
            tol: 1e-8,
            max_iterations: 10_000,
            preconditioner: pre,
        };
        let mut x = vec![Vec3::zeros(); n];
        let s = Pcg::new(n).solve(&a, &rhs, &mut x, m.fixed(), &params);
        assert!(s.converged);
        s.iterations
    };
    let (plain, jacobi) = (
        count(Preconditioner::None),
        count(Preconditioner::BlockJacobi),
    );
    assert!(
        (jacobi as f64) < 0.8 * plain as f64,
        "block-Jacobi {jacobi} vs none {plain}"
    );
    // Same for the quasi-static stiffness −K.
    let mut negk = m.pattern().clone();
    negk.set_combination(-1.0, &k, 0.0, &b, &vec![0.0; n]);
    let count_k = |pre| {
        let params = PcgParams {
            tol: 1e-8,
            max_iterations: 100_000,
            preconditioner: pre,
        };
        let mut x = vec![Vec3::zeros(); n];
        let s = Pcg::new(n).solve(&negk, &rhs, &mut x, m.fixed(), &params);
        assert!(s.converged);
        s.iterations
    };
    let (plain_k, jacobi_k) = (
        count_k(Preconditioner::None),
        count_k(Preconditioner::BlockJacobi),
    );
    assert!(
        (jacobi_k as f64) < 0.8 * plain_k as f64,
        "−K: block-Jacobi {jacobi_k} vs none {plain_k}"
    );
    eprintln!("M−hB−h²K: none {plain}, block-Jacobi {jacobi}; −K: none {plain_k}, block-Jacobi {jacobi_k}");
}

#[test]
fn pattern_is_fixed_and_checked() {
    let mut a = BlockSparse::from_pairs(4, [(0, 1), (1, 2), (2, 3)]);
    assert_eq!(a.nnz_blocks(), 4 + 6);
    assert!(a.add_block(0, 1, &Matrix3::identity()).is_ok());
    let err = a.add_block(0, 3, &Matrix3::identity()).unwrap_err();
    assert_eq!((err.row, err.col), (0, 3));
    assert!(a.add_block(9, 0, &Matrix3::identity()).is_err());
    // y = A x on a known case.
    let mut x = vec![Vec3::zeros(); 4];
    x[1] = Vec3::new(1.0, 2.0, 3.0);
    let mut y = vec![Vec3::zeros(); 4];
    a.mul_vec(&x, &mut y);
    assert_eq!(y[0], Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(y[1], Vec3::zeros());
}
