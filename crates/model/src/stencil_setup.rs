//! The start of the SIMD PCG (issue 18) in one pass over the nodes, four
//! lanes at a time: the block-Jacobi preconditioner of
//! [`crate::pcg`]'s `block_jacobi_inverse` — the closed-form inverse
//! `cof(M)ᵀ / det M` of each diagonal block's symmetric part
//! `M = (D + Dᵀ)/2` where `M` is positive definite by Sylvester's criterion
//! (`m₀₀ > 0`, `m₀₀m₁₁ − m₀₁² > 0`, `det M > 0`), else scalar Jacobi on
//! `|diag D|` (1 where zero) — and the start residual
//! `r = S (b − A x)`, `z = P⁻¹ r`, with `|S b|²`, `rᵀ r` and `rᵀ z`.

// Component loops index several arrays at once.
#![allow(clippy::needless_range_loop)]

use crate::simd::{chunks, view, view_mut};
use crate::stencil::Soa3;
use pulp::{Simd, WithSimd};

/// Inputs and outputs of [`start`].
pub struct Start<'a> {
    /// Padding (nodes before node 0).
    pub pad: usize,
    /// Nodes processed.
    pub rounded: usize,
    /// Block-Jacobi (else the identity).
    pub jacobi: bool,
    /// Diagonal blocks, row-major entries.
    pub diag: &'a [Vec<f64>; 9],
    /// 1 on free nodes, 0 on fixed ones and the padding.
    pub free: &'a [f64],
    /// `A x`.
    pub q: &'a Soa3,
    /// In: `b`; out: `r = S (b − A x)`.
    pub r: &'a mut Soa3,
    /// Out: `z = P⁻¹ r`.
    pub z: &'a mut Soa3,
    /// Out: `P⁻¹` (row-major entries; zero on fixed nodes).
    pub inv: &'a mut [Vec<f64>; 9],
}

impl WithSimd for Start<'_> {
    /// `(|S b|², rᵀ r, rᵀ z)`.
    type Output = (f64, f64, f64);

    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> (f64, f64, f64) {
        let (pad, nr) = (self.pad, self.rounded);
        let nch = chunks::<S>(nr);
        let d: [&[S::f64s]; 9] = std::array::from_fn(|e| view::<S>(&self.diag[e], pad, nr, 0, nch));
        let q: [&[S::f64s]; 3] = std::array::from_fn(|c| view::<S>(&self.q.c[c], pad, nr, 0, nch));
        let free = view::<S>(self.free, pad, nr, 0, nch);
        let r = self.r.c.each_mut().map(|v| view_mut::<S>(v, pad, nr, nch));
        let z = self.z.c.each_mut().map(|v| view_mut::<S>(v, pad, nr, nch));
        let inv = self.inv.each_mut().map(|v| view_mut::<S>(v, pad, nr, nch));
        let (zero, one, half) = (s.splat_f64s(0.0), s.splat_f64s(1.0), s.splat_f64s(0.5));
        let (mut b2, mut rr, mut rz) = (zero, zero, zero);
        for m in 0..nch {
            let e = |i: usize| d[i][m];
            // Symmetric part.
            let (s00, s11, s22) = (e(0), e(4), e(8));
            let s01 = s.mul_f64s(half, s.add_f64s(e(1), e(3)));
            let s02 = s.mul_f64s(half, s.add_f64s(e(2), e(6)));
            let s12 = s.mul_f64s(half, s.add_f64s(e(5), e(7)));
            let minor = |a, b, c, d| s.sub_f64s(s.mul_f64s(a, b), s.mul_f64s(c, d));
            let c00 = minor(s11, s22, s12, s12);
            let c01 = minor(s02, s12, s01, s22);
            let c02 = minor(s01, s12, s02, s11);
            let c11 = minor(s00, s22, s02, s02);
            let c12 = minor(s01, s02, s00, s12);
            let c22 = minor(s00, s11, s01, s01);
            let det = s.mul_add_f64s(s02, c02, s.mul_add_f64s(s01, c01, s.mul_f64s(s00, c00)));
            let spd = s.and_m64s(
                s.and_m64s(
                    s.greater_than_f64s(s00, zero),
                    s.greater_than_f64s(c22, zero),
                ),
                s.greater_than_f64s(det, zero),
            );
            let f = free[m];
            let scale = s.div_f64s(f, det);
            // Fallback: 1/|d_rr| (1 where zero).
            let jac = |v| {
                let a = s.abs_f64s(v);
                let nz = s.greater_than_f64s(a, zero);
                s.mul_f64s(f, s.select_f64s_m64s(nz, s.div_f64s(one, a), one))
            };
            let full = [c00, c01, c02, c01, c11, c12, c02, c12, c22];
            let diag_only = [
                jac(s00),
                zero,
                zero,
                zero,
                jac(s11),
                zero,
                zero,
                zero,
                jac(s22),
            ];
            let ident = [f, zero, zero, zero, f, zero, zero, zero, f];
            let mut p = [zero; 9];
            for i in 0..9 {
                p[i] = if self.jacobi {
                    s.select_f64s_m64s(spd, s.mul_f64s(full[i], scale), diag_only[i])
                } else {
                    ident[i]
                };
                inv[i][m] = p[i];
            }
            let mut res = [zero; 3];
            for c in 0..3 {
                let bc = r[c][m];
                b2 = s.mul_add_f64s(s.mul_f64s(f, bc), bc, b2);
                res[c] = s.mul_f64s(f, s.sub_f64s(bc, q[c][m]));
                r[c][m] = res[c];
                rr = s.mul_add_f64s(res[c], res[c], rr);
            }
            for c in 0..3 {
                let zc = s.mul_add_f64s(
                    p[3 * c + 2],
                    res[2],
                    s.mul_add_f64s(p[3 * c + 1], res[1], s.mul_f64s(p[3 * c], res[0])),
                );
                z[c][m] = zc;
                rz = s.mul_add_f64s(res[c], zc, rz);
            }
        }
        (
            s.reduce_sum_f64s(b2),
            s.reduce_sum_f64s(rr),
            s.reduce_sum_f64s(rz),
        )
    }
}

/// Runs [`Start`], returning `(|S b|², rᵀ r, rᵀ z)`. Allocates nothing.
pub fn start(arch: pulp::Arch, op: Start<'_>) -> (f64, f64, f64) {
    arch.dispatch(op)
}
