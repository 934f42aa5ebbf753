//! The SIMD dispatch of the kernels that need a square root (issue 18):
//! `pulp`'s portable [`Simd`] trait has none, so these kernels are written
//! against [`SimdSqrt`] and run on x86-64 v3 (AVX2 + FMA, four f64 lanes)
//! when the CPU has it, else on `pulp`'s one-lane scalar type: the same
//! code, the same order of operations per lane.

use pulp::Simd;

/// A [`Simd`] with a correctly rounded square root.
pub trait SimdSqrt: Simd {
    /// `√a` per lane.
    fn sqrt_f64s(self, a: Self::f64s) -> Self::f64s;
}

#[cfg(target_arch = "x86_64")]
impl SimdSqrt for pulp::x86::V3 {
    #[inline(always)]
    fn sqrt_f64s(self, a: Self::f64s) -> Self::f64s {
        self.sqrt_f64x4(a)
    }
}

impl SimdSqrt for pulp::Scalar {
    #[inline(always)]
    fn sqrt_f64s(self, a: f64) -> f64 {
        a.sqrt()
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
