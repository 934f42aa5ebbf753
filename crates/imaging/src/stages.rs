//! The per-column stages of a frame, run by the renderer: lateral
//! convolution, and attenuation/TGC plus log compression (the axial splat
//! of the scatterers is [`crate::splat`]).

use crate::anatomy::{Anatomy, MAX_BREAKPOINTS};
use crate::deformation::column_depth;
use crate::psf::{safe_log2, PsfTables, BLOCK_ROWS};
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

/// Output column `j` of the lateral convolution with the depth-dependent
/// lateral profile: `out[i] = Σ_k h_i[k] rf[j + H + k][i]` over the padded
/// bins (`H` the halo), unpadded rows, each block of rows over its own
/// half-width. A full block accumulates in registers over all its offsets
/// (`k` increasing from a zero sum, as a row-by-row sum: the same floats).
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
    let hh = t.lat_half as i64;
    for (blk, chunk) in out.chunks_mut(BLOCK_ROWS).enumerate() {
        let h = t.block_half[blk] as i64;
        let i0 = blk * BLOCK_ROWS;
        let n = chunk.len();
        let weights = |k: i64| &t.lateral[(k + hh) as usize * rows + i0..][..n];
        let source = |k: i64| {
            let start = (j as i64 + hh + k) as usize * padded_rows + pad + i0;
            &rf[start..start + n]
        };
        if let Ok(block) = <&mut [[f32; 2]; BLOCK_ROWS]>::try_from(&mut *chunk) {
            let mut acc = [[0.0f32; 2]; BLOCK_ROWS];
            for k in -h..=h {
                let w: &[f32; BLOCK_ROWS] = weights(k).try_into().expect("full block");
                let s: &[[f32; 2]; BLOCK_ROWS] = source(k).try_into().expect("full block");
                for m in 0..BLOCK_ROWS {
                    acc[m][0] += w[m] * s[m][0];
                    acc[m][1] += w[m] * s[m][1];
                }
            }
            *block = acc;
        } else {
            chunk.fill([0.0, 0.0]);
            for k in -h..=h {
                for ((o, s), &wk) in chunk.iter_mut().zip(source(k)).zip(weights(k)) {
                    o[0] += wk * s[0];
                    o[1] += wk * s[1];
                }
            }
        }
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

/// The partial block `blk` (rows `blk · 16 ..`, `out.len()` of them) of
/// output column `j`, as [`convolve_column`] computes it.
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
    out.fill([0.0, 0.0]);
    for k in -h..=h {
        let w = &t.lateral[(k + hh) as usize * rows + i0..][..n];
        let start = (j as i64 + hh + k) as usize * padded_rows + pad + i0;
        for ((o, s), &wk) in out.iter_mut().zip(&rf[start..start + n]).zip(w) {
            o[0] += wk * s[0];
            o[1] += wk * s[1];
        }
    }
}

/// One full block of [`convolve_column`] with AVX2 for one output column,
/// `out_a`, and the next one, `out_b` if any: `out[m] = Σ_k w_k[m]
/// s_k[m]` over the `n` offsets, `w_k` at `w[k · w_stride..]` (weights as
/// pairs, [`PsfTables::lateral_pairs`]) and `s_k` at `s[k · s_stride..]`
/// for `out_a`, one source column (`s_stride`) further for `out_b`, `k`
/// increasing from a zero sum. Sixteen complex rows are four registers of
/// interleaved `(re, im)` pairs, multiplied and added (no FMA contraction)
/// as the scalar loop does per float: the same floats.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
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
    assert!(n >= 1 && w.len() >= (n - 1) * w_stride + BLOCK_ROWS);
    assert!(s.len() >= (n - 1 + extra) * s_stride + BLOCK_ROWS);
    let mut acc = [_mm256_setzero_ps(); 4];
    let mut acc_b = [_mm256_setzero_ps(); 4];
    let (wp, sp) = (w.as_ptr().cast::<f32>(), s.as_ptr().cast::<f32>());
    if extra == 1 {
        for k in 0..n {
            let (wk, sk) = (2 * k * w_stride, 2 * k * s_stride);
            for q in 0..4 {
                // SAFETY: 8 floats (4 rows) within `w` and `s` (asserted
                // above, the next column included); unaligned loads.
                let (wv, sa, sb) = unsafe {
                    (
                        _mm256_loadu_ps(wp.add(wk + 8 * q)),
                        _mm256_loadu_ps(sp.add(sk + 8 * q)),
                        _mm256_loadu_ps(sp.add(sk + 2 * s_stride + 8 * q)),
                    )
                };
                acc[q] = _mm256_add_ps(acc[q], _mm256_mul_ps(wv, sa));
                acc_b[q] = _mm256_add_ps(acc_b[q], _mm256_mul_ps(wv, sb));
            }
        }
    } else {
        for k in 0..n {
            let (wk, sk) = (2 * k * w_stride, 2 * k * s_stride);
            for (q, a) in acc.iter_mut().enumerate() {
                // SAFETY: as above.
                let (wv, sv) = unsafe {
                    (
                        _mm256_loadu_ps(wp.add(wk + 8 * q)),
                        _mm256_loadu_ps(sp.add(sk + 8 * q)),
                    )
                };
                *a = _mm256_add_ps(*a, _mm256_mul_ps(wv, sv));
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
