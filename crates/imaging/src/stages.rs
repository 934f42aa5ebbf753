//! The per-column stages of a frame, run by the renderer: axial splat of
//! the scatterers (complex baseband PSF), lateral convolution, and
//! attenuation/TGC plus log compression.

use crate::anatomy::{Anatomy, MAX_BREAKPOINTS};
use crate::deformation::column_depth;
use crate::psf::{safe_log2, PsfTables, BLOCK_ROWS, PHASE_STEPS};
use crate::pulse::AXIAL_SUBSTEPS;
use crate::warp::WarpSet;

/// Frame-wide quantities the column stages read.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrameGeometry {
    /// Depth of the probe face below the undeformed skin (m).
    pub face: f64,
    /// Depth of the femur below the undeformed skin, end of the column compression (m).
    pub bone: f64,
    /// Axial pixel pitch (m).
    pub dz: f64,
    /// Image rows.
    pub rows: usize,
    /// Padding rows above and below the image in the splat buffer.
    pub pad: usize,
}

/// Image depth below the face (m) of the tissue point at `depth` (m) in a
/// column with skin displacement `surface` (m) and the vessels' `warps`.
#[inline]
pub(crate) fn image_depth(g: &FrameGeometry, surface: f64, warps: &WarpSet, depth: f64) -> f64 {
    let d = warps.apply(depth);
    column_depth(surface, g.bone, d) - g.face
}

/// Scatterers whose setup [`splat_column`] computes together: two AVX2
/// registers of f64 lanes, on the stack (nothing allocated per frame).
const SPLAT_BATCH: usize = 8;

/// Clears the padded column `out` and splats into it (see [`splat_add`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn splat_column<const AVX2: bool>(
    t: &PsfTables,
    g: &FrameGeometry,
    elev: &[f32],
    depth: &[f32],
    amp: &[[f32; 2]],
    surface: f64,
    warps: &WarpSet,
    out: &mut [[f32; 2]],
) {
    out.fill([0.0, 0.0]);
    splat_add::<AVX2>(t, g, elev, depth, amp, surface, warps, out);
}

/// Adds the axial PSF of each scatterer of one bin into its padded column
/// `out` (`rows + 2·pad` complex samples), weighted by the
/// elevation weight `elev` of its splat row (`row + pad`). The per-scatterer
/// setup (depth through the deformation, row, sub-row, phase) is computed
/// [`SPLAT_BATCH`] scatterers at a time, then their taps are added one
/// scatterer after the other: the same float operations per scatterer, in
/// the same order into `out`. `AVX2`: the caller runs with AVX2 enabled
/// (see [`add_taps`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn splat_add<const AVX2: bool>(
    t: &PsfTables,
    g: &FrameGeometry,
    elev: &[f32],
    depth: &[f32],
    amp: &[[f32; 2]],
    surface: f64,
    warps: &WarpSet,
    out: &mut [[f32; 2]],
) {
    let ax = &t.axial;
    let k = ax.half;
    let taps = 2 * k;
    let inv_dz = 1.0 / g.dz;
    let lowest = -(k as f64) - 1.0;
    let highest = (g.rows + k) as f64;
    let any_warp = warps.is_active();
    let last = elev.len() as i64 - 1;
    let phase_mask = PHASE_STEPS as i32 - 1;
    for (ds, amps) in depth.chunks(SPLAT_BATCH).zip(amp.chunks(SPLAT_BATCH)) {
        // Setup of the batch, lane by lane without branches (the compiler
        // takes several lanes per instruction): image depth, fractional row,
        // its floor, sub-row and phase index. Lanes past the batch's end, and
        // lanes the loop below skips or stops at, are computed for nothing.
        let mut z = [0.0f64; SPLAT_BATCH];
        if any_warp {
            for (zk, &d) in z.iter_mut().zip(ds) {
                *zk = image_depth(g, surface, warps, d as f64);
            }
        } else {
            for (zk, &d) in z.iter_mut().zip(ds) {
                *zk = column_depth(surface, g.bone, d as f64) - g.face;
            }
        }
        let mut r = [0.0f64; SPLAT_BATCH];
        let mut fl = [0i32; SPLAT_BATCH];
        let mut q = [0i32; SPLAT_BATCH];
        let mut ph = [0i32; SPLAT_BATCH];
        for l in 0..SPLAT_BATCH {
            let rl = z[l] * inv_dz - 0.5;
            let f = rl.floor();
            r[l] = rl;
            // For a splatted scatterer r − fl ∈ [0, 1) and −K − 1 ≤ fl <
            // rows + K: the conversions through i32 give what the saturating
            // ones to usize/i64 would, and clamping the sub-row at 63 before
            // the truncation gives what clamping after it would.
            q[l] = ((rl - f) * AXIAL_SUBSTEPS as f64).min((AXIAL_SUBSTEPS - 1) as f64) as i32;
            fl[l] = f as i32;
            // |z · 2k₀/2π · 4096| < 2³¹ for |z| < 53 m: the i32 truncation
            // is the i64 one, and its low 12 bits the same.
            ph[l] = (z[l] * t.phase_per_metre) as i32 & phase_mask;
        }
        for (l, a) in amps.iter().enumerate() {
            if r[l] < lowest {
                continue;
            }
            if r[l] >= highest {
                return; // depths are sorted and the map is increasing
            }
            let p = t.phase[ph[l] as usize];
            let fi = fl[l] as i64;
            let e = elev[(fi + g.pad as i64).clamp(0, last) as usize];
            let c = [
                e * (a[0] * p[0] - a[1] * p[1]),
                e * (a[0] * p[1] + a[1] * p[0]),
            ];
            // First tap: row fl − K + 1, at index fl − K + 1 + pad ≥ 0.
            let first = (fi - k as i64 + 1 + g.pad as i64) as usize;
            // `ax.knot(r)` from its table (no division).
            let knot = ax.row_knot[fi.max(0) as usize] as usize;
            let base = (knot * AXIAL_SUBSTEPS + q[l] as usize) * taps;
            add_taps::<AVX2>(
                &mut out[first..first + taps],
                &ax.taps[base..base + taps],
                c,
            );
        }
    }
}

/// `out[t] += c · w[t]` (complex) for every tap `t` (`out` and `w` of one
/// length): `re += c₀w₀ − c₁w₁`, `im += c₀w₁ + c₁w₀`, one tap at a time, or
/// with `AVX2` four taps per instruction ([`add_taps_avx2`]), which computes
/// the same floats.
#[inline(always)]
fn add_taps<const AVX2: bool>(out: &mut [[f32; 2]], w: &[[f32; 2]], c: [f32; 2]) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is true only in the code that `Renderer::stages_avx2`
        // runs, after the CPU was found to have AVX2.
        unsafe { add_taps_avx2(out, w, c) };
        return;
    }
    for (o, wk) in out.iter_mut().zip(w) {
        o[0] += c[0] * wk[0] - c[1] * wk[1];
        o[1] += c[0] * wk[1] + c[1] * wk[0];
    }
}

/// [`add_taps`] four taps (eight interleaved floats) at a time, in place:
/// `a = c₀ (w₀, w₁)`, `b = c₁ (w₁, w₀)` (the pair swapped in its lane),
/// then `addsub(a, b) = (c₀w₀ − c₁w₁, c₀w₁ + c₁w₀)` added to `out`: per lane
/// the scalar loop's products, difference or sum and accumulation, in the
/// same order and without FMA contraction, so the same floats, without
/// splitting real and imaginary parts apart and back. Two taps left over
/// (`w.len()` is even, `2K`) go through the 128-bit form of the same steps,
/// a last odd tap through the scalar loop.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline] // into the AVX2 splat: a call per scatterer costs as much as its taps
fn add_taps_avx2(out: &mut [[f32; 2]], w: &[[f32; 2]], c: [f32; 2]) {
    use std::arch::x86_64::*;
    let n = out.len().min(w.len());
    let (out, w) = (&mut out[..n], &w[..n]);
    let (o4, o_rest) = out.as_chunks_mut::<4>();
    let (w4, w_rest) = w.as_chunks::<4>();
    let (c0, c1) = (_mm256_set1_ps(c[0]), _mm256_set1_ps(c[1]));
    for (o, wk) in o4.iter_mut().zip(w4) {
        // SAFETY: 4 × [f32; 2] = 8 contiguous f32 behind each reference;
        // unaligned loads and stores.
        unsafe {
            let wv = _mm256_loadu_ps(wk.as_ptr().cast());
            let ws = _mm256_permute_ps::<0b10_11_00_01>(wv);
            let t = _mm256_addsub_ps(_mm256_mul_ps(c0, wv), _mm256_mul_ps(c1, ws));
            let op = o.as_mut_ptr().cast::<f32>();
            _mm256_storeu_ps(op, _mm256_add_ps(_mm256_loadu_ps(op), t));
        }
    }
    let (o2, o_last) = o_rest.as_chunks_mut::<2>();
    let (w2, w_last) = w_rest.as_chunks::<2>();
    let (c0, c1) = (_mm_set1_ps(c[0]), _mm_set1_ps(c[1]));
    for (o, wk) in o2.iter_mut().zip(w2) {
        // SAFETY: 2 × [f32; 2] = 4 contiguous f32 behind each reference.
        unsafe {
            let wv = _mm_loadu_ps(wk.as_ptr().cast());
            let ws = _mm_permute_ps::<0b10_11_00_01>(wv);
            let t = _mm_addsub_ps(_mm_mul_ps(c0, wv), _mm_mul_ps(c1, ws));
            let op = o.as_mut_ptr().cast::<f32>();
            _mm_storeu_ps(op, _mm_add_ps(_mm_loadu_ps(op), t));
        }
    }
    for (o, wk) in o_last.iter_mut().zip(w_last) {
        o[0] += c[0] * wk[0] - c[1] * wk[1];
        o[1] += c[0] * wk[1] + c[1] * wk[0];
    }
}

/// Output column `j` of the lateral convolution with the depth-dependent
/// lateral profile: `out[i] = Σ_k h_i[k] rf[j + H + k][i]` over the padded
/// bins (`H` the halo), unpadded rows, each block of rows over its own
/// half-width ([`convolve_tail`] block by block).
#[inline(always)]
pub(crate) fn convolve_column(
    t: &PsfTables,
    rf: &[[f32; 2]],
    padded_rows: usize,
    pad: usize,
    j: usize,
    out: &mut [[f32; 2]],
) {
    let rows = out.len();
    for (blk, chunk) in out.chunks_mut(BLOCK_ROWS).enumerate() {
        convolve_tail(t, rf, padded_rows, pad, rows, blk, j, chunk);
    }
}

/// The lateral convolution of the whole frame into `iq` (column-major,
/// `rows` per column): [`convolve_column`] of every column, or with `AVX2`
/// its full blocks through [`convolve_block_avx2`] block by block over all
/// the columns, then the last partial block of each column by
/// [`convolve_column`]'s loop. Block-major order keeps the block's
/// `2H + 1` source columns (16 rows each, ≈ 12 kB) and weights in L1 from
/// one output column to the next, where the column-major order streamed
/// the `2H + 1` whole columns (≈ 0.7 MB) from L2 for every output column.
/// The same floats either way (each pixel's sum in the same order).
#[inline(always)]
pub(crate) fn convolve_frame<const AVX2: bool>(
    t: &PsfTables,
    rf: &[[f32; 2]],
    padded_rows: usize,
    pad: usize,
    rows: usize,
    iq: &mut [[f32; 2]],
) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        let cols = iq.len() / rows;
        let hh = t.lat_half;
        let full = rows / BLOCK_ROWS;
        for blk in 0..full {
            let h = t.block_half[blk];
            let i0 = blk * BLOCK_ROWS;
            let w = &t.lateral_pairs[(hh - h) * rows + i0..];
            // Two output columns at a time: eight independent sums hide
            // the latency of the additions (each sum still adds its terms
            // in order), and the two columns share the weights' loads.
            let mut j = 0;
            while j < cols {
                let pair = j + 1 < cols;
                let s0 = (j + hh - h) * padded_rows + pad + i0;
                let (a, b) = iq[j * rows..].split_at_mut(rows);
                let out_a: &mut [[f32; 2]; BLOCK_ROWS] = (&mut a[i0..i0 + BLOCK_ROWS])
                    .try_into()
                    .expect("full block");
                let out_b: Option<&mut [[f32; 2]; BLOCK_ROWS]> = pair.then(|| {
                    (&mut b[i0..i0 + BLOCK_ROWS])
                        .try_into()
                        .expect("full block")
                });
                // The two source columns that the pair `PREFETCH_PAIRS`
                // further on reads and the pairs before it do not (its
                // last two), fetched ahead.
                for c in [2 * h + 2 * PREFETCH_PAIRS, 2 * h + 2 * PREFETCH_PAIRS + 1] {
                    prefetch_rows(rf, s0 + c * padded_rows);
                }
                // SAFETY: `AVX2` is true only in the code that
                // `Renderer::stages_avx2` runs, after the CPU was found
                // to have AVX2.
                unsafe {
                    convolve_block_avx2(w, rows, &rf[s0..], padded_rows, 2 * h + 1, out_a, out_b)
                };
                j += 2;
            }
        }
        if full * BLOCK_ROWS < rows {
            let mut one = [[0.0f32; 2]; BLOCK_ROWS];
            let n = rows - full * BLOCK_ROWS;
            for j in 0..cols {
                // The last block alone: `convolve_column` of a column of
                // that block's rows, written into the frame's column.
                convolve_tail(t, rf, padded_rows, pad, rows, full, j, &mut one[..n]);
                iq[j * rows + full * BLOCK_ROWS..(j + 1) * rows].copy_from_slice(&one[..n]);
            }
        }
        return;
    }
    for (j, col) in iq.chunks_mut(rows).enumerate() {
        convolve_column(t, rf, padded_rows, pad, j, col);
    }
}

/// Output pairs ahead whose new source columns [`convolve_frame`]
/// prefetches: one pair's arithmetic (`2H + 1` offsets × 4 registers, a few
/// hundred cycles) covers a fetch from L3, two leave a margin.
const PREFETCH_PAIRS: usize = 2;

/// Asks for the cache lines of the block of [`BLOCK_ROWS`] complex rows
/// at `rf[start..]` (its first and last byte; nothing past `rf`'s end).
/// The block-major convolution steps through the source columns
/// `padded_rows` apart (≈ 7 kB at 864 rows), a stride across pages that
/// the hardware prefetchers do not follow, and the frame's field (≈ 4 MB)
/// does not stay in L2 between blocks: without this each new column waits
/// on L3. A hint only: the floats are unchanged.
#[inline(always)]
fn prefetch_rows(rf: &[[f32; 2]], start: usize) {
    #[cfg(target_arch = "x86_64")]
    if start + BLOCK_ROWS <= rf.len() {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let block = &rf[start..start + BLOCK_ROWS];
        // SAFETY: `_mm_prefetch` only hints the cache (no access, no
        // fault); SSE, part of x86_64's baseline.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().cast());
            _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().add(BLOCK_ROWS - 1).cast());
        }
    }
}

/// Block `blk` (rows `blk · 16 ..`, `out.len()` of them) of output column
/// `j`. The profile is even (`h_i[−k] = h_i[k]`, [`PsfTables::lateral`]), so
/// the two sources at `±k` are added first and weighted once, in order:
/// `acc ← fma(h[k], s[k] + s[−k], acc)` for `k = −h … −1` from a zero sum,
/// then `fma(h[0], s[0], acc)`: half the products of the plain sum, each
/// term rounded once.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn convolve_tail(
    t: &PsfTables,
    rf: &[[f32; 2]],
    padded_rows: usize,
    pad: usize,
    rows: usize,
    blk: usize,
    j: usize,
    out: &mut [[f32; 2]],
) {
    let hh = t.lat_half as i64;
    let h = t.block_half[blk] as i64;
    let i0 = blk * BLOCK_ROWS;
    let n = out.len();
    let weights = |k: i64| &t.lateral[(k + hh) as usize * rows + i0..][..n];
    let source = |k: i64| {
        let start = (j as i64 + hh + k) as usize * padded_rows + pad + i0;
        &rf[start..start + n]
    };
    out.fill([0.0, 0.0]);
    for k in -h..0 {
        for (((o, &wk), a), b) in out
            .iter_mut()
            .zip(weights(k))
            .zip(source(k))
            .zip(source(-k))
        {
            o[0] = wk.mul_add(a[0] + b[0], o[0]);
            o[1] = wk.mul_add(a[1] + b[1], o[1]);
        }
    }
    for ((o, &wk), a) in out.iter_mut().zip(weights(0)).zip(source(0)) {
        o[0] = wk.mul_add(a[0], o[0]);
        o[1] = wk.mul_add(a[1], o[1]);
    }
}

/// One full block of [`convolve_column`] with AVX2 and FMA for one output
/// column, `out_a`, and the next one, `out_b` if any, over the `n = 2h + 1`
/// offsets: weights `w_m` at `w[m · w_stride..]` (as pairs,
/// [`PsfTables::lateral_pairs`]), sources `s_m` at `s[m · s_stride..]` for
/// `out_a`, one source column (`s_stride`) further for `out_b`. As
/// [`convolve_tail`]: `acc ← fma(w_m, s_m + s_{n−1−m}, acc)` for `m < h`
/// from a zero sum, then `fma(w_h, s_h, acc)` (the profile is even:
/// `w_m = w_{n−1−m}`). Sixteen complex rows are four registers of
/// interleaved `(re, im)` pairs: the scalar loop's floats.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn convolve_block_avx2(
    w: &[[f32; 2]],
    w_stride: usize,
    s: &[[f32; 2]],
    s_stride: usize,
    n: usize,
    out_a: &mut [[f32; 2]; BLOCK_ROWS],
    out_b: Option<&mut [[f32; 2]; BLOCK_ROWS]>,
) {
    use std::arch::x86_64::*;
    const _: () = assert!(BLOCK_ROWS == 16);
    let extra = usize::from(out_b.is_some());
    assert!(n % 2 == 1 && w.len() >= (n - 1) * w_stride + BLOCK_ROWS);
    assert!(s.len() >= (n - 1 + extra) * s_stride + BLOCK_ROWS);
    let h = n / 2;
    let mut acc = [_mm256_setzero_ps(); 4];
    let mut acc_b = [_mm256_setzero_ps(); 4];
    let (wp, sp) = (w.as_ptr().cast::<f32>(), s.as_ptr().cast::<f32>());
    // SAFETY (every load below): 8 floats (4 rows) within `w` and `s`
    // (asserted above, the next column included when `extra`); unaligned.
    let load = |p: *const f32, at: usize| unsafe { _mm256_loadu_ps(p.add(at)) };
    for m in 0..=h {
        let (wk, lo, hi) = (
            2 * m * w_stride,
            2 * m * s_stride,
            2 * (n - 1 - m) * s_stride,
        );
        for q in 0..4 {
            let wv = load(wp, wk + 8 * q);
            let (a, b) = if m < h {
                (
                    _mm256_add_ps(load(sp, lo + 8 * q), load(sp, hi + 8 * q)),
                    (extra == 1).then(|| {
                        _mm256_add_ps(
                            load(sp, lo + 2 * s_stride + 8 * q),
                            load(sp, hi + 2 * s_stride + 8 * q),
                        )
                    }),
                )
            } else {
                (
                    load(sp, lo + 8 * q),
                    (extra == 1).then(|| load(sp, lo + 2 * s_stride + 8 * q)),
                )
            };
            acc[q] = _mm256_fmadd_ps(wv, a, acc[q]);
            if let Some(b) = b {
                acc_b[q] = _mm256_fmadd_ps(wv, b, acc_b[q]);
            }
        }
    }
    let op = out_a.as_mut_ptr().cast::<f32>();
    for (q, a) in acc.iter().enumerate() {
        // SAFETY: `out_a` holds 16 rows, 32 floats.
        unsafe { _mm256_storeu_ps(op.add(8 * q), *a) };
    }
    if let Some(out_b) = out_b {
        let op = out_b.as_mut_ptr().cast::<f32>();
        for (q, a) in acc_b.iter().enumerate() {
            // SAFETY: `out_b` holds 16 rows, 32 floats.
            unsafe { _mm256_storeu_ps(op.add(8 * q), *a) };
        }
    }
}

/// The additive echoes of one column that do not come from its scatterers:
/// diffuse clutter (scaled per row, attenuated like tissue echoes) and
/// electronic noise (after the attenuation, before the TGC).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Additive<'a> {
    /// Unit-power clutter field of the column.
    pub clutter: &'a [[f32; 2]],
    /// RMS clutter amplitude per row (envelope units).
    pub clutter_amp: &'a [f32],
    /// Unit-power noise field of the column.
    pub noise: &'a [[f32; 2]],
    /// RMS noise amplitude (envelope units).
    pub noise_amp: f32,
}

/// Display mapping: `gray = a log₂ I + b + c · gain_dB`, clamped to [0, 255].
#[derive(Debug, Clone, Copy)]
pub(crate) struct LogCompression {
    /// Gray levels per unit of `log₂ I`.
    pub a: f32,
    /// Offset (gray levels).
    pub b: f32,
    /// Gray levels per dB.
    pub c: f32,
    /// Centre frequency (MHz).
    pub f_mhz: f64,
    /// Attenuation slope compensated by the TGC (dB/(cm·MHz)).
    pub tgc: f64,
}

/// The round-trip loss exponent `−2 f A` (Np of amplitude) of each row of
/// one column into `loss_np` (one value per image row), for
/// [`compress_column`].
///
/// The received echo at image depth `z` is `(iq + clutter) · 10^{−A/20} + noise`,
/// `A = 2 f ∫₀^z α(z') dz'` dB; `α` is the
/// attenuation slope of the tissue met along the beam (piecewise constant
/// between the anatomy's breakpoints, carried by the deformation). Bone
/// attenuates ≈ 30 times more than soft tissue, which makes its shadow;
/// blood ≈ 4 times less, which makes the enhancement below the vessels.
/// Without anatomy (a phantom) `α` is the TGC's.
#[inline(always)]
pub(crate) fn column_loss(
    lc: &LogCompression,
    g: &FrameGeometry,
    anatomy: Option<&Anatomy>,
    u: f64,
    surface: f64,
    warps: &WarpSet,
    loss_np: &mut [f64],
) {
    // Breakpoints mapped to image depth (m, cm) and the slope after each.
    let mut z = [0.0f64; MAX_BREAKPOINTS + 1];
    let mut alpha = [0.0f64; MAX_BREAKPOINTS + 1];
    let n = match anatomy {
        Some(a) => {
            let mut b = [0.0; MAX_BREAKPOINTS];
            let n = a.column_breakpoints(u, &mut b);
            for i in 0..n {
                let next = if i + 1 < n { b[i + 1] } else { b[i] + 2e-3 };
                alpha[i] = a.attenuation_at(u, 0.5 * (b[i] + next));
                z[i] = image_depth(g, surface, warps, b[i]);
            }
            n
        }
        None => {
            z[0] = f64::NEG_INFINITY;
            alpha[0] = lc.tgc;
            1
        }
    };
    // Walk down from the face (z = 0): segments that start above it only set
    // the slope; nothing above the face is traversed by the beam.
    let mut seg = 0; // next segment to enter
    let mut acc = 0.0f64; // ∫ α dz from the face to z_at (dB/MHz, z in cm)
    let mut z_at = 0.0f64;
    let mut slope = 0.0f64;
    while seg < n && z[seg] <= 0.0 {
        slope = alpha[seg];
        seg += 1;
    }
    let db_to_np = std::f64::consts::LN_10 / 20.0;
    // Serial: the segments.
    for (i, x) in loss_np.iter_mut().enumerate() {
        let zi = (i as f64 + 0.5) * g.dz;
        while seg < n && z[seg] <= zi {
            acc += slope * (z[seg] - z_at) * 100.0;
            z_at = z[seg];
            slope = alpha[seg];
            seg += 1;
        }
        let att = acc + slope * (zi - z_at) * 100.0;
        *x = -2.0 * lc.f_mhz * att * db_to_np;
    }
}

/// The loss `loss_np` (Np of amplitude per row, from [`column_loss`] and
/// the frame's corrections), added clutter and noise, TGC along one column,
/// and the log compression of its envelope into `gray`: the received echo
/// `(iq + clutter) e^{x} + noise`, displayed with the TGC gain
/// `2 f α_TGC z` dB. With `AVX2`, eight rows at a time with polynomial
/// `exp` and `log₂` ([`crate::compress_avx2`]: within one gray level of
/// this scalar libm loop, on a small fraction of pixels).
#[inline(always)]
pub(crate) fn compress_column<const AVX2: bool>(
    lc: &LogCompression,
    g: &FrameGeometry,
    iq: &[[f32; 2]],
    add: &Additive,
    loss_np: &[f64],
    gray: &mut [u8],
) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is true only in the code that
        // `Renderer::stages_avx2` runs, after the CPU was found to have AVX2.
        unsafe { crate::compress_avx2::compress_column_avx2(lc, g, iq, add, loss_np, gray) };
        return;
    }
    compress_rows(lc, g, 0, iq, add, loss_np, gray);
}

/// [`compress_column`]'s scalar loop over rows `first ..` of a column
/// (`iq`, `add`, `loss_np` and `gray` start at row `first`), with libm's
/// `exp` and `log2f`.
#[inline(always)]
pub(crate) fn compress_rows(
    lc: &LogCompression,
    g: &FrameGeometry,
    first: usize,
    iq: &[[f32; 2]],
    add: &Additive,
    loss_np: &[f64],
    gray: &mut [u8],
) {
    // Independent pixels: loss, clutter and noise, TGC, log compression.
    for (i, ((px, out), &x)) in iq.iter().zip(gray.iter_mut()).zip(loss_np).enumerate() {
        let zi = ((first + i) as f64 + 0.5) * g.dz;
        let loss = x.exp() as f32;
        let gain = 2.0 * lc.f_mhz * lc.tgc * zi * 100.0;
        let (c, ca, nz) = (add.clutter[i], add.clutter_amp[i], add.noise[i]);
        let re = (px[0] + ca * c[0]) * loss + add.noise_amp * nz[0];
        let im = (px[1] + ca * c[1]) * loss + add.noise_amp * nz[1];
        let level = lc.a * safe_log2(re * re + im * im) + lc.b + lc.c * gain as f32;
        *out = level.clamp(0.0, 255.0).round() as u8;
    }
}
