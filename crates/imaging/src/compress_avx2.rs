//! [`compress_column`](crate::stages::compress_column) eight pixels at a
//! time with AVX2 (issue 21): the loss `e^x` and the `log₂` of the echo's
//! power by polynomials instead of libm's scalar calls; every other
//! operation is the scalar loop's, in its order and without FMA.
//!
//! - `e^x` ([`exp_pd`], f64, four lanes): `x = n ln 2 + r` with `n` the
//!   nearest integer to `x / ln 2` and `r = (x − n ln2_hi) − n ln2_lo`
//!   (Cody–Waite: `ln2_hi` has 32 significant bits, so `n ln2_hi` is
//!   exact for `|n| < 2²¹`), `|r| ≤ ln 2 / 2`; `e^r` by its Taylor series
//!   to `r¹¹/11!` (truncation `≤ √2 (ln2/2)¹²/12! = 9·10⁻¹⁵` relative),
//!   times `2ⁿ` built in the exponent bits.
//! - `log₂ s` ([`log2_ps`], from f32, in f64): `s = m 2ᵉ` with
//!   `m ∈ [√½, √2)` from the float's bits, `log₂ m = (2/ln 2) atanh t`,
//!   `t = (m − 1)/(m + 1)`, `|t| ≤ 0.1716`, by its series to `t¹³/13`
//!   (truncation `≤ (2/ln 2) |t|¹⁵/15 / (1 − t²) = 1.1·10⁻¹³` absolute).
//!
//! Both are far below an f32's half ulp (`2⁻²⁴ = 6·10⁻⁸` relative), so the
//! f32 loss and `log₂` equal the correctly rounded values except within
//! `≈10⁻¹²` of a rounding midpoint; libm's `exp` (f64, < 1 ulp) rounded to
//! f32 and `log2f` (< 1 ulp) are off the correctly rounded f32 by at most one
//! ulp, hence so is the polynomial path off libm's. A gray level moves by
//! `a · ulp(log₂ s) ≤ 12.8 · 2⁻¹⁷ ≈ 10⁻⁴` ([`LogCompression::a`] ≤ 12.8
//! gray/unit of `log₂` at the 60 dB default range; `|log₂ s| < 128`), and
//! rounds to another level only within that of a half level: at most one
//! level apart, on a fraction of pixels of the order of `2 · 10⁻⁴` (gray
//! levels spread over many levels). The tests bound both.

use crate::stages::{Additive, FrameGeometry, LogCompression};
use std::arch::x86_64::*;

/// `ln 2` split for the reduction (fdlibm's): `LN2_HI` has 32 significant bits.
const LN2_HI: f64 = 6.931_471_803_691_238e-1;
/// `ln 2 − LN2_HI`.
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
/// `1.5 · 2⁵²`: added to a float of magnitude < 2⁵¹, rounds it to the
/// nearest integer (ties to even), held in the low mantissa bits.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// `e^x` of four lanes, `x` clamped to `[−700, 709]` (below, `e^x`
/// underflows an f32 all the same; above, it overflows an f64). Relative
/// error `< 2·10⁻¹⁴` (module doc; measured in the tests).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn exp_pd(x: __m256d) -> __m256d {
    // Lanes below −708 would give 2ⁿ with n < −1022 (the exponent field
    // would wrap): clamp at −700 (e^−700 = 10⁻³⁰⁴, 0 as an f32).
    let x = _mm256_min_pd(
        _mm256_max_pd(x, _mm256_set1_pd(-700.0)),
        _mm256_set1_pd(709.0),
    );
    let magic = _mm256_set1_pd(ROUND_MAGIC);
    let nm = _mm256_add_pd(
        _mm256_mul_pd(x, _mm256_set1_pd(std::f64::consts::LOG2_E)),
        magic,
    );
    let n = _mm256_sub_pd(nm, magic);
    let r = _mm256_sub_pd(
        _mm256_sub_pd(x, _mm256_mul_pd(n, _mm256_set1_pd(LN2_HI))),
        _mm256_mul_pd(n, _mm256_set1_pd(LN2_LO)),
    );
    // Horner from 1/11! down to 1.
    const INV_FACT: [f64; 12] = [
        1.0,
        1.0,
        1.0 / 2.0,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5040.0,
        1.0 / 40320.0,
        1.0 / 362_880.0,
        1.0 / 3_628_800.0,
        1.0 / 39_916_800.0,
    ];
    let mut p = _mm256_set1_pd(INV_FACT[11]);
    for &c in INV_FACT[..11].iter().rev() {
        p = _mm256_add_pd(_mm256_mul_pd(p, r), _mm256_set1_pd(c));
    }
    // 2ⁿ: the low bits of `nm` hold 2⁵¹ + n; (n + 1023) mod 2¹² shifted
    // into the exponent field (n + 1023 ∈ [13, 2046]: sign bit clear).
    let bits = _mm256_slli_epi64::<52>(_mm256_add_epi64(
        _mm256_castpd_si256(nm),
        _mm256_set1_epi64x(1023),
    ));
    _mm256_mul_pd(p, _mm256_castsi256_pd(bits))
}

/// `log₂ s` of eight positive normal f32 lanes, computed in f64 and
/// rounded to f32. Absolute error `< 10⁻¹²` before the rounding (module
/// doc; measured in the tests).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn log2_ps(s: __m256) -> __m256 {
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
    let lo = log2_half(_mm256_castps256_ps128(m), _mm256_castsi256_si128(e));
    let hi = log2_half(
        _mm256_extractf128_ps::<1>(m),
        _mm256_extracti128_si256::<1>(e),
    );
    _mm256_set_m128(hi, lo)
}

/// `e + log₂ m` of four lanes (`m ∈ [√½, √2)`), in f64, rounded to f32.
#[target_feature(enable = "avx2")]
#[inline]
fn log2_half(m: __m128, e: __m128i) -> __m128 {
    let m = _mm256_cvtps_pd(m);
    let one = _mm256_set1_pd(1.0);
    let t = _mm256_div_pd(_mm256_sub_pd(m, one), _mm256_add_pd(m, one));
    let t2 = _mm256_mul_pd(t, t);
    // atanh t / t = Σ t²ᵏ/(2k + 1), k = 0..6, by Horner.
    let mut p = _mm256_set1_pd(1.0 / 13.0);
    for k in (0..6).rev() {
        p = _mm256_add_pd(
            _mm256_mul_pd(p, t2),
            _mm256_set1_pd(1.0 / (2 * k + 1) as f64),
        );
    }
    let scale = _mm256_set1_pd(2.0 * std::f64::consts::LOG2_E);
    let l = _mm256_add_pd(
        _mm256_cvtepi32_pd(e),
        _mm256_mul_pd(_mm256_mul_pd(scale, t), p),
    );
    _mm256_cvtpd_ps(l)
}

/// The TGC gain `2 f α_TGC z · 100` (dB, f64 rounded to f32) of rows
/// `first .. first + 4`, `z = (i + ½) dz`; `k = 2 f α_TGC`.
#[target_feature(enable = "avx2")]
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
#[target_feature(enable = "avx2")]
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
/// `e^x` by [`exp_pd`], the `log₂` by [`log2_ps`]; clutter, noise, power,
/// TGC gain, clamp and rounding (half away from zero, as `f32::round`) the
/// scalar loop's floats.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
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
        let loss = _mm256_set_m128(_mm256_cvtpd_ps(exp_pd(x_hi)), _mm256_cvtpd_ps(exp_pd(x_lo)));
        let gain = _mm256_set_m128(gain4(k, g.dz, i as f64 + 4.0), gain4(k, g.dz, i as f64));
        let sq0 = echo_squares(px0, c0, nz0, ca, loss, namp, dup_lo);
        let sq1 = echo_squares(px1, c1, nz1, ca, loss, namp, dup_hi);
        // re² + im² per pixel: hadd gives rows (0 1 4 5 | 2 3 6 7).
        let power = _mm256_castpd_ps(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(
            _mm256_hadd_ps(sq0, sq1),
        )));
        let power = _mm256_max_ps(power, _mm256_set1_ps(1e-30));
        let level = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(a, log2_ps(power)), b),
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

    fn exp4(x: [f64; 4]) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: called only after the AVX2 check.
        unsafe {
            let v = exp_pd(_mm256_loadu_pd(x.as_ptr()));
            _mm256_storeu_pd(out.as_mut_ptr(), v);
        }
        out
    }

    fn log8(s: [f32; 8]) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: called only after the AVX2 check.
        unsafe {
            let v = log2_ps(_mm256_loadu_ps(s.as_ptr()));
            _mm256_storeu_ps(out.as_mut_ptr(), v);
        }
        out
    }

    /// Over the loss exponents a frame meets (0 down to −60 Np: a bone
    /// shadow's ≈ 30 dB/cm over 60 mm is −21 Np at 7.5 MHz, with margin),
    /// the polynomial `e^x` is within 2·10⁻¹⁴ of libm's relative (the
    /// series' truncation 9·10⁻¹⁵, module doc, plus the rounding of the
    /// reduction and Horner steps, a few 10⁻¹⁶, and libm's own < 1 ulp),
    /// and the f32 loss equals libm's rounded to f32 in all but a rare lane
    /// (a value within 2·10⁻¹⁴ of an f32 midpoint: a fraction ~
    /// 2·10⁻¹⁴/6·10⁻⁸ ≈ 3·10⁻⁷; bounded at 10⁻⁴).
    /// exp(0) is exactly 1 and the clamps give 0 and ∞ as an f32.
    #[test]
    fn exp_matches_libm_over_the_loss_range() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let (mut worst, mut f32_diff, trials) = (0.0f64, 0usize, 200_000);
        for _ in 0..trials / 4 {
            let x: [f64; 4] = std::array::from_fn(|_| rng.gen_range(-60.0..=0.0));
            for (got, &x) in exp4(x).iter().zip(&x) {
                let want = x.exp();
                worst = worst.max((got / want - 1.0).abs());
                f32_diff += usize::from(*got as f32 != want as f32);
            }
        }
        eprintln!("exp: max relative error {worst:e}, {f32_diff} of {trials} f32 losses differ");
        assert!(worst < 2e-14, "max relative error {worst:e}");
        assert!(
            (f32_diff as f64) < 1e-4 * trials as f64,
            "{f32_diff} f32 losses differ"
        );
        let e = exp4([0.0, -1000.0, 1000.0, 88.0]);
        assert_eq!(e[0], 1.0);
        assert_eq!(e[1] as f32, 0.0);
        assert_eq!(e[2] as f32, f32::INFINITY);
        assert!((e[3] / 88f64.exp() - 1.0).abs() < 2e-14);
    }

    /// Over the powers a frame's compression meets (the 10⁻³⁰ floor up to
    /// 10¹², log-uniformly), `log₂` is within 10⁻¹² of the f64 libm value
    /// before the f32 rounding (truncation 1.1·10⁻¹³, module doc, plus the
    /// f64 steps' rounding, ≈ 10⁻¹⁴ at `|log₂| < 128`), hence within one
    /// f32 ulp of libm's `log2f`; exact on powers of two.
    #[test]
    fn log2_matches_libm_over_the_power_range() {
        if !std::arch::is_x86_feature_detected!("avx2") {
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
                worst_ulps = worst_ulps.max((*got as f64 - s.log2() as f64).abs() / ulp as f64);
                assert!(
                    (*got as f64 - exact).abs() <= 0.5 * ulp as f64 + 1e-12,
                    "log2({s}) = {got}, libm f64 {exact}"
                );
            }
        }
        eprintln!("log2: at most {worst_ulps} f32 ulps from log2f");
        assert!(worst_ulps <= 1.0, "{worst_ulps} ulps from log2f");
        let p = log8([1.0, 2.0, 0.5, 1024.0, 1e-30, 3.0, 1.5, 1.41]);
        assert_eq!(&p[..4], &[0.0, 1.0, -1.0, 10.0]);
    }
}
