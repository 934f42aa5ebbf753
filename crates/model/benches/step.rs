//! Criterion bench of one implicit step (`load` scenario) at ~500, 1 000 and
//! 2 000 nodes. The JSON command `echothigh bench physics` covers all sizes.

use criterion::{criterion_group, criterion_main, Criterion};
use echothigh_model::bench::{apply_patch_load, case_model, probe_patch, Scenario};
use echothigh_model::NoExtraForce;

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("implicit_step_load");
    group.sample_size(20);
    for (nt, nz) in [(32, 16), (48, 21), (64, 32)] {
        let mut model = case_model(Scenario::Press, nt, nz).expect("valid bench config");
        let patch = probe_patch(&model);
        group.bench_function(format!("{}_nodes", nt * nz), |b| {
            b.iter(|| {
                // Alternate the load so every step has work to do.
                let t = model.time();
                let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * t).cos());
                apply_patch_load(&mut model, &patch, f);
                model.step(0.01, &mut NoExtraForce)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
