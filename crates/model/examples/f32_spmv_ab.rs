//! The f32 `(d, p, q)` trial (issue 18): a same-run A/B of the stencil
//! product `y = (D + Σ springs) x` with the springs' `(d, p, q)` stored as
//! f64 (A, as the model stores them) or f32 (B, converted to f64 in the
//! registers), the same four-lane AVX2 + FMA loop otherwise, on the Newton
//! matrix of the 10 112-node thigh at the press's peak. Reports the median
//! thread-CPU time per product over alternated rounds and the relative
//! difference of the two products.
//!
//! `cargo run --release -p echothigh-model --example f32_spmv_ab -- <n_theta> <n_z> <rounds>`

use echothigh_model::{
    BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, ModelConfig, NoExtraForce, StencilLayout,
    ThighModel, TissueForces, Vec3,
};

#[cfg(target_arch = "x86_64")]
mod kernel {
    use core::arch::x86_64::{__m128, __m256d};
    use pulp::x86::V3;

    /// A class's spring arrays stored as `T`: `d` (3), `p`, `q`, padded.
    pub struct Class<T> {
        pub offset: usize,
        pub a: [Vec<T>; 5],
    }

    pub trait Storage: Copy {
        fn load(v3: V3, a: &[Self], i: usize) -> __m256d;
    }

    impl Storage for f64 {
        #[inline(always)]
        fn load(_: V3, a: &[f64], i: usize) -> __m256d {
            let c: [f64; 4] = a[i..i + 4].try_into().unwrap();
            pulp::cast(c)
        }
    }

    impl Storage for f32 {
        #[inline(always)]
        fn load(v3: V3, a: &[f32], i: usize) -> __m256d {
            let c: [f32; 4] = a[i..i + 4].try_into().unwrap();
            let c: __m128 = pulp::cast(c);
            v3.avx._mm256_cvtps_pd(c)
        }
    }

    #[inline(always)]
    fn ld(a: &[f64], i: usize) -> __m256d {
        let c: [f64; 4] = a[i..i + 4].try_into().unwrap();
        pulp::cast(c)
    }

    /// `acc += p (d·u) d + q u` (a function: a closure would be compiled
    /// without the AVX2 target features).
    #[inline(always)]
    fn spring(
        v3: V3,
        (d, p, q): ([__m256d; 3], __m256d, __m256d),
        u: [__m256d; 3],
        acc: &mut [__m256d; 3],
    ) {
        let (avx, fma) = (v3.avx, v3.fma);
        let du = fma._mm256_fmadd_pd(
            d[2],
            u[2],
            fma._mm256_fmadd_pd(d[1], u[1], avx._mm256_mul_pd(d[0], u[0])),
        );
        let t = avx._mm256_mul_pd(p, du);
        for r in 0..3 {
            acc[r] = fma._mm256_fmadd_pd(t, d[r], fma._mm256_fmadd_pd(q, u[r], acc[r]));
        }
    }

    /// `y = (D + classes) x` on nodes `[pad, pad + rounded)`, returning `xᵀ y`.
    #[inline(always)]
    pub fn product<T: Storage>(
        v3: V3,
        (pad, rounded): (usize, usize),
        diag: &[Vec<f64>; 9],
        classes: &[Class<T>],
        x: &[Vec<f64>; 3],
        y: &mut [Vec<f64>; 3],
    ) -> f64 {
        let (avx, fma) = (v3.avx, v3.fma);
        let zero = avx._mm256_setzero_pd();
        let mut quad = zero;
        for i in (pad..pad + rounded).step_by(4) {
            let u = [ld(&x[0], i), ld(&x[1], i), ld(&x[2], i)];
            let mut acc = [zero; 3];
            for r in 0..3 {
                acc[r] = fma._mm256_fmadd_pd(
                    ld(&diag[3 * r + 2], i),
                    u[2],
                    fma._mm256_fmadd_pd(
                        ld(&diag[3 * r + 1], i),
                        u[1],
                        avx._mm256_mul_pd(ld(&diag[3 * r], i), u[0]),
                    ),
                );
            }
            for c in classes {
                for j in [i, i - c.offset] {
                    let other = if j == i { i + c.offset } else { j };
                    let a = &c.a;
                    let d = [
                        T::load(v3, &a[0], j),
                        T::load(v3, &a[1], j),
                        T::load(v3, &a[2], j),
                    ];
                    let (p, q) = (T::load(v3, &a[3], j), T::load(v3, &a[4], j));
                    let w = [ld(&x[0], other), ld(&x[1], other), ld(&x[2], other)];
                    spring(v3, (d, p, q), w, &mut acc);
                }
            }
            for r in 0..3 {
                let out: [f64; 4] = pulp::cast(acc[r]);
                y[r][i..i + 4].copy_from_slice(&out);
                quad = fma._mm256_fmadd_pd(u[r], acc[r], quad);
            }
        }
        let q: [f64; 4] = pulp::cast(quad);
        (q[0] + q[1]) + (q[2] + q[3])
    }
}

fn thread_cpu_us() -> f64 {
    cpu_time::ThreadTime::try_now().map_or(0.0, |t| t.as_duration().as_secs_f64() * 1e6)
}

#[cfg(target_arch = "x86_64")]
fn main() {
    use kernel::{product, Class};
    let args: Vec<String> = std::env::args().collect();
    let (nt, nz): (usize, usize) = (args[1].parse().unwrap(), args[2].parse().unwrap());
    let rounds: usize = args[3].parse().unwrap();
    let v3 = pulp::x86::V3::try_new().expect("AVX2 + FMA");
    // The press to its peak (0.5 s of the 1 Hz load), as `bench physics`.
    let mut c = ModelConfig::default();
    c.thigh.n_theta = nt;
    c.thigh.n_z = nz;
    let mut m = ThighModel::new(&c).unwrap();
    let mesh = m.mesh().clone();
    let centre = mesh.rest_positions()[mesh.node_at(std::f64::consts::FRAC_PI_2, 0.0)];
    let patch: Vec<usize> = (0..mesh.node_count())
        .filter(|&k| {
            let p = mesh.rest_positions()[k];
            (p.x - centre.x).abs() <= 0.020 && (p.z - centre.z).abs() <= 0.005 && p.y > 0.0
        })
        .collect();
    for _ in 0..50 {
        let f = 15.0 * 0.5 * (1.0 - (std::f64::consts::TAU * m.time()).cos());
        for &k in &patch {
            m.external_forces_mut()[k] = -mesh.rest_normals()[k] * (f / patch.len() as f64);
        }
        m.step(0.01, &mut NoExtraForce);
    }
    // Its Newton matrix M − λhB − λ²h²K (λ = 1, h = 10 ms) in edge form.
    let pattern = BlockSparse::from_pairs(mesh.node_count(), mesh.coupled_pairs());
    let mut tissue = TissueForces::new(&mesh, &c.tissue, &pattern, 0.05, false);
    let mut edge = EdgeMatrix::new(&pattern, 0);
    let mut scratch = JacobianScratch::new(&pattern);
    edge.begin(m.masses());
    let (x, v) = (m.positions().to_vec(), m.velocities().to_vec());
    tissue.add_scaled_jacobians_edge(&x, &v, -1e-4, -1e-2, &mut edge, &mut scratch);
    edge.finish();
    let layout = StencilLayout::from_pattern(&pattern);
    let (pad, rounded, len) = (layout.pad(), layout.rounded(), layout.len());
    let classes = edge.stencil().expect("the SIMD assembly fills the classes");
    let c64: Vec<Class<f64>> = classes
        .iter()
        .map(|c| Class {
            offset: c.offset,
            a: [
                c.d[0].clone(),
                c.d[1].clone(),
                c.d[2].clone(),
                c.p.clone(),
                c.q.clone(),
            ],
        })
        .collect();
    let c32: Vec<Class<f32>> = c64
        .iter()
        .map(|c| Class {
            offset: c.offset,
            a: std::array::from_fn(|k| c.a[k].iter().map(|&v| v as f32).collect()),
        })
        .collect();
    let mut diag: [Vec<f64>; 9] = std::array::from_fn(|_| vec![0.0; len]);
    for (k, b) in edge.diagonal().iter().enumerate() {
        for e in 0..9 {
            diag[e][pad + k] = b[(e / 3, e % 3)];
        }
    }
    let mut xs: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; len]);
    let w: Vec<Vec3> = m.velocities().to_vec();
    for (k, wk) in w.iter().enumerate() {
        for r in 0..3 {
            xs[r][pad + k] = wk[r];
        }
    }
    let (mut y64, mut y32): ([Vec<f64>; 3], [Vec<f64>; 3]) = (
        std::array::from_fn(|_| vec![0.0; len]),
        std::array::from_fn(|_| vec![0.0; len]),
    );
    let reps = 200;
    let (mut a, mut b) = (vec![], vec![]);
    for _ in 0..rounds {
        let t = thread_cpu_us();
        for _ in 0..reps {
            std::hint::black_box(v3.vectorize(
                #[inline(always)]
                || product(v3, (pad, rounded), &diag, &c64, &xs, &mut y64),
            ));
        }
        a.push((thread_cpu_us() - t) / reps as f64);
        let t = thread_cpu_us();
        for _ in 0..reps {
            std::hint::black_box(v3.vectorize(
                #[inline(always)]
                || product(v3, (pad, rounded), &diag, &c32, &xs, &mut y32),
            ));
        }
        b.push((thread_cpu_us() - t) / reps as f64);
    }
    let (mut num, mut den) = (0.0, 0.0);
    for r in 0..3 {
        for k in 0..mesh.node_count() {
            num += (y32[r][pad + k] - y64[r][pad + k]).powi(2);
            den += y64[r][pad + k].powi(2);
        }
    }
    println!("rounds f64 µs/product: {a:.1?}");
    println!("rounds f32 µs/product: {b:.1?}");
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (ma, mb) = (a[a.len() / 2], b[b.len() / 2]);
    println!(
        "{} nodes, {} classes: median f64 {ma:.1} µs, f32 {mb:.1} µs per product (f64/f32 {:.3}); |y32 − y64|/|y64| = {:.2e}",
        mesh.node_count(),
        classes.len(),
        ma / mb,
        (num / den).sqrt()
    );
}

#[cfg(not(target_arch = "x86_64"))]
fn main() {
    eprintln!("x86-64 only");
}
