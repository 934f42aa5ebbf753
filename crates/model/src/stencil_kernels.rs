//! SIMD kernels on the [`StencilMatrix`] (issue 18): four-lane f64 with
//! fused multiply–add where the CPU has it (x86-64 v3: AVX2 + FMA, chosen
//! at run time by `pulp`, which falls back to scalar code elsewhere), over
//! structure-of-arrays vectors ([`Soa3`]). Each kernel computes the same
//! sums as its scalar counterpart in another order, each `a·b + c` rounded
//! once instead of twice: results differ from the scalar path by rounding
//! only (the tests bound it by `γ_T`, Higham §3.1).

// Component and lane loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

use crate::simd::{view, view_mut};
use crate::stencil::{Soa3, StencilClass, StencilMatrix, CHUNK, MAX_CLASSES};
use pulp::{Simd, WithSimd};

/// `E u` accumulated into `acc`: `acc += p (d·u) d + q u`, `E = p d dᵀ + q I`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn add_spring<S: Simd>(
    s: S,
    d: [S::f64s; 3],
    p: S::f64s,
    q: S::f64s,
    u: [S::f64s; 3],
    acc: &mut [S::f64s; 3],
) {
    let du = s.mul_add_f64s(
        d[2],
        u[2],
        s.mul_add_f64s(d[1], u[1], s.mul_f64s(d[0], u[0])),
    );
    let t = s.mul_f64s(p, du);
    for r in 0..3 {
        acc[r] = s.mul_add_f64s(t, d[r], s.mul_add_f64s(q, u[r], acc[r]));
    }
}

/// One class's arrays at the nodes (forward slot `k`), at `k − o` (the
/// slot of the spring from `k − o`), and `x` at `k + o` and `k − o`.
struct ClassView<'a, S: Simd> {
    fwd: [&'a [S::f64s]; 5],
    bwd: [&'a [S::f64s]; 5],
    x_fwd: [&'a [S::f64s]; 3],
    x_bwd: [&'a [S::f64s]; 3],
}

/// `y = (D + stencil) x` over all nodes, returning `xᵀ (D + stencil) x`.
struct Product<'a> {
    m: &'a StencilMatrix,
    classes: &'a [StencilClass],
    x: &'a Soa3,
    y: &'a mut Soa3,
}

impl<'a> WithSimd for Product<'a> {
    type Output = f64;

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> f64 {
        let layout = self.m.layout();
        let (pad, nr) = (layout.pad(), layout.rounded());
        let chunks = nr * std::mem::size_of::<f64>() / std::mem::size_of::<S::f64s>();
        let at = |v: &'a [f64], shift: isize| view::<S>(v, pad, nr, shift, chunks);
        let x: [&[S::f64s]; 3] = std::array::from_fn(|r| at(&self.x.c[r], 0));
        let d: [&[S::f64s]; 9] = std::array::from_fn(|e| at(&self.m.diag[e], 0));
        let empty: &[S::f64s] = &[];
        let mut views: [ClassView<S>; MAX_CLASSES] = std::array::from_fn(|_| ClassView {
            fwd: [empty; 5],
            bwd: [empty; 5],
            x_fwd: [empty; 3],
            x_bwd: [empty; 3],
        });
        let nc = self.classes.len();
        for (v, c) in views.iter_mut().zip(self.classes) {
            let o = c.offset as isize;
            let arrays = [&c.d[0], &c.d[1], &c.d[2], &c.p, &c.q];
            v.fwd = arrays.map(|a| at(a, 0));
            v.bwd = arrays.map(|a| at(a, -o));
            v.x_fwd = std::array::from_fn(|r| at(&self.x.c[r], o));
            v.x_bwd = std::array::from_fn(|r| at(&self.x.c[r], -o));
        }
        let [y0, y1, y2] = &mut self.y.c;
        let y0 = view_mut::<S>(y0, pad, nr, chunks);
        let y1 = view_mut::<S>(y1, pad, nr, chunks);
        let y2 = view_mut::<S>(y2, pad, nr, chunks);
        let mut quad = s.splat_f64s(0.0);
        for m in 0..chunks {
            let u = [x[0][m], x[1][m], x[2][m]];
            let mut acc = [s.splat_f64s(0.0); 3];
            for (r, a) in acc.iter_mut().enumerate() {
                let row = &d[3 * r..3 * r + 3];
                *a = s.mul_add_f64s(
                    row[2][m],
                    u[2],
                    s.mul_add_f64s(row[1][m], u[1], s.mul_f64s(row[0][m], u[0])),
                );
            }
            for v in &views[..nc] {
                let f = v.fwd;
                add_spring(
                    s,
                    [f[0][m], f[1][m], f[2][m]],
                    f[3][m],
                    f[4][m],
                    [v.x_fwd[0][m], v.x_fwd[1][m], v.x_fwd[2][m]],
                    &mut acc,
                );
                let b = v.bwd;
                add_spring(
                    s,
                    [b[0][m], b[1][m], b[2][m]],
                    b[3][m],
                    b[4][m],
                    [v.x_bwd[0][m], v.x_bwd[1][m], v.x_bwd[2][m]],
                    &mut acc,
                );
            }
            y0[m] = acc[0];
            y1[m] = acc[1];
            y2[m] = acc[2];
            quad = s.mul_add_f64s(
                u[2],
                acc[2],
                s.mul_add_f64s(u[1], acc[1], s.mul_add_f64s(u[0], acc[0], quad)),
            );
        }
        s.reduce_sum_f64s(quad)
    }
}

/// `y = (D + stencil) x` (`m`'s diagonal blocks and `classes`, of `m`'s
/// layout; not the leftovers), returning `xᵀ (D + stencil) x`. `x`'s
/// padding must be zero; `y`'s padding is left as it was. Allocates nothing.
pub fn stencil_product(
    arch: pulp::Arch,
    m: &StencilMatrix,
    classes: &[StencilClass],
    x: &Soa3,
    y: &mut Soa3,
) -> f64 {
    debug_assert_eq!(m.layout().rounded() % CHUNK, 0);
    debug_assert!(classes.len() <= MAX_CLASSES);
    arch.dispatch(Product { m, classes, x, y })
}

/// `p = z + β p` over the nodes.
struct Direction<'a> {
    pad: usize,
    rounded: usize,
    z: &'a Soa3,
    p: &'a mut Soa3,
    beta: f64,
}

impl WithSimd for Direction<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) {
        let (pad, nr) = (self.pad, self.rounded);
        let beta = s.splat_f64s(self.beta);
        for (p, z) in self.p.c.iter_mut().zip(&self.z.c) {
            let p = S::as_mut_simd_f64s(&mut p[pad..pad + nr]).0;
            let z = S::as_simd_f64s(&z[pad..pad + nr]).0;
            for (p, z) in p.iter_mut().zip(z) {
                *p = s.mul_add_f64s(beta, *p, *z);
            }
        }
    }
}

/// `p = z + β p` over the nodes (padding untouched). Allocates nothing.
pub fn update_direction(arch: pulp::Arch, z: &Soa3, p: &mut Soa3, beta: f64, pad: usize) {
    let rounded = z.c[0].len() - 2 * pad;
    arch.dispatch(Direction {
        pad,
        rounded,
        z,
        p,
        beta,
    })
}

/// The PCG update: `x += α p`, `r = free (r − α q)`, `z = P⁻¹ r`, and the
/// sums `rᵀ r`, `rᵀ z`.
pub struct Update<'a> {
    /// Padding (nodes before node 0).
    pub pad: usize,
    /// Nodes processed.
    pub rounded: usize,
    /// Step length α.
    pub alpha: f64,
    /// Search direction.
    pub p: &'a Soa3,
    /// `A p`.
    pub q: &'a Soa3,
    /// 1 on free nodes, 0 on fixed ones and the padding.
    pub free: &'a [f64],
    /// Preconditioner blocks (row-major entries; zero on fixed nodes).
    pub inv: &'a [Vec<f64>; 9],
    /// Iterate.
    pub x: &'a mut Soa3,
    /// Residual.
    pub r: &'a mut Soa3,
    /// Preconditioned residual.
    pub z: &'a mut Soa3,
}

impl<'a> WithSimd for Update<'a> {
    type Output = (f64, f64);

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> (f64, f64) {
        let (pad, nr) = (self.pad, self.rounded);
        let chunks = nr * std::mem::size_of::<f64>() / std::mem::size_of::<S::f64s>();
        let at = |v: &'a [f64]| view::<S>(v, pad, nr, 0, chunks);
        let p: [&[S::f64s]; 3] = std::array::from_fn(|r| at(&self.p.c[r]));
        let q: [&[S::f64s]; 3] = std::array::from_fn(|r| at(&self.q.c[r]));
        let inv: [&[S::f64s]; 9] = std::array::from_fn(|e| at(&self.inv[e]));
        let free = at(self.free);
        let x: [&mut [S::f64s]; 3] = self
            .x
            .c
            .each_mut()
            .map(|v| view_mut::<S>(v, pad, nr, chunks));
        let r: [&mut [S::f64s]; 3] = self
            .r
            .c
            .each_mut()
            .map(|v| view_mut::<S>(v, pad, nr, chunks));
        let z: [&mut [S::f64s]; 3] = self
            .z
            .c
            .each_mut()
            .map(|v| view_mut::<S>(v, pad, nr, chunks));
        let alpha = s.splat_f64s(self.alpha);
        let minus_alpha = s.splat_f64s(-self.alpha);
        let (mut rr, mut rz) = (s.splat_f64s(0.0), s.splat_f64s(0.0));
        for m in 0..chunks {
            let mut rm = [s.splat_f64s(0.0); 3];
            for c in 0..3 {
                x[c][m] = s.mul_add_f64s(alpha, p[c][m], x[c][m]);
                rm[c] = s.mul_f64s(free[m], s.mul_add_f64s(minus_alpha, q[c][m], r[c][m]));
                r[c][m] = rm[c];
                rr = s.mul_add_f64s(rm[c], rm[c], rr);
            }
            for c in 0..3 {
                let row = &inv[3 * c..3 * c + 3];
                let zc = s.mul_add_f64s(
                    row[2][m],
                    rm[2],
                    s.mul_add_f64s(row[1][m], rm[1], s.mul_f64s(row[0][m], rm[0])),
                );
                z[c][m] = zc;
                rz = s.mul_add_f64s(rm[c], zc, rz);
            }
        }
        (s.reduce_sum_f64s(rr), s.reduce_sum_f64s(rz))
    }
}

/// Runs [`Update`], returning `(rᵀ r, rᵀ z)`. Allocates nothing.
pub fn update(arch: pulp::Arch, u: Update<'_>) -> (f64, f64) {
    arch.dispatch(u)
}
