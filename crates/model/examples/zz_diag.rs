use echothigh_model::bench::{apply_patch_load, probe_patch};
use echothigh_model::{ModelConfig, NoExtraForce, ThighModel};
use std::time::Instant;
fn run(cfg: &ModelConfig, steps: usize) -> (ThighModel, u32, u32, f64, u32) {
    let mut model = ThighModel::new(cfg).unwrap();
    let patch = probe_patch(&model);
    let (mut cg, mut nw, mut reg) = (0, 0, 0);
    let t0 = Instant::now();
    for _ in 0..steps {
        let t = model.time();
        let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * t).cos());
        apply_patch_load(&mut model, &patch, f);
        let s = model.step(0.01, &mut NoExtraForce);
        cg += s.cg_iterations; nw += s.newton_iterations; reg += s.regularized;
    }
    (model, cg, nw, t0.elapsed().as_secs_f64(), reg)
}
fn main() {
    let steps = 100;
    let mut base = ModelConfig::default();
    base.thigh.n_theta = 48; base.thigh.n_z = 21;
    let mut tight = base.clone();
    tight.integrator.newton_tol = 1e-10; tight.integrator.newton_abs_tol = 1e-14; tight.integrator.cg_tol = 1e-10; tight.integrator.newton_max_iterations = 30;
    let (reference, ..) = run(&tight, steps);
    for geo in [true, false] {
        for (nt, na, ct) in [(1e-3, 1e-8, 1e-4), (1e-2, 1e-7, 1e-3), (1e-2, 1e-6, 1e-2), (3e-2, 1e-6, 1e-2), (1e-1, 1e-6, 3e-2), (1e-1, 1e-6, 1e-1)] {
            let mut c = base.clone();
            c.integrator.newton_tol = nt; c.integrator.newton_abs_tol = na; c.integrator.cg_tol = ct;
            c.integrator.geometric_stiffness_in_compression = geo;
            let (m, cg, nw, secs, reg) = run(&c, steps);
            let err = m.positions().iter().zip(reference.positions()).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            println!("geo {geo} ntol {nt:e} abs {na:e} cg {ct:e}: CG/step {:.1} Newton/step {:.2} reg {reg} ms/step {:.3} max pos err {:.2e} m", cg as f64 / steps as f64, nw as f64 / steps as f64, secs * 1e3 / steps as f64, err);
        }
    }
}
