//! The axial splat of a bin's scatterers into its padded column: each
//! scatterer's complex-baseband axial PSF ([`crate::pulse::AxialTables`]),
//! at its depth through the deformation, times its amplitude, phase and
//! elevation weight.

use crate::deformation::column_depth;
use crate::psf::{PsfTables, PHASE_STEPS};
use crate::pulse::AXIAL_SUBSTEPS;
use crate::stages::{image_depth, FrameGeometry};
use crate::warp::WarpSet;

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

/// A batch of scatterers' setup for the splat: fractional row `r`, its
/// floor `fl`, sub-row `q` and phase index `ph` per lane.
struct Batch {
    r: [f64; SPLAT_BATCH],
    fl: [i32; SPLAT_BATCH],
    q: [i32; SPLAT_BATCH],
    ph: [i32; SPLAT_BATCH],
}

impl Batch {
    /// The setup of the scatterers at tissue depths `ds` (m), lane by lane
    /// without branches (the compiler takes several lanes per instruction):
    /// image depth, fractional row, its floor, sub-row and phase index.
    /// Lanes past the batch's end, and lanes the splat skips or stops at,
    /// are computed for nothing.
    #[inline(always)]
    fn new(t: &PsfTables, g: &FrameGeometry, ds: &[f32], surface: f64, warps: &WarpSet) -> Self {
        let inv_dz = 1.0 / g.dz;
        let phase_mask = PHASE_STEPS as i32 - 1;
        let mut z = [0.0f64; SPLAT_BATCH];
        // Where no warp reaches the batch's span of depths the warps are
        // the identity (the same floats), and the branch-free map serves.
        let span = ds
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &d| {
                (a.min(d), b.max(d))
            });
        if warps.is_active() && warps.reaches(span.0 as f64, span.1 as f64) {
            for (zk, &d) in z.iter_mut().zip(ds) {
                *zk = image_depth(g, surface, warps, d as f64);
            }
        } else {
            for (zk, &d) in z.iter_mut().zip(ds) {
                *zk = column_depth(surface, g.bone, d as f64) - g.face;
            }
        }
        let mut b = Batch {
            r: [0.0; SPLAT_BATCH],
            fl: [0; SPLAT_BATCH],
            q: [0; SPLAT_BATCH],
            ph: [0; SPLAT_BATCH],
        };
        for l in 0..SPLAT_BATCH {
            let rl = z[l] * inv_dz - 0.5;
            let f = rl.floor();
            b.r[l] = rl;
            // For a splatted scatterer r − fl ∈ [0, 1) and −K − 1 ≤ fl <
            // rows + K: the conversions through i32 give what the saturating
            // ones to usize/i64 would, and clamping the sub-row at 63 before
            // the truncation gives what clamping after it would.
            b.q[l] = ((rl - f) * AXIAL_SUBSTEPS as f64).min((AXIAL_SUBSTEPS - 1) as f64) as i32;
            b.fl[l] = f as i32;
            // |z · 2k₀/2π · 4096| < 2³¹ for |z| < 53 m: the i32 truncation
            // is the i64 one, and its low 12 bits the same.
            b.ph[l] = (z[l] * t.phase_per_metre) as i32 & phase_mask;
        }
        b
    }
}

/// One scatterer's splat: its first tap's index in the padded column, its
/// depth knot, sub-row, and complex weight (amplitude × phase × elevation).
#[derive(Clone, Copy)]
struct Splat {
    first: usize,
    knot: usize,
    q: usize,
    c: [f32; 2],
}

/// Calls `add` with each scatterer of one bin that reaches the image's
/// padded column, in order, and stops at the first past its bottom
/// (depths are sorted and the map is increasing).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn for_each_splat(
    t: &PsfTables,
    g: &FrameGeometry,
    elev: &[f32],
    depth: &[f32],
    amp: &[[f32; 2]],
    surface: f64,
    warps: &WarpSet,
    mut add: impl FnMut(Splat),
) {
    let ax = &t.axial;
    let k = ax.half;
    let lowest = -(k as f64) - 1.0;
    let highest = (g.rows + k) as f64;
    let last = elev.len() as i64 - 1;
    for (ds, amps) in depth.chunks(SPLAT_BATCH).zip(amp.chunks(SPLAT_BATCH)) {
        let b = Batch::new(t, g, ds, surface, warps);
        for (l, a) in amps.iter().enumerate() {
            if b.r[l] < lowest {
                continue;
            }
            if b.r[l] >= highest {
                return;
            }
            let p = t.phase[b.ph[l] as usize];
            let fi = b.fl[l] as i64;
            let e = elev[(fi + g.pad as i64).clamp(0, last) as usize];
            add(Splat {
                // First tap: row fl − K + 1, at index fl − K + 1 + pad ≥ 0.
                first: (fi - k as i64 + 1 + g.pad as i64) as usize,
                // `ax.knot(r)` from its table (no division).
                knot: ax.row_knot[fi.max(0) as usize] as usize,
                q: b.q[l] as usize,
                c: [
                    e * (a[0] * p[0] - a[1] * p[1]),
                    e * (a[0] * p[1] + a[1] * p[0]),
                ],
            });
        }
    }
}

/// Adds the axial PSF of each scatterer of one bin into its padded column
/// `out` (at least `rows + 2·pad` complex samples, [`splat_stride`] with
/// `AVX2`), weighted by the elevation weight `elev` of its splat row
/// (`row + pad`). The per-scatterer setup (depth through the deformation,
/// row, sub-row, phase) is computed [`SPLAT_BATCH`] scatterers at a time,
/// then their taps are added one scatterer after the other: the same float
/// operations per scatterer, in the same order into each sample. `AVX2`:
/// the caller runs with AVX2 enabled; for kernels of four or more groups
/// of rows the sums are held in registers ([`splat_groups_avx2`]).
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
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY (each arm): `AVX2` is true only in the code that
        // `Renderer::stages_avx2` runs, after the CPU was found to have AVX2.
        let a = (t, g, elev, depth, amp, surface, warps);
        // Below four groups (`2K` ≤ 12 taps, e.g. the live frame's 8) the
        // zero taps cost more than the stores they save (3 groups for 8
        // taps: 50 % more products; measured no faster): taps added in
        // memory as before.
        match t.axial.groups {
            4 => unsafe { splat_groups_avx2::<4>(a, out) },
            5 => unsafe { splat_groups_avx2::<5>(a, out) },
            6 => unsafe { splat_groups_avx2::<6>(a, out) },
            7 => unsafe { splat_groups_avx2::<7>(a, out) },
            8 => unsafe { splat_groups_avx2::<8>(a, out) },
            _ => for_each_splat(t, g, elev, depth, amp, surface, warps, |s| {
                let taps = 2 * t.axial.half;
                let base = (s.knot * AXIAL_SUBSTEPS + s.q) * taps;
                add_taps::<true>(
                    &mut out[s.first..s.first + taps],
                    &t.axial.taps[base..base + taps],
                    s.c,
                );
            }),
        }
        return;
    }
    let taps = 2 * t.axial.half;
    for_each_splat(t, g, elev, depth, amp, surface, warps, |s| {
        let base = (s.knot * AXIAL_SUBSTEPS + s.q) * taps;
        add_taps::<false>(
            &mut out[s.first..s.first + taps],
            &t.axial.taps[base..base + taps],
            s.c,
        );
    });
}

/// The stride (complex samples) of a padded splat column for `rows` image
/// rows: `rows + 2·pad` rounded up to whole groups of four, plus the
/// [`AxialTables::groups`](crate::pulse::AxialTables) groups that
/// [`splat_groups_avx2`]'s window may reach past the last first tap.
pub(crate) fn splat_stride(t: &PsfTables, rows: usize) -> usize {
    (rows + 2 * t.pad()).next_multiple_of(4) + 4 * t.axial.groups
}

/// The arguments of [`splat_add`] but its output column.
type SplatArgs<'a> = (
    &'a PsfTables,
    &'a FrameGeometry,
    &'a [f32],
    &'a [f32],
    &'a [[f32; 2]],
    f64,
    &'a WarpSet,
);

/// [`splat_add`]'s [`add_taps`] of every scatterer, with the column's sums in
/// registers: a window of `G` groups of four rows (one AVX2 register of
/// interleaved `(re, im)` each) from the group of the scatterer's first
/// tap; the window slides down with the scatterers (storing the groups it
/// leaves, loading those it enters). A scatterer whose first tap is row
/// `s` of its group adds the four taps from `3 − s + 4m` of its zero-padded
/// table ([`AxialTables::padded`](crate::pulse::AxialTables)) to group
/// `m`: per sample the products, `addsub` and sum of [`add_taps_avx2`], in
/// the scatterers' order, plus zero taps (an exact `+0` or `−0`, which
/// leaves a sum that started at `+0` unchanged): the same floats. `out`
/// must hold [`splat_stride`] samples.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn splat_groups_avx2<const G: usize>(args: SplatArgs, out: &mut [[f32; 2]]) {
    use std::arch::x86_64::*;
    let (t, g, elev, depth, amp, surface, warps) = args;
    let ax = &t.axial;
    let n = ax.padded_len;
    let mut acc = [_mm256_setzero_ps(); G];
    // First group of the window; `usize::MAX` before the first scatterer.
    let mut base = usize::MAX;
    let group = |out: &mut [[f32; 2]], b: usize| -> *mut f32 {
        let g: &mut [[f32; 2]; 4] = (&mut out[4 * b..4 * b + 4]).try_into().expect("group");
        g.as_mut_ptr().cast()
    };
    let mut add = |s: Splat| {
        let grp = s.first / 4;
        if grp != base {
            if base != usize::MAX && grp > base && grp - base < G {
                // Slide by one group at a time.
                for _ in base..grp {
                    // SAFETY: `group` points at 8 floats of `out`.
                    unsafe { _mm256_storeu_ps(group(out, base), acc[0]) };
                    for m in 0..G - 1 {
                        acc[m] = acc[m + 1];
                    }
                    base += 1;
                    // SAFETY: as above.
                    acc[G - 1] = unsafe { _mm256_loadu_ps(group(out, base + G - 1)) };
                }
            } else {
                if base != usize::MAX {
                    for (m, a) in acc.iter().enumerate() {
                        // SAFETY: as above.
                        unsafe { _mm256_storeu_ps(group(out, base + m), *a) };
                    }
                }
                base = grp;
                for (m, a) in acc.iter_mut().enumerate() {
                    // SAFETY: as above.
                    *a = unsafe { _mm256_loadu_ps(group(out, base + m)) };
                }
            }
        }
        let start = (s.knot * AXIAL_SUBSTEPS + s.q) * n + 3 - s.first % 4;
        let w: &[[f32; 2]] = &ax.padded[start..start + 4 * G];
        let wp = w.as_ptr().cast::<f32>();
        let (c0, c1) = (_mm256_set1_ps(s.c[0]), _mm256_set1_ps(s.c[1]));
        for (m, a) in acc.iter_mut().enumerate() {
            // SAFETY: `w` holds 4G taps, 8G floats; unaligned loads.
            let wv = unsafe { _mm256_loadu_ps(wp.add(8 * m)) };
            let ws = _mm256_permute_ps::<0b10_11_00_01>(wv);
            let tm = _mm256_addsub_ps(_mm256_mul_ps(c0, wv), _mm256_mul_ps(c1, ws));
            *a = _mm256_add_ps(*a, tm);
        }
    };
    for_each_splat(t, g, elev, depth, amp, surface, warps, &mut add);
    if base != usize::MAX {
        for (m, a) in acc.iter().enumerate() {
            // SAFETY: as above.
            unsafe { _mm256_storeu_ps(group(out, base + m), *a) };
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
