//! Helpers shared by the integration tests.
#![allow(dead_code)]

use echothigh_model::{ModelConfig, ThighModel, Vec3};

/// A small thigh (n_θ × n_z) with the default tissue.
pub fn small_config(n_theta: usize, n_z: usize) -> ModelConfig {
    let mut c = ModelConfig::default();
    c.thigh.n_theta = n_theta;
    c.thigh.n_z = n_z;
    c
}

/// As [`small_config`], on the default patient's leg (issue 12) when `leg`.
pub fn small_config_on(n_theta: usize, n_z: usize, leg: bool) -> ModelConfig {
    let mut c = small_config(n_theta, n_z);
    if leg {
        c.thigh.patient = "lean-male".into();
    }
    c
}

/// Builds a model, panicking on an invalid configuration (tests only).
pub fn model(config: &ModelConfig) -> ThighModel {
    ThighModel::new(config).expect("valid test configuration")
}

/// Index of the top (anterior) node of the middle ring.
pub fn top_node(m: &ThighModel) -> usize {
    let mesh = m.mesh();
    mesh.node_index(mesh.n_theta() / 4, mesh.n_z() / 2)
}

/// Inward load (N) of total magnitude `total` on the top node and its
/// θ-neighbours (three nodes, along −rest normal).
pub fn press_top(m: &mut ThighModel, total: f64) {
    let mesh = m.mesh().clone();
    let (it, iz) = mesh.grid_index(top_node(m));
    let ext = m.external_forces_mut();
    for d in [mesh.n_theta() - 1, 0, 1] {
        let k = mesh.node_index(it + d, iz);
        ext[k] = -mesh.rest_normals()[k] * (total / 3.0);
    }
}

/// A deterministic pseudo-random perturbation field of amplitude `amp`.
pub fn perturbation(n: usize, amp: f64, seed: u64) -> Vec<Vec3> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            Vec3::new(
                rng.gen_range(-amp..amp),
                rng.gen_range(-amp..amp),
                rng.gen_range(-amp..amp),
            )
        })
        .collect()
}
