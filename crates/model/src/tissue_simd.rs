//! The tissue's springs on the grid stencil (issue 18): forces and Newton
//! matrix assembly in four-lane f64 with FMA over structure-of-arrays data
//! ([`crate::simd`]), the same laws as [`crate::tissue`] (see
//! [`crate::springs`] for the equations):
//!
//! - a linear spring of class `c` at slot `k` (nodes `k`, `k + o`), with
//!   `δ = x_{k+o} − x_k`, `l = |δ|`, `d = δ/l`, `f = a (l − L₀)`:
//!   force on `k` `F = (f + c (v_{k+o} − v_k)·d) d` (N), and the matrix
//!   term `p d dᵀ + q I` with `g = f/l` (0 in compression without the
//!   geometric term), `p = α (a − g) + β c`, `q = α g`;
//! - node `k` then pulls `Σ_c (F_c[k] − F_c[k−o])` and the diagonal block
//!   `−Σ_c (E_c[k] + E_c[k−o])`, plus its normal spring, a column along
//!   the rest normal `n₀` from the anchor (`e = n₀·(x − anchor) − L₀`,
//!   `f = e/(a e + b)`, `f′ = b/(a e + b)²`, damper `c` along `n₀`,
//!   tangential tie `k_t (I − n₀n₀ᵀ)`, `c_t (I − n₀n₀ᵀ)`).
//!
//! A spring of zero length contributes nothing (as in the scalar code);
//! springs outside the classes are left to the scalar code.

// Component and lane loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

mod product;

use crate::simd::{chunks, dispatch, lanes, view, view_mut, SimdSqrt, SqrtKernel};
use crate::stencil::{Soa3, StencilClass, StencilLayout};
use crate::Vec3;
use nalgebra::Matrix3;

/// A linear spring by its endpoints and constants: `(i, j, L₀ (m), a (N/m), c (N·s/m))`.
pub type SpringSpec = (usize, usize, f64, f64, f64);

/// A normal spring's constants (see [`crate::tissue`]).
#[derive(Debug, Clone, Copy)]
pub struct NormalSpec {
    /// Anchor (m).
    pub anchor: Vec3,
    /// Rest length (m).
    pub rest: f64,
    /// Law `x/(a x + b)`: `a` (1/N), `b` (m/N).
    pub a: f64,
    /// See `a`.
    pub b: f64,
    /// Damper (N·s/m).
    pub c: f64,
    /// Rest normal `n₀` (unit).
    pub n0: Vec3,
    /// Tangential stiffness `k_t` (N/m) and damping `c_t` (N·s/m).
    pub kt: f64,
    /// See `kt`.
    pub ct: f64,
    /// Rest position (m).
    pub x_rest: Vec3,
}

/// One class's spring constants, zero where a slot has no spring.
#[derive(Debug, Clone)]
struct SpringClass {
    offset: usize,
    a: Vec<f64>,
    c: Vec<f64>,
    rest: Vec<f64>,
    force: [Vec<f64>; 3],
}

/// The tissue in stencil form, with its scratch.
#[derive(Debug, Clone)]
pub struct TissueStencil {
    layout: StencilLayout,
    classes: Vec<SpringClass>,
    /// `anchor (3), rest, a, b, c, n0 (3), kt, ct, x_rest (3)`, padded.
    normals: [Vec<f64>; 15],
    leftover: Vec<usize>,
    /// `(class, slot)` of each spring given to [`Self::new`] (`None`: left over).
    slots: Vec<Option<(usize, usize)>>,
    x: Soa3,
    v: Soa3,
}

const ANCHOR: usize = 0;
const REST: usize = 3;
const A: usize = 4;
const B: usize = 5;
const C: usize = 6;
const N0: usize = 7;
const KT: usize = 10;
const CT: usize = 11;
const XR: usize = 12;

impl TissueStencil {
    /// Sorts `springs` into `layout`'s classes (the index of each spring
    /// left over is kept) and lays the normal springs out (allocates once).
    pub fn new(layout: &StencilLayout, springs: &[SpringSpec], normals: &[NormalSpec]) -> Self {
        let z = vec![0.0; layout.len()];
        let mut classes: Vec<SpringClass> = layout
            .offsets()
            .iter()
            .map(|&offset| SpringClass {
                offset,
                a: z.clone(),
                c: z.clone(),
                rest: z.clone(),
                force: [z.clone(), z.clone(), z.clone()],
            })
            .collect();
        let mut leftover = Vec::new();
        let mut slots = Vec::with_capacity(springs.len());
        for (e, &(i, j, rest, a, c)) in springs.iter().enumerate() {
            match layout.slot(i, j) {
                Some((k, s)) if classes[k].a[s] == 0.0 && classes[k].c[s] == 0.0 => {
                    let class = &mut classes[k];
                    (class.a[s], class.c[s], class.rest[s]) = (a, c, rest);
                    slots.push(Some((k, s)));
                }
                _ => {
                    leftover.push(e);
                    slots.push(None);
                }
            }
        }
        let mut arrays: [Vec<f64>; 15] = std::array::from_fn(|_| z.clone());
        // b = 1 off the nodes keeps the padding's law finite.
        arrays[B].fill(1.0);
        let mut t = TissueStencil {
            layout: layout.clone(),
            classes,
            normals: arrays,
            leftover,
            slots,
            x: Soa3::new(layout),
            v: Soa3::new(layout),
        };
        for (k, s) in normals.iter().enumerate() {
            t.set_normal(k, s);
        }
        t
    }

    /// Replaces the constants of the springs given to [`Self::new`] (same
    /// springs, same order: `(L₀, a, c)` each) and of node `k`'s normal
    /// spring for every `k`: the same topology with other values (the
    /// active window moved, [`crate::window`]). Allocates nothing.
    pub fn reload(
        &mut self,
        springs: impl Iterator<Item = (f64, f64, f64)>,
        normals: impl Iterator<Item = NormalSpec>,
    ) {
        for (slot, (rest, a, c)) in self.slots.iter().zip(springs) {
            if let Some((k, s)) = *slot {
                let class = &mut self.classes[k];
                (class.a[s], class.c[s], class.rest[s]) = (a, c, rest);
            }
        }
        for (k, s) in normals.enumerate() {
            self.set_normal(k, &s);
        }
    }

    /// Writes node `k`'s normal spring into the structure-of-arrays data.
    fn set_normal(&mut self, k: usize, s: &NormalSpec) {
        let values = [
            s.anchor.x, s.anchor.y, s.anchor.z, s.rest, s.a, s.b, s.c, s.n0.x, s.n0.y, s.n0.z,
            s.kt, s.ct, s.x_rest.x, s.x_rest.y, s.x_rest.z,
        ];
        let pad = self.layout.pad();
        for (array, v) in self.normals.iter_mut().zip(values) {
            array[pad + k] = v;
        }
    }

    /// Indices (into the springs given to [`Self::new`]) of the springs in no class.
    pub fn leftover(&self) -> &[usize] {
        &self.leftover
    }

    /// The layout.
    pub fn layout(&self) -> &StencilLayout {
        &self.layout
    }

    /// `f += F(x, v)` of the classes' springs and the normal springs (N).
    /// Allocates nothing.
    pub fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        self.x.load(x);
        self.v.load(v);
        dispatch(Forces { t: self, f });
    }

    /// Writes the classes' springs `α S + β c d dᵀ` into `classes` (every
    /// slot) and adds `−Σ_c (E_c[k] + E_c[k−o]) − (α K_n + β B_n)` to the
    /// diagonal blocks (`geometric`: the compressed springs' `f/l` term).
    /// Allocates nothing.
    pub fn assemble(
        &mut self,
        x: &[Vec3],
        (alpha, beta, geometric): (f64, f64, bool),
        classes: &mut [StencilClass],
        diag: &mut [Matrix3<f64>],
    ) {
        self.x.load(x);
        dispatch(Assembly {
            t: self,
            alpha,
            beta,
            geometric,
            classes,
            diag,
        });
    }
}

/// `1/l` where `l > MIN_POSITIVE`, else 0 (a zero-length spring has no term).
#[inline(always)]
fn inverse_length<S: SimdSqrt>(s: S, l2: S::f64s) -> (S::f64s, S::f64s) {
    let l = s.sqrt_f64s(l2);
    let ok = s.greater_than_f64s(l, s.splat_f64s(f64::MIN_POSITIVE));
    let inv = s.select_f64s_m64s(ok, s.div_f64s(s.splat_f64s(1.0), l), s.splat_f64s(0.0));
    (l, inv)
}

#[inline(always)]
fn dot<S: SimdSqrt>(s: S, a: [S::f64s; 3], b: [S::f64s; 3]) -> S::f64s {
    s.mul_add_f64s(
        a[2],
        b[2],
        s.mul_add_f64s(a[1], b[1], s.mul_f64s(a[0], b[0])),
    )
}

struct Forces<'a> {
    t: &'a mut TissueStencil,
    f: &'a mut [Vec3],
}

impl SqrtKernel for Forces<'_> {
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
        let (x, v) = (&t.x, &t.v);
        // Pass 1: each class's spring force on its first node.
        for class in &mut t.classes {
            let o = class.offset as isize;
            let (ka, kc, rest) = (at!(&class.a, 0), at!(&class.c, 0), at!(&class.rest, 0));
            let xi: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
            let xj: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], o));
            let vi: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&v.c[r], 0));
            let vj: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&v.c[r], o));
            let [f0, f1, f2] = &mut class.force;
            let out = [f0, f1, f2].map(|a| view_mut::<S>(a, pad, nr, nch));
            for m in 0..nch {
                let delta = std::array::from_fn(|r| s.sub_f64s(xj[r][m], xi[r][m]));
                let dv = std::array::from_fn(|r| s.sub_f64s(vj[r][m], vi[r][m]));
                let (l, inv) = inverse_length(s, dot(s, delta, delta));
                let rate = s.mul_f64s(dot(s, dv, delta), inv);
                let law = s.mul_add_f64s(ka[m], s.sub_f64s(l, rest[m]), s.mul_f64s(kc[m], rate));
                let scale = s.mul_f64s(law, inv);
                for r in 0..3 {
                    out[r][m] = s.mul_f64s(scale, delta[r]);
                }
            }
        }
        // Pass 2: each node pulls its springs' forces and its normal spring's.
        let nrm: [&[S::f64s]; 15] = std::array::from_fn(|e| at!(&t.normals[e], 0));
        let xs: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
        let vs: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&v.c[r], 0));
        let n = t.layout.n();
        let width = std::mem::size_of::<S::f64s>() / std::mem::size_of::<f64>();
        for m in 0..nch {
            let mut acc = [s.splat_f64s(0.0); 3];
            for class in &t.classes {
                let o = class.offset as isize;
                for r in 0..3 {
                    let fwd = at!(&class.force[r], 0)[m];
                    let bwd = at!(&class.force[r], -o)[m];
                    acc[r] = s.sub_f64s(s.add_f64s(acc[r], fwd), bwd);
                }
            }
            let xk = [xs[0][m], xs[1][m], xs[2][m]];
            let vk = [vs[0][m], vs[1][m], vs[2][m]];
            // The column: e = n₀·(x − anchor) − L₀, force −(f(e) + c n₀·v) n₀.
            let n0 = [nrm[N0][m], nrm[N0 + 1][m], nrm[N0 + 2][m]];
            let rel = std::array::from_fn(|r| s.sub_f64s(xk[r], nrm[ANCHOR + r][m]));
            let e = s.sub_f64s(dot(s, n0, rel), nrm[REST][m]);
            let law = s.div_f64s(e, s.mul_add_f64s(nrm[A][m], e, nrm[B][m]));
            let u: [S::f64s; 3] = std::array::from_fn(|r| s.sub_f64s(xk[r], nrm[XR + r][m]));
            let (nu, nv) = (dot(s, n0, u), dot(s, n0, vk));
            let axial = s.mul_add_f64s(nrm[C][m], nv, law);
            for r in 0..3 {
                // −k_t (u − n₀ (n₀·u)) − c_t (v − n₀ (n₀·v)).
                let tu = s.mul_add_f64s(s.neg_f64s(n0[r]), nu, u[r]);
                let tv = s.mul_add_f64s(s.neg_f64s(n0[r]), nv, vk[r]);
                let tangential = s.mul_add_f64s(nrm[KT][m], tu, s.mul_f64s(nrm[CT][m], tv));
                let along = s.mul_f64s(axial, n0[r]);
                acc[r] = s.sub_f64s(s.sub_f64s(acc[r], along), tangential);
            }
            let cols = [
                lanes::<S>(&acc[0]),
                lanes::<S>(&acc[1]),
                lanes::<S>(&acc[2]),
            ];
            for lane in 0..width {
                let k = m * width + lane;
                if k < n {
                    self.f[k] += Vec3::new(cols[0][lane], cols[1][lane], cols[2][lane]);
                }
            }
        }
    }
}

struct Assembly<'a> {
    t: &'a mut TissueStencil,
    alpha: f64,
    beta: f64,
    geometric: bool,
    classes: &'a mut [StencilClass],
    diag: &'a mut [Matrix3<f64>],
}

/// Adds `p d dᵀ + q I` to the symmetric entries `(00, 11, 22, 01, 02, 12)`.
#[inline(always)]
fn add_block<S: SimdSqrt>(s: S, d: [S::f64s; 3], p: S::f64s, q: S::f64s, e: &mut [S::f64s; 6]) {
    let pd = [
        s.mul_f64s(p, d[0]),
        s.mul_f64s(p, d[1]),
        s.mul_f64s(p, d[2]),
    ];
    for r in 0..3 {
        e[r] = s.add_f64s(e[r], s.mul_add_f64s(pd[r], d[r], q));
    }
    e[3] = s.mul_add_f64s(pd[0], d[1], e[3]);
    e[4] = s.mul_add_f64s(pd[0], d[2], e[4]);
    e[5] = s.mul_add_f64s(pd[1], d[2], e[5]);
}

impl SqrtKernel for Assembly<'_> {
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
        let x = &t.x;
        let (alpha, beta) = (s.splat_f64s(self.alpha), s.splat_f64s(self.beta));
        let zero = s.splat_f64s(0.0);
        // Pass 1: each class's (d, p, q) into the matrix's class arrays.
        for (class, out) in t.classes.iter().zip(self.classes.iter_mut()) {
            debug_assert_eq!(class.offset, out.offset);
            let o = class.offset as isize;
            let (ka, kc, rest) = (at!(&class.a, 0), at!(&class.c, 0), at!(&class.rest, 0));
            let xi: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
            let xj: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], o));
            let [d0, d1, d2] = &mut out.d;
            let d = [d0, d1, d2].map(|a| view_mut::<S>(a, pad, nr, nch));
            let p = view_mut::<S>(&mut out.p, pad, nr, nch);
            let q = view_mut::<S>(&mut out.q, pad, nr, nch);
            for m in 0..nch {
                let delta: [S::f64s; 3] = std::array::from_fn(|r| s.sub_f64s(xj[r][m], xi[r][m]));
                let (l, inv) = inverse_length(s, dot(s, delta, delta));
                let f = s.mul_f64s(ka[m], s.sub_f64s(l, rest[m]));
                let mut g = s.mul_f64s(f, inv);
                if !self.geometric {
                    g = s.select_f64s_m64s(s.less_than_f64s(f, zero), zero, g);
                }
                p[m] = s.mul_add_f64s(alpha, s.sub_f64s(ka[m], g), s.mul_f64s(beta, kc[m]));
                q[m] = s.mul_f64s(alpha, g);
                for r in 0..3 {
                    d[r][m] = s.mul_f64s(delta[r], inv);
                }
            }
        }
        // Pass 2: each node's diagonal block.
        let nrm: [&[S::f64s]; 15] = std::array::from_fn(|e| at!(&t.normals[e], 0));
        let xs: [&[S::f64s]; 3] = std::array::from_fn(|r| at!(&x.c[r], 0));
        let n = t.layout.n();
        let width = std::mem::size_of::<S::f64s>() / std::mem::size_of::<f64>();
        for m in 0..nch {
            let mut e = [zero; 6];
            for class in self.classes.iter() {
                let o = class.offset as isize;
                for shift in [0, -o] {
                    let d = std::array::from_fn(|r| at!(&class.d[r], shift)[m]);
                    add_block(
                        s,
                        d,
                        at!(&class.p, shift)[m],
                        at!(&class.q, shift)[m],
                        &mut e,
                    );
                }
            }
            // Normal column: (α f′ + β c) n₀n₀ᵀ + (α k_t + β c_t)(I − n₀n₀ᵀ),
            // i.e. p n₀n₀ᵀ + q I with p = α f′ + β c − q, q = α k_t + β c_t.
            let n0 = [0, 1, 2].map(|r| nrm[N0 + r][m]);
            let rel = std::array::from_fn(|r| s.sub_f64s(xs[r][m], nrm[ANCHOR + r][m]));
            let ev = s.sub_f64s(dot(s, n0, rel), nrm[REST][m]);
            let den = s.mul_add_f64s(nrm[A][m], ev, nrm[B][m]);
            let df = s.div_f64s(nrm[B][m], s.mul_f64s(den, den));
            let tan = s.mul_add_f64s(alpha, nrm[KT][m], s.mul_f64s(beta, nrm[CT][m]));
            let axial = s.mul_add_f64s(alpha, df, s.mul_f64s(beta, nrm[C][m]));
            add_block(s, n0, s.sub_f64s(axial, tan), tan, &mut e);
            let cols: [&[f64]; 6] = std::array::from_fn(|i| lanes::<S>(&e[i]));
            for lane in 0..width {
                let k = m * width + lane;
                if k < n {
                    let v = cols.map(|c| c[lane]);
                    let block = Matrix3::new(v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2]);
                    self.diag[k] -= block;
                }
            }
        }
    }
}
