//! [`compress_column`](crate::stages::compress_column) eight pixels at a
//! time with AVX2 and FMA (issue 21): the loss `e^x` and the `log₂` of the
//! echo's power by f32 polynomials instead of libm's scalar calls; every
//! other operation is the scalar loop's, in its order and without FMA.
//!
//! - `e^x` ([`exp_8`]): `x` (f64) clamped to `[−87, 88]` (an f32 `2ⁿ` stays
//!   normal), `n` the nearest integer to `x / ln 2` and `r = (x − n ln2_hi)
//!   − n ln2_lo` in f64 (Cody–Waite: `ln2_hi` has 32 significant bits, so
//!   `n ln2_hi` is exact), `|r| ≤ ln 2 / 2`, rounded to f32; `e^r` by
//!   Cephes' `expf` polynomial (Moshier 1989, "Methods and Programs for
//!   Mathematical Functions": `1 + r + r² P(r)`, `P` of degree 5), in f32
//!   with FMA, times `2ⁿ` built in the exponent bits.
//! - `log₂ s` ([`log2_8`]): `s = m 2ᵉ` with `m ∈ [√½, √2)` from the float's
//!   bits, `f = m − 1` (exact), `ln(1 + f) = f − f²/2 + f³ Q(f)` by Cephes'
//!   `logf` polynomial (`Q` of degree 8), then `e + ln · log₂ e`, in f32
//!   with FMA.
//!
//! In exact arithmetic the two polynomials are within 1.1·10⁻⁹ (relative,
//! `e^r` over `|r| ≤ ln 2/2`) and 1.2·10⁻⁹ (absolute, `ln(1 + f)`) of the
//! functions (evaluated on 200 001 points in f64); the f32 evaluation adds
//! its roundings, a few `2⁻²⁴ = 6·10⁻⁸` each, so the loss is within
//! `≈ 5·10⁻⁷` relative and `log₂` within two f32 ulps of libm's (the
//! tests measure both). A gray level moves by at most `a · (2 · 5·10⁻⁷
//! / ln 2 + 2 ulp(log₂ s)) ≤ 12.8 · (1.4·10⁻⁶ + 2⁻¹⁵) ≈ 4·10⁻⁴`
//! ([`LogCompression::a`] ≤ 12.8 gray per unit of `log₂` at the 60 dB
//! default range; `|log₂ s| < 128`), and rounds to another level only
//! within that of a half level: at most one level apart, on a fraction of
//! pixels of the order of 10⁻³ at the worst (gray levels spread over many
//! levels; `render::tests` bounds it on real frames). Before (stop 34)
//! both were f64 polynomials within 10⁻¹² of libm, four lanes at a time,
//! the `log₂` with a division: a third of the compression's time.

use crate::stages::{Additive, FrameGeometry, LogCompression};
use std::arch::x86_64::*;

/// `ln 2` split for the reduction (fdlibm's): `LN2_HI` has 32 significant bits.
const LN2_HI: f64 = 6.931_471_803_691_238e-1;
/// `ln 2 − LN2_HI`.
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;

/// Cephes `expf`'s `P` (highest degree first): `e^r ≈ 1 + r + r² P(r)`.
const EXP_P: [f32; 6] = [
    1.987_569_1e-4,
    1.398_199_9e-3,
    8.333_452e-3,
    4.166_579_6e-2,
    1.666_666_5e-1,
    5e-1, // Cephes: 5.0000001201e-1, the same f32
];

/// Cephes `logf`'s `Q` (highest degree first): `ln(1 + f) ≈ f − f²/2 + f³ Q(f)`.
const LOG_Q: [f32; 9] = [
    7.037_683_6e-2,
    -1.151_461e-1,
    1.167_699_9e-1,
    -1.242_014_1e-1,
    1.424_932_3e-1,
    -1.666_805_8e-1,
    2.000_071_4e-1,
    -2.499_999_4e-1,
    0.333_333_3, // Cephes: 3.3333331174e-1, the same f32
];

/// `r` (rounded to f32) and `n` of `x = n ln 2 + r` for four f64 lanes,
/// `x` clamped to `[−87, 88]` (module doc).
#[target_feature(enable = "avx2,fma")]
#[inline]
fn exp_reduce(x: __m256d) -> (__m128, __m128i) {
    let x = _mm256_min_pd(
        _mm256_max_pd(x, _mm256_set1_pd(-87.0)),
        _mm256_set1_pd(88.0),
    );
    let n = _mm256_round_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(_mm256_mul_pd(
        x,
        _mm256_set1_pd(std::f64::consts::LOG2_E),
    ));
    let r = _mm256_sub_pd(
        _mm256_sub_pd(x, _mm256_mul_pd(n, _mm256_set1_pd(LN2_HI))),
        _mm256_mul_pd(n, _mm256_set1_pd(LN2_LO)),
    );
    (_mm256_cvtpd_ps(r), _mm256_cvtpd_epi32(n))
}

/// `e^x` of eight lanes given as two f64 registers (`lo`: lanes 0–3),
/// as f32: the amplitude factor of a round-trip loss `x` (Np, from
/// `stages::column_loss`); `x` clamped to `[−87, 88]` (`e^−87 = 1.6·10⁻³⁸`, under which a
/// pixel's echo is under the noise all the same). Relative error
/// `< 5·10⁻⁷` (module doc; measured in the tests).
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(crate) fn exp_8(lo: __m256d, hi: __m256d) -> __m256 {
    let ((r_lo, n_lo), (r_hi, n_hi)) = (exp_reduce(lo), exp_reduce(hi));
    let r = _mm256_set_m128(r_hi, r_lo);
    let n = _mm256_set_m128i(n_hi, n_lo);
    let mut p = _mm256_set1_ps(EXP_P[0]);
    for &c in &EXP_P[1..] {
        p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(c));
    }
    let y = _mm256_fmadd_ps(
        p,
        _mm256_mul_ps(r, r),
        _mm256_add_ps(r, _mm256_set1_ps(1.0)),
    );
    // 2ⁿ, n + 127 ∈ [1, 254]: a normal f32.
    let two_n = _mm256_slli_epi32::<23>(_mm256_add_epi32(n, _mm256_set1_epi32(127)));
    _mm256_mul_ps(y, _mm256_castsi256_ps(two_n))
}

/// `log₂ s` of eight positive normal f32 lanes (`s` an echo's power,
/// envelope units squared, for the log compression). Within two f32 ulps of
/// libm's (module doc; measured in the tests).
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(crate) fn log2_8(s: __m256) -> __m256 {
    let bits = _mm256_castps_si256(s);
    let e = _mm256_sub_epi32(_mm256_srli_epi32::<23>(bits), _mm256_set1_epi32(127));
    let m = _mm256_castsi256_ps(_mm256_or_si256(
        _mm256_and_si256(bits, _mm256_set1_epi32(0x007f_ffff)),
        _mm256_set1_epi32(0x3f80_0000),
    ));
    // m ∈ [1, 2): above √2 halve it (exact) and raise e.
    let big = _mm256_cmp_ps::<_CMP_GE_OQ>(m, _mm256_set1_ps(std::f32::consts::SQRT_2));
    let m = _mm256_blendv_ps(m, _mm256_mul_ps(m, _mm256_set1_ps(0.5)), big);
    let e = _mm256_sub_epi32(e, _mm256_castps_si256(big)); // true lanes are −1
    let f = _mm256_sub_ps(m, _mm256_set1_ps(1.0));
    let mut q = _mm256_set1_ps(LOG_Q[0]);
    for &c in &LOG_Q[1..] {
        q = _mm256_fmadd_ps(q, f, _mm256_set1_ps(c));
    }
    let z = _mm256_mul_ps(f, f);
    // f − z/2 + f z Q
    let y = _mm256_fmadd_ps(
        _mm256_mul_ps(f, z),
        q,
        _mm256_fnmadd_ps(z, _mm256_set1_ps(0.5), f),
    );
    _mm256_fmadd_ps(
        y,
        _mm256_set1_ps(std::f32::consts::LOG2_E),
        _mm256_cvtepi32_ps(e),
    )
}

/// The TGC gain `2 f α_TGC z · 100` (dB, f64 rounded to f32) of rows
/// `first .. first + 4`, `z = (i + ½) dz`; `k = 2 f α_TGC`.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn gain4(k: f64, dz: f64, first: f64) -> __m128 {
    let steps = _mm256_setr_pd(0.5, 1.5, 2.5, 3.5);
    let zi = _mm256_mul_pd(
        _mm256_add_pd(_mm256_set1_pd(first), steps),
        _mm256_set1_pd(dz),
    );
    _mm256_cvtpd_ps(_mm256_mul_pd(
        _mm256_mul_pd(_mm256_set1_pd(k), zi),
        _mm256_set1_pd(100.0),
    ))
}

/// `|(px + ca c) loss + n_amp nz|²` parts of four pixels as interleaved
/// `(re², im²)` pairs; `ca` and `loss` hold eight pixels' values, of which
/// `dup` picks the four, each twice.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn echo_squares(
    px: __m256,
    clutter: __m256,
    noise: __m256,
    ca: __m256,
    loss: __m256,
    namp: __m256,
    dup: __m256i,
) -> __m256 {
    let (ca, l) = (
        _mm256_permutevar8x32_ps(ca, dup),
        _mm256_permutevar8x32_ps(loss, dup),
    );
    let v = _mm256_add_ps(
        _mm256_mul_ps(_mm256_add_ps(px, _mm256_mul_ps(ca, clutter)), l),
        _mm256_mul_ps(namp, noise),
    );
    _mm256_mul_ps(v, v)
}

/// [`compress_column`](crate::stages::compress_column) eight rows at a
/// time (the last `rows mod 8` through the scalar loop): the loss
/// `e^x` by [`exp_8`], the `log₂` by [`log2_8`]; clutter, noise, power,
/// TGC gain, clamp and rounding (half away from zero, as `f32::round`) the
/// scalar loop's floats.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(crate) fn compress_column_avx2(
    lc: &LogCompression,
    g: &FrameGeometry,
    iq: &[[f32; 2]],
    add: &Additive,
    loss_np: &[f64],
    gray: &mut [u8],
) {
    let n = gray
        .len()
        .min(iq.len())
        .min(loss_np.len())
        .min(add.clutter.len())
        .min(add.clutter_amp.len())
        .min(add.noise.len());
    let body = n / 8 * 8;
    // `2 f α_TGC` first, as the scalar `2.0 * f * tgc * zi * 100.0`
    // multiplies left to right.
    let k = 2.0 * lc.f_mhz * lc.tgc;
    let (a, b, c) = (
        _mm256_set1_ps(lc.a),
        _mm256_set1_ps(lc.b),
        _mm256_set1_ps(lc.c),
    );
    let namp = _mm256_set1_ps(add.noise_amp);
    let dup_lo = _mm256_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3);
    let dup_hi = _mm256_setr_epi32(4, 4, 5, 5, 6, 6, 7, 7);
    for i in (0..body).step_by(8) {
        // SAFETY (all loads and stores below): `i + 8 ≤ body ≤` the length
        // of every slice read (complex slices: 16 floats from `2i`).
        let (x_lo, x_hi, px0, px1, c0, c1, nz0, nz1, ca) = unsafe {
            let xp = loss_np.as_ptr().add(i);
            let pp = iq.as_ptr().add(i).cast::<f32>();
            let cp = add.clutter.as_ptr().add(i).cast::<f32>();
            let np = add.noise.as_ptr().add(i).cast::<f32>();
            (
                _mm256_loadu_pd(xp),
                _mm256_loadu_pd(xp.add(4)),
                _mm256_loadu_ps(pp),
                _mm256_loadu_ps(pp.add(8)),
                _mm256_loadu_ps(cp),
                _mm256_loadu_ps(cp.add(8)),
                _mm256_loadu_ps(np),
                _mm256_loadu_ps(np.add(8)),
                _mm256_loadu_ps(add.clutter_amp.as_ptr().add(i)),
            )
        };
        let loss = exp_8(x_lo, x_hi);
        let gain = _mm256_set_m128(gain4(k, g.dz, i as f64 + 4.0), gain4(k, g.dz, i as f64));
        let sq0 = echo_squares(px0, c0, nz0, ca, loss, namp, dup_lo);
        let sq1 = echo_squares(px1, c1, nz1, ca, loss, namp, dup_hi);
        // re² + im² per pixel: hadd gives rows (0 1 4 5 | 2 3 6 7).
        let power = _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(
            _mm256_hadd_ps(sq0, sq1),
        )));
        let power = _mm256_max_ps(power, _mm256_set1_ps(1e-30));
        let level = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(a, log2_8(power)), b),
            _mm256_mul_ps(c, gain),
        );
        let level = _mm256_min_ps(
            _mm256_max_ps(level, _mm256_setzero_ps()),
            _mm256_set1_ps(255.0),
        );
        // Half away from zero on [0, 255]: trunc, plus 1 where the
        // (exact) fraction is ≥ ½.
        let t = _mm256_round_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(level);
        let up = _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_sub_ps(level, t), _mm256_set1_ps(0.5));
        let r = _mm256_add_ps(t, _mm256_and_ps(up, _mm256_set1_ps(1.0)));
        let mut q = [0i32; 8];
        // SAFETY: `q` holds 8 i32.
        unsafe { _mm256_storeu_si256(q.as_mut_ptr().cast(), _mm256_cvttps_epi32(r)) };
        for (o, v) in gray[i..i + 8].iter_mut().zip(q) {
            *o = v as u8;
        }
    }
    if body < n {
        let tail = Additive {
            clutter: &add.clutter[body..n],
            clutter_amp: &add.clutter_amp[body..n],
            noise: &add.noise[body..n],
            noise_amp: add.noise_amp,
        };
        let rows = body..n;
        crate::stages::compress_rows(
            lc,
            g,
            body,
            &iq[rows.clone()],
            &tail,
            &loss_np[rows.clone()],
            &mut gray[rows],
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn exp8(x: [f64; 8]) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: called only after the AVX2 and FMA check.
        unsafe {
            let v = exp_8(
                _mm256_loadu_pd(x.as_ptr()),
                _mm256_loadu_pd(x.as_ptr().add(4)),
            );
            _mm256_storeu_ps(out.as_mut_ptr(), v);
        }
        out
    }

    fn log8(s: [f32; 8]) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: called only after the AVX2 and FMA check.
        unsafe {
            let v = log2_8(_mm256_loadu_ps(s.as_ptr()));
            _mm256_storeu_ps(out.as_mut_ptr(), v);
        }
        out
    }

    fn has_avx2_fma() -> bool {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }

    /// Over the loss exponents a frame meets (0 down to −60 Np: a bone
    /// shadow's ≈ 30 dB/cm over 60 mm is −21 Np at 7.5 MHz, with margin),
    /// the f32 `e^x` is within 5·10⁻⁷ of libm's f64 relative: the
    /// polynomial's 1.1·10⁻⁹ (module doc), `r`'s rounding to f32 (half an
    /// ulp of `|r| ≤ 0.35`, 1.5·10⁻⁸ absolute, as much relative in `e^r`),
    /// the five FMAs of Horner and the last three operations (each ≤ 2⁻²⁴
    /// relative, eight of them: 4.8·10⁻⁷ if all add up; in practice they
    /// partly cancel). `e^0` is 1 within that, and the clamps give
    /// `e^−87` and `e^88`.
    #[test]
    fn exp_matches_libm_over_the_loss_range() {
        if !has_avx2_fma() {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut worst = 0.0f64;
        for _ in 0..200_000 / 8 {
            let x: [f64; 8] = std::array::from_fn(|_| rng.gen_range(-60.0..=0.0));
            for (got, &x) in exp8(x).iter().zip(&x) {
                worst = worst.max((*got as f64 / x.exp() - 1.0).abs());
            }
        }
        eprintln!("exp: max relative error {worst:e}");
        assert!(worst < 5e-7, "max relative error {worst:e}");
        let e = exp8([0.0, -1000.0, 1000.0, 88.0, -87.0, -1.0, 1.0, 0.5]);
        let rel = |got: f32, want: f64| (got as f64 / want - 1.0).abs();
        assert!(rel(e[0], 1.0) < 5e-7);
        assert!(rel(e[1], (-87f64).exp()) < 5e-7, "clamped below: {}", e[1]);
        assert!(rel(e[2], 88f64.exp()) < 5e-7, "clamped above: {}", e[2]);
        assert!(rel(e[3], 88f64.exp()) < 5e-7 && rel(e[4], (-87f64).exp()) < 5e-7);
    }

    /// Over the powers a frame's compression meets (the 10⁻³⁰ floor up to
    /// 10¹², log-uniformly), `log₂` is within two f32 ulps of libm's f64
    /// value: the result's own rounding (half an ulp), and the `ln` part's
    /// error (the polynomial's 1.2·10⁻⁹ and the f32 steps' ≈ 2⁻²⁴ · |ln m|,
    /// |ln m| ≤ 0.35) scaled by log₂ e, under one ulp of the result
    /// wherever `e ≠ 0` (|result| ≥ 0.5) and a few ulps of `|ln m|` where
    /// `e = 0` (bounded there by 2⁻²² absolute). Exact on powers of two.
    #[test]
    fn log2_matches_libm_over_the_power_range() {
        if !has_avx2_fma() {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut worst_ulps = 0.0f64;
        for _ in 0..100_000 / 8 {
            let s: [f32; 8] = std::array::from_fn(|_| 10f32.powf(rng.gen_range(-30.0..12.0)));
            for (got, &s) in log8(s).iter().zip(&s) {
                let exact = (s as f64).log2();
                let ulp = (exact as f32).abs().max(f32::MIN_POSITIVE);
                let ulp = f32::from_bits(ulp.to_bits() + 1) - ulp;
                let err = (*got as f64 - exact).abs();
                if exact.abs() >= 0.5 {
                    worst_ulps = worst_ulps.max(err / ulp as f64);
                } else {
                    assert!(err <= 2f64.powi(-22), "log2({s}) = {got}, libm f64 {exact}");
                }
            }
        }
        eprintln!("log2: at most {worst_ulps} f32 ulps from libm");
        assert!(worst_ulps <= 2.0, "{worst_ulps} ulps from libm");
        let p = log8([1.0, 2.0, 0.5, 1024.0, 1e-30, 3.0, 1.5, 1.41]);
        assert_eq!(&p[..4], &[0.0, 1.0, -1.0, 10.0]);
    }
}
