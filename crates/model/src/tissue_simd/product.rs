//! `α K w` of the stencil's springs without assembling `K` (issue 18): the
//! matrix-free product the stiffness query uses to test its warm start
//! ([`crate::ThighModel::solve_stiffness_with_product`]). The blocks are
//! those [`TissueStencil::assemble`] writes with `β = 0`, applied on the
//! fly; the passes are those of the force kernel:
//!
//! 1. per class and slot `k` (spring `k`–`k+o`, `δ = x_{k+o} − x_k`,
//!    `l = |δ|`, `d = δ/l`, `g = a (l − L₀)/l`, 0 in compression without
//!    the geometric term): `s_k = α S (w_{k+o} − w_k)` with
//!    `S = (a − g) d dᵀ + g I`, computed as `((a − g)(δ·u)/l²) δ + g u`
//!    (no division beyond the one `1/l`);
//! 2. per node: `Σ_c (s_c[k] − s_c[k−o])` minus its normal spring's block
//!    `α (f′ n₀n₀ᵀ + k_t (I − n₀n₀ᵀ))` times `w_k`, `f′ = b/(a e + b)²`.

// Component and lane loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

use super::{dot, inverse_length, TissueStencil, A, ANCHOR, B, KT, N0, REST};
use crate::simd::{chunks, dispatch, lanes, view, view_mut, SimdSqrt, SqrtKernel};
use crate::Vec3;

impl TissueStencil {
    /// `out += α K w` (N for `α` = 1 and `w` in m), `K = ∂F/∂x` (N/m) of
    /// the classes' springs and the normal springs at `x` (m), without
    /// assembling (`geometric`: the compressed springs' `f/l` term, as in
    /// [`Self::assemble`]). The springs left over are the caller's. Uses
    /// the velocity scratch for `w`; allocates nothing.
    pub fn add_stiffness_product(
        &mut self,
        x: &[Vec3],
        w: &[Vec3],
        (alpha, geometric): (f64, bool),
        out: &mut [Vec3],
    ) {
        self.x.load(x);
        self.v.load(w);
        dispatch(Product {
            t: self,
            alpha,
            geometric,
            out,
        });
    }
}

struct Product<'a> {
    t: &'a mut TissueStencil,
    alpha: f64,
    geometric: bool,
    out: &'a mut [Vec3],
}

impl SqrtKernel for Product<'_> {
    type Output = ();

    #[inline(always)]
    fn run<S: SimdSqrt>(self, s: S) {
        let t = self.t;
        let (pad, nr) = (t.layout.pad(), t.layout.rounded());
        let nch = chunks::<S>(nr);
        macro_rules! at {
            ($v:expr, $shift:expr) => {
                view::<S>($v, pad, nr, $shift, nch)
            };
        }
        let (x, w) = (&t.x, &t.v);
        let alpha = s.splat_f64s(self.alpha);
        let zero = s.splat_f64s(0.0);
        // Pass 1: each class's α S u on its first node (scratch: `force`).
        for class in &mut t.classes {
            let o = class.offset as isize;
            let (ka, rest) = (at!(&class.a, 0), at!(&class.rest, 0));
            let xi: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
            let xj: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], o));
            let wi: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&w.c[r], 0));
            let wj: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&w.c[r], o));
            let [f0, f1, f2] = &mut class.force;
            let out = [f0, f1, f2].map(|a| view_mut::<S>(a, pad, nr, nch));
            for m in 0..nch {
                let delta: [S::f64s; 3] = std::array::from_fn(|r| s.sub_f64s(xj[r][m], xi[r][m]));
                let u: [S::f64s; 3] = std::array::from_fn(|r| s.sub_f64s(wj[r][m], wi[r][m]));
                let (l, inv) = inverse_length(s, dot(s, delta, delta));
                let f = s.mul_f64s(ka[m], s.sub_f64s(l, rest[m]));
                let mut g = s.mul_f64s(f, inv);
                if !self.geometric {
                    g = s.select_f64s_m64s(s.less_than_f64s(f, zero), zero, g);
                }
                // (a − g)(d·u) d = ((a − g)(δ·u)/l²) δ; α folded in.
                let along = s.mul_f64s(
                    s.mul_f64s(alpha, s.sub_f64s(ka[m], g)),
                    s.mul_f64s(dot(s, delta, u), s.mul_f64s(inv, inv)),
                );
                let ag = s.mul_f64s(alpha, g);
                for r in 0..3 {
                    out[r][m] = s.mul_add_f64s(along, delta[r], s.mul_f64s(ag, u[r]));
                }
            }
        }
        // Pass 2: each node pulls its springs' terms and its normal block.
        let nrm: [&[S::f64s]; 15] = std::array::from_fn(|e| at!(&t.normals[e], 0));
        let xs: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
        let ws: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&w.c[r], 0));
        let n = t.layout.n();
        let width = std::mem::size_of::<S::f64s>() / std::mem::size_of::<f64>();
        for m in 0..nch {
            let mut acc = [zero; 3];
            for class in &t.classes {
                let o = class.offset as isize;
                for r in 0..3 {
                    let fwd = at!(&class.force[r], 0)[m];
                    let bwd = at!(&class.force[r], -o)[m];
                    acc[r] = s.sub_f64s(s.add_f64s(acc[r], fwd), bwd);
                }
            }
            // −(p n₀n₀ᵀ + q I) w_k with q = α k_t, p = α f′ − q.
            let n0 = [0, 1, 2].map(|r| nrm[N0 + r][m]);
            let rel = std::array::from_fn(|r| s.sub_f64s(xs[r][m], nrm[ANCHOR + r][m]));
            let ev = s.sub_f64s(dot(s, n0, rel), nrm[REST][m]);
            let den = s.mul_add_f64s(nrm[A][m], ev, nrm[B][m]);
            let df = s.div_f64s(nrm[B][m], s.mul_f64s(den, den));
            let q = s.mul_f64s(alpha, nrm[KT][m]);
            let p = s.sub_f64s(s.mul_f64s(alpha, df), q);
            let wk = [ws[0][m], ws[1][m], ws[2][m]];
            let pnw = s.mul_f64s(p, dot(s, n0, wk));
            for r in 0..3 {
                let block = s.mul_add_f64s(pnw, n0[r], s.mul_f64s(q, wk[r]));
                acc[r] = s.sub_f64s(acc[r], block);
            }
            let cols = [
                lanes::<S>(&acc[0]),
                lanes::<S>(&acc[1]),
                lanes::<S>(&acc[2]),
            ];
            for lane in 0..width {
                let k = m * width + lane;
                if k < n {
                    self.out[k] += Vec3::new(cols[0][lane], cols[1][lane], cols[2][lane]);
                }
            }
        }
    }
}
