//! The SIMD dispatch of the kernels that need a square root or read
//! 3-vectors stored node after node (issue 18): `pulp`'s portable [`Simd`]
//! trait has neither, so these kernels are written against [`SimdSqrt`] and
//! run on x86-64 v3 (AVX2 + FMA, four f64 lanes) when the CPU has it, else
//! on `pulp`'s one-lane scalar type: the same code, the same order of
//! operations per lane.

use crate::Vec3;
use pulp::Simd;

/// A [`Simd`] with a correctly rounded square root and a load of
/// array-of-structures 3-vectors into structure-of-arrays lanes.
pub trait SimdSqrt: Simd {
    /// `√a` per lane.
    fn sqrt_f64s(self, a: Self::f64s) -> Self::f64s;

    /// The x, y and z components of `v`'s first [`Simd::F64_LANES`]
    /// vectors, one vector per lane (`v` holds at least that many): lane
    /// `l` of the first output is `v[l].x`, and so on. Exact (a copy).
    fn load_xyz(self, v: &[Vec3]) -> (Self::f64s, Self::f64s, Self::f64s);
}

#[cfg(target_arch = "x86_64")]
impl SimdSqrt for pulp::x86::V3 {
    #[inline(always)]
    fn sqrt_f64s(self, a: Self::f64s) -> Self::f64s {
        self.sqrt_f64x4(a)
    }

    /// Three loads of the 12 contiguous values, then two blends and one
    /// lane permutation per component.
    #[inline(always)]
    fn load_xyz(self, v: &[Vec3]) -> (Self::f64s, Self::f64s, Self::f64s) {
        use core::arch::x86_64::__m256d;
        let v = &v[..4];
        // a = [x0 y0 z0 x1], b = [y1 z1 x2 y2], c = [z2 x3 y3 z3].
        let a: __m256d = pulp::cast([v[0].x, v[0].y, v[0].z, v[1].x]);
        let b: __m256d = pulp::cast([v[1].y, v[1].z, v[2].x, v[2].y]);
        let c: __m256d = pulp::cast([v[2].z, v[3].x, v[3].y, v[3].z]);
        let (avx, avx2) = (self.avx, self.avx2);
        // Blend bit l set: lane l from the second operand.
        // [x0 y0 x2 x1] → [x0 x3 x2 x1] → lanes (0, 3, 2, 1).
        let x = avx._mm256_blend_pd::<0b0100>(a, b);
        let x = avx2._mm256_permute4x64_pd::<0b01_10_11_00>(avx._mm256_blend_pd::<0b0010>(x, c));
        // [y1 y0 z0 y2] → [y1 y0 y3 y2] → lanes (1, 0, 3, 2).
        let y = avx._mm256_blend_pd::<0b1001>(a, b);
        let y = avx2._mm256_permute4x64_pd::<0b10_11_00_01>(avx._mm256_blend_pd::<0b0100>(y, c));
        // [x0 z1 z0 x1] → [z2 z1 z0 z3] → lanes (2, 1, 0, 3).
        let z = avx._mm256_blend_pd::<0b0010>(a, b);
        let z = avx2._mm256_permute4x64_pd::<0b11_00_01_10>(avx._mm256_blend_pd::<0b1001>(z, c));
        (pulp::cast(x), pulp::cast(y), pulp::cast(z))
    }
}

impl SimdSqrt for pulp::Scalar {
    #[inline(always)]
    fn sqrt_f64s(self, a: f64) -> f64 {
        a.sqrt()
    }

    #[inline(always)]
    fn load_xyz(self, v: &[Vec3]) -> (f64, f64, f64) {
        (v[0].x, v[0].y, v[0].z)
    }
}

/// A kernel generic over [`SimdSqrt`].
pub trait SqrtKernel {
    /// What the kernel returns.
    type Output;
    /// Runs the kernel on `s`.
    fn run<S: SimdSqrt>(self, s: S) -> Self::Output;
}

/// Runs `op` with AVX2 + FMA enabled if the CPU has them, else on scalar lanes.
#[inline]
pub fn dispatch<K: SqrtKernel>(op: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = pulp::x86::V3::try_new() {
        return v3.vectorize(
            #[inline(always)]
            move || op.run(v3),
        );
    }
    op.run(pulp::Scalar::new())
}

/// The lanes of a SIMD vector as a slice.
#[inline(always)]
pub fn lanes<S: Simd>(v: &S::f64s) -> &[f64] {
    bytemuck::cast_slice(std::slice::from_ref(v))
}

/// The `chunks` SIMD vectors of the padded node range `[pad, pad + rounded)`
/// shifted by `shift` nodes (`|shift| ≤ pad`).
#[inline(always)]
pub fn view<S: Simd>(
    v: &[f64],
    pad: usize,
    rounded: usize,
    shift: isize,
    chunks: usize,
) -> &[S::f64s] {
    let start = (pad as isize + shift) as usize;
    let (head, tail) = S::as_simd_f64s(&v[start..start + rounded]);
    debug_assert!(tail.is_empty());
    &head[..chunks]
}

/// As [`view`], mutable and unshifted.
#[inline(always)]
pub fn view_mut<S: Simd>(
    v: &mut [f64],
    pad: usize,
    rounded: usize,
    chunks: usize,
) -> &mut [S::f64s] {
    let (head, tail) = S::as_mut_simd_f64s(&mut v[pad..pad + rounded]);
    debug_assert!(tail.is_empty());
    &mut head[..chunks]
}

/// SIMD vectors in `rounded` values.
#[inline(always)]
pub fn chunks<S: Simd>(rounded: usize) -> usize {
    rounded * std::mem::size_of::<f64>() / std::mem::size_of::<S::f64s>()
}
