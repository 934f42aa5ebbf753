//! Same-run A/B of the physics step (issue 18): the press of
//! `bench physics` (15 N · ½(1 − cos 2π t) on a 40 × 10 mm patch on the
//! anterior line, h = 10 ms, from rest) on two models that differ in one
//! setting, alternated round by round; per round each side's median
//! thread-CPU time per step, CG iterations per step and stage medians.
//!
//! `cargo run --release -p echothigh-model --example precond_ab -- \
//!   <n_theta> <n_z> <steps> <rounds> <scalar-kernels | scalar-limit>`
//!
//! `scalar-kernels`: A is the default model, B runs the scalar kernels
//! (its `step_fraction` stage differs from A's only by the limiter's
//! kernel: the stage's other work, the path vectors, is the same code).
//! `scalar-limit` times the limiter alone on the press states, both
//! kernels alternated. (The two-level preconditioner trial of issue 18
//! was measured with this example at commit 96e66b5, B = `coarse_patch`.)

use echothigh_model::{ColumnLimits, Kernels, ModelConfig, NoExtraForce, ThighModel, Vec3};
use std::time::Instant;

/// The calling thread's CPU time (µs).
fn thread_cpu_us() -> f64 {
    cpu_time::ThreadTime::try_now().map_or(0.0, |t| t.as_duration().as_secs_f64() * 1e6)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct Run {
    cpu_us: f64,
    cg_per_step: f64,
    newton_per_step: f64,
    pcg_us: f64,
    fraction_us: f64,
    y_top: f64,
    /// The local stiffness solve (1 N inward at the top node, cold start,
    /// at the end of the press): thread-CPU µs (median of 5) and CG iterations.
    stiff_us: f64,
    stiff_iters: u32,
}

fn model(nt: usize, nz: usize) -> ThighModel {
    let mut c = ModelConfig::default();
    c.thigh.n_theta = nt;
    c.thigh.n_z = nz;
    ThighModel::new(&c).expect("model")
}

fn patch(m: &ThighModel) -> Vec<usize> {
    let mesh = m.mesh();
    let centre = mesh.rest_positions()[mesh.node_at(std::f64::consts::FRAC_PI_2, 0.0)];
    (0..mesh.node_count())
        .filter(|&k| {
            let p = mesh.rest_positions()[k];
            (p.x - centre.x).abs() <= 0.020 && (p.z - centre.z).abs() <= 0.005 && p.y > 0.0
        })
        .collect()
}

fn press(m: &mut ThighModel, steps: usize, warmup: usize) -> Run {
    let p = patch(m);
    let top = m.mesh().node_at(std::f64::consts::FRAC_PI_2, 0.0);
    let (mut cpu, mut pcg, mut frac) = (vec![], vec![], vec![]);
    let (mut cg, mut newton) = (0u64, 0u64);
    for i in 0..warmup + steps {
        let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * m.time()).cos());
        let normals: Vec<Vec3> = p.iter().map(|&k| m.mesh().rest_normals()[k]).collect();
        for (&k, n) in p.iter().zip(&normals) {
            m.external_forces_mut()[k] = -n * (f / p.len() as f64);
        }
        let c0 = thread_cpu_us();
        let s = m.step(0.01, &mut NoExtraForce);
        let c1 = thread_cpu_us();
        if i >= warmup {
            cpu.push(c1 - c0);
            pcg.push(s.timings.pcg * 1e6);
            frac.push(s.timings.step_fraction * 1e6);
            cg += u64::from(s.cg_iterations);
            newton += u64::from(s.newton_iterations);
        }
    }
    let n = m.node_count();
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[top] = -m.mesh().rest_normals()[top];
    let mut out = vec![Vec3::zeros(); n];
    let (mut st, mut iters) = (vec![], 0);
    for _ in 0..5 {
        out.fill(Vec3::zeros());
        let c0 = thread_cpu_us();
        iters = m
            .solve_stiffness(&mut NoExtraForce, &rhs, &mut out)
            .iterations;
        st.push(thread_cpu_us() - c0);
    }
    Run {
        stiff_us: median(&mut st),
        stiff_iters: iters,
        cpu_us: median(&mut cpu),
        cg_per_step: cg as f64 / steps as f64,
        newton_per_step: newton as f64 / steps as f64,
        pcg_us: median(&mut pcg),
        fraction_us: median(&mut frac),
        y_top: m.positions()[top].y,
    }
}

/// The limiter alone on the press states: per step, the fraction of
/// `x → x + h v` timed on both kernels, alternated (thread-CPU over 50
/// calls each, µs per call).
fn limiter_ab(nt: usize, nz: usize, steps: usize) -> (f64, f64) {
    let mut m = model(nt, nz);
    let limits = ColumnLimits::new((0..m.node_count()).map(|k| {
        (
            m.mesh().rest_normals()[k],
            m.positions()[k].dot(&m.mesh().rest_normals()[k]) - 0.01,
        )
    }));
    let p = patch(&m);
    let (mut a, mut b) = (vec![], vec![]);
    for _ in 0..steps {
        let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * m.time()).cos());
        let normals: Vec<Vec3> = p.iter().map(|&k| m.mesh().rest_normals()[k]).collect();
        for (&k, n) in p.iter().zip(&normals) {
            m.external_forces_mut()[k] = -n * (f / p.len() as f64);
        }
        m.step(0.01, &mut NoExtraForce);
        let dx: Vec<Vec3> = m.velocities().iter().map(|v| v * 0.01).collect();
        for (kernels, out) in [(Kernels::Scalar, &mut a), (Kernels::Simd, &mut b)] {
            let c0 = thread_cpu_us();
            let mut s = 0.0;
            for _ in 0..50 {
                s += limits.max_step_fraction(std::hint::black_box(m.positions()), &dx, kernels);
            }
            std::hint::black_box(s);
            out.push((thread_cpu_us() - c0) / 50.0);
        }
    }
    (median(&mut a), median(&mut b))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let nt: usize = args[1].parse().unwrap();
    let nz: usize = args[2].parse().unwrap();
    let steps: usize = args[3].parse().unwrap();
    let rounds: usize = args[4].parse().unwrap();
    if args[5] == "scalar-limit" {
        for r in 0..rounds {
            let (a, b) = limiter_ab(nt, nz, steps);
            println!(
                "round {r}: limiter µs/call scalar {a:.2}, simd {b:.2}, ratio {:.2}",
                a / b
            );
        }
        return;
    }
    assert_eq!(
        args[5], "scalar-kernels",
        "B: scalar-kernels or scalar-limit"
    );
    let t0 = Instant::now();
    let mut ab: [Vec<Run>; 2] = [vec![], vec![]];
    for r in 0..rounds {
        for side in [0, 1] {
            let mut m = model(nt, nz);
            if side == 1 {
                m.set_kernels(Kernels::Scalar);
            }
            let run = press(&mut m, steps, 3);
            println!(
                "round {r} {}: CPU median {:.1} µs/step, CG/step {:.2}, Newton/step {:.2}, pcg median {:.1} µs, step_fraction median {:.1} µs, y_top {:.6e} m; stiffness solve {:.1} µs, {} CG",
                ["A", "B"][side],
                run.cpu_us, run.cg_per_step, run.newton_per_step, run.pcg_us, run.fraction_us, run.y_top,
                run.stiff_us, run.stiff_iters
            );
            ab[side].push(run);
        }
    }
    let med = |side: usize, f: fn(&Run) -> f64| {
        let mut v: Vec<f64> = ab[side].iter().map(f).collect();
        median(&mut v)
    };
    let (a, b) = (med(0, |r| r.cpu_us), med(1, |r| r.cpu_us));
    println!(
        "{} nodes: medians over {rounds} rounds: A {a:.1} µs/step ({:.2} CG), B {b:.1} µs/step ({:.2} CG); B/A {:.3}; pcg A {:.1} B {:.1} µs; step_fraction A {:.1} B {:.1} µs; stiffness solve A {:.1} B {:.1} µs; {:.0} s",
        nt * nz,
        med(0, |r| r.cg_per_step),
        med(1, |r| r.cg_per_step),
        b / a,
        med(0, |r| r.pcg_us),
        med(1, |r| r.pcg_us),
        med(0, |r| r.fraction_us),
        med(1, |r| r.fraction_us),
        med(0, |r| r.stiff_us),
        med(1, |r| r.stiff_us),
        t0.elapsed().as_secs_f64()
    );
}
