//! The lateral motion of a widening lumen in the image (issue 21), drawn
//! by moving the splatted echo across columns.
//!
//! In the image (`x` lateral, `z` depth below the face, m) a vessel whose
//! lumen widens ([`crate::widen`]) moves the point at `x` to
//! `x + w(z) D(x − x₀)`, `x₀` the vessel's centre:
//! - `D` is piecewise linear through the knots
//!   `(−o − L₀, −o, −a, a, o, o + L₁)` with the values
//!   `(0, −δ₀, −δ₀, δ₁, δ₁, 0)`: the lumen `[−a, a]` is stretched onto
//!   `[−a − δ₀, a + δ₁]`, the walls (out to the wall's outer half-width
//!   `o`) move rigidly with its edges, and the tissue beyond follows, the
//!   shift decaying linearly to 0 over `L₀` medially and `L₁` laterally
//!   ([`crate::widen::decay_lengths`]);
//! - `w(z)` is 1 over the vessel's band (its walls' depth span in the frame,
//!   after the vertical warp) and falls linearly to 0 over `up` above it
//!   and `down` below it (`down` ends at the femur's top: bone does not
//!   move).
//!
//! For every `z` the map is continuous and increasing in `x`: its slope is
//! `1 + w (δ₀ + δ₁)/2a ≥ 1` in the lumen, 1 in the walls and
//! `1 − w δ_k / L_k ≥ 2/3` beyond (`δ_k ≤ L_k / 3`,
//! [`crate::widen::side_caps`]); it is the identity outside
//! `[−o − L₀, o + L₁]` and outside the band's decays, and continuous in `z`
//! (`w` is). So the tissue is carried, not torn, as by the vertical warp.
//!
//! The splat bins scatterers by column before this is known, so the map is
//! drawn on the splatted echo, row by row, before the lateral convolution:
//! each bin takes the echo of the bin nearest its source `x_s` (the inverse
//! map), times `√(dx_s/dx)`. Whole bins keep the speckle's statistics
//! (linear interpolation between two bins of independent scatterers would
//! darken the midpoints by up to 3 dB: `(1 − t)² + t²` of the power); the
//! factor is the change of scatterer density (tissue stretched by `s`
//! holds `1/s` of the scatterers per column: `10 log₁₀ s` dB less echo, as
//! under the vertical warp; tissue squeezed to 2/3 echoes at most 1.76 dB
//! more).

use std::ops::Range;

/// One widening vessel's lateral map in the image frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct LateralMap {
    /// The vessel's centre `x₀` (m, image frame).
    x0: f64,
    /// Source knots relative to `x₀` (m), non-decreasing.
    s: [f64; 6],
    /// The full shift `D` at each knot (m).
    d: [f64; 6],
    /// The band where `w = 1` (m below the face).
    top: f64,
    bottom: f64,
    /// Decay lengths of `w` above and below the band (m, > 0).
    up: f64,
    down: f64,
}

impl LateralMap {
    /// The map of a lumen of half-width `a` (m) whose wall reaches `outer`
    /// (m) from the centre `x0` (m), its edges shifted outwards by
    /// `shift` (m; medial, lateral), the shift decaying over `decay` (m,
    /// each at least 3 times its shift), in full over the depths `band`
    /// (m) and decaying over `up` and `down` (m) above and below it.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        x0: f64,
        a: f64,
        outer: f64,
        shift: [f64; 2],
        decay: [f64; 2],
        band: (f64, f64),
        up: f64,
        down: f64,
    ) -> Self {
        let o = outer.max(a);
        LateralMap {
            x0,
            s: [-o - decay[0], -o, -a, a, o, o + decay[1]],
            d: [0.0, -shift[0], -shift[0], shift[1], shift[1], 0.0],
            top: band.0,
            bottom: band.1.max(band.0),
            up: up.max(1e-6),
            down: down.max(1e-6),
        }
    }

    /// `w(z)`: 1 in the band, linear to 0 over `up` above and `down` below.
    pub fn weight(&self, z: f64) -> f64 {
        if z < self.top {
            (1.0 - (self.top - z) / self.up).max(0.0)
        } else if z > self.bottom {
            (1.0 - (z - self.bottom) / self.down).max(0.0)
        } else {
            1.0
        }
    }

    /// The knots' images at weight `w` (relative to `x₀`).
    fn targets(&self, w: f64) -> [f64; 6] {
        std::array::from_fn(|k| self.s[k] + w * self.d[k])
    }

    /// Where the point at `(x, z)` (m, image frame) moves laterally (m):
    /// the map itself, which the renderer draws through its inverse
    /// ([`LateralMap::source`]); the tests check one against the other.
    #[cfg(test)]
    pub fn apply(&self, x: f64, z: f64) -> f64 {
        let r = x - self.x0;
        if r <= self.s[0] || r >= self.s[5] {
            return x;
        }
        let k = (0..5).find(|&k| r < self.s[k + 1]).unwrap_or(4);
        let t = (r - self.s[k]) / (self.s[k + 1] - self.s[k]);
        let dk = self.d[k] + t * (self.d[k + 1] - self.d[k]);
        x + self.weight(z) * dk
    }

    /// The source (m, image frame) of the point drawn at `x` (m) at weight
    /// `w`: the inverse of [`LateralMap::apply`] in that row.
    pub fn source(&self, x: f64, w: f64) -> f64 {
        let r = x - self.x0;
        let t = self.targets(w);
        if r <= t[0] || r >= t[5] {
            return x;
        }
        let k = (0..5).find(|&k| r < t[k + 1]).unwrap_or(4);
        let len = t[k + 1] - t[k];
        let f = if len > 0.0 { (r - t[k]) / len } else { 0.0 };
        self.x0 + self.s[k] + f * (self.s[k + 1] - self.s[k])
    }

    /// The image rows the map moves anything in (`dz` the row pitch, m).
    pub fn rows(&self, dz: f64, rows: usize) -> Range<usize> {
        let first = ((self.top - self.up) / dz - 0.5).floor().max(0.0) as usize;
        let last = ((self.bottom + self.down) / dz + 0.5).ceil().max(0.0) as usize;
        first.min(rows)..last.min(rows)
    }

    /// Draws the map on the splatted echo `rf` (column-major, `padded_rows`
    /// per bin, image row `i` at `pad + i`; bin `b` at lateral
    /// `u_first + b dx`, m): in each row it moves anything in, each bin of
    /// the map's span takes its source's nearest bin times `√(dx_s/dx)`.
    /// The span's columns are first copied into `scratch` (over the rows
    /// the map moves), then written back column by column: each column
    /// reads and writes its rows in order (a first version went row by
    /// row, a cache line per column for every row: it measured ≈ 2 ms more
    /// splat stage at 512 × 864). Nothing is allocated.
    #[allow(clippy::too_many_arguments)]
    pub fn remap(
        &self,
        rf: &mut [[f32; 2]],
        padded_rows: usize,
        pad: usize,
        rows: usize,
        dz: f64,
        u_first: f64,
        dx: f64,
        scratch: &mut RemapScratch,
    ) {
        let bins = rf.len() / padded_rows;
        let range = self.rows(dz, rows.min(scratch.rows.len()));
        if bins == 0 || range.is_empty() {
            return;
        }
        let last = bins - 1;
        let b0 = ((self.x0 + self.s[0] - u_first) / dx).ceil().max(0.0) as usize;
        let b1 =
            (((self.x0 + self.s[5] - u_first) / dx).floor().max(-1.0) as isize).min(last as isize);
        if b1 < b0 as isize {
            return;
        }
        let b1 = b1 as usize;
        // Sources lie in the span; rounding reaches one bin further.
        let (c0, c1) = (b0.saturating_sub(1), (b1 + 1).min(last));
        let (r0, n) = (range.start, range.len());
        if (c1 - c0 + 1) * n > scratch.region.len() {
            return; // not reached: the renderer's scratch holds every bin's rows
        }
        let maps = &mut scratch.rows[..n];
        for (m, row) in maps.iter_mut().enumerate() {
            *row = RowMap::new(self, self.weight(((r0 + m) as f64 + 0.5) * dz));
        }
        let region = &mut scratch.region[..(c1 - c0 + 1) * n];
        for (c, copy) in region.chunks_mut(n).enumerate() {
            let start = (c0 + c) * padded_rows + pad + r0;
            copy.copy_from_slice(&rf[start..start + n]);
        }
        for b in b0..=b1 {
            let r = u_first + b as f64 * dx - self.x0;
            let start = b * padded_rows + pad + r0;
            let column = &mut rf[start..start + n];
            for (m, (out, row)) in column.iter_mut().zip(maps.iter_mut()).enumerate() {
                if row.w <= 0.0 {
                    continue;
                }
                while row.k < 4 && r >= row.t[row.k + 1] {
                    row.k += 1;
                }
                let k = row.k;
                let xs = self.s[k] + (r - row.t[k]) * row.ratio[k];
                let src = ((xs + self.x0 - u_first) / dx).round().max(c0 as f64) as usize;
                let v = region[(src.min(c1) - c0) * n + m];
                *out = [v[0] * row.gain[k], v[1] * row.gain[k]];
            }
        }
    }
}

/// The map in one image row: its weight, the knots' images, and per
/// segment `dx_s/dx` and its square root (the density factor).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct RowMap {
    w: f64,
    t: [f64; 6],
    ratio: [f64; 5],
    gain: [f32; 5],
    /// The segment the column walk has reached.
    k: usize,
}

impl RowMap {
    fn new(map: &LateralMap, w: f64) -> Self {
        let t = map.targets(w);
        let mut ratio = [1.0f64; 5];
        let mut gain = [1.0f32; 5];
        for k in 0..5 {
            let len = t[k + 1] - t[k];
            if len > 0.0 {
                ratio[k] = (map.s[k + 1] - map.s[k]) / len;
                gain[k] = ratio[k].sqrt() as f32;
            }
        }
        RowMap {
            w,
            t,
            ratio,
            gain,
            k: 0,
        }
    }
}

/// Work memory of [`LateralMap::remap`], allocated once for a frame size.
#[derive(Debug, Clone)]
pub(crate) struct RemapScratch {
    /// A copy of the moved columns' rows.
    region: Vec<[f32; 2]>,
    /// The map in each row.
    rows: Vec<RowMap>,
}

impl RemapScratch {
    /// For `bins` columns of `rows` image rows.
    pub fn new(bins: usize, rows: usize) -> Self {
        RemapScratch {
            region: vec![[0.0; 2]; bins * rows],
            rows: vec![RowMap::default(); rows],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default vein's numbers: a = 5.7 mm, wall to 6.2 mm, edges out by
    /// 1 mm medially and 0.2 mm laterally (hemmed in by the artery).
    fn map() -> LateralMap {
        LateralMap::new(
            -0.008,
            0.0057,
            0.0062,
            [1e-3, 0.2e-3],
            [0.0124, 0.6e-3],
            (0.026, 0.032),
            0.0044,
            0.002,
        )
    }

    #[test]
    fn continuous_increasing_and_the_identity_outside() {
        let m = map();
        for zi in 0..=200 {
            let z = 0.015 + zi as f64 * 1e-4;
            let mut last = f64::NEG_INFINITY;
            for xi in 0..=4000 {
                let x = -0.03 + xi as f64 * 1e-5;
                let y = m.apply(x, z);
                // Slope ≥ 2/3 between samples 10 µm apart; a step of the
                // sample can move by at most the largest slope,
                // 1 + 1.2/11.4, so no jump.
                if xi > 0 {
                    assert!(
                        y - last >= (2.0 / 3.0) * 1e-5 - 1e-15,
                        "not increasing at {x}, {z}"
                    );
                    assert!(y - last <= 1.11e-5, "jump at {x}, {z}");
                }
                last = y;
                // Inverse.
                assert!((m.source(y, m.weight(z)) - x).abs() < 1e-12);
            }
            // Identity beyond the decays and outside the band's decays.
            assert_eq!(
                m.apply(-0.008 - 0.0062 - 0.0124 - 1e-6, z),
                -0.008 - 0.0186 - 1e-6
            );
            assert_eq!(m.apply(-0.008 + 0.0068 + 1e-6, z), -0.008 + 0.0068 + 1e-6);
            if !(0.026 - 0.0044..=0.032 + 0.002).contains(&z) {
                assert_eq!(m.apply(-0.01, z), -0.01);
            }
        }
        // Continuous in depth: 10 µm deeper moves a point by at most
        // |D| · 10 µm / up.
        for xi in 0..=400 {
            let x = -0.03 + xi as f64 * 1e-4;
            for zi in 0..2000 {
                let z = 0.02 + zi as f64 * 1e-5;
                let dy = (m.apply(x, z + 1e-5) - m.apply(x, z)).abs();
                assert!(dy <= 1e-3 * 1e-5 / 0.002 + 1e-15);
            }
        }
    }

    #[test]
    fn the_lumen_is_stretched_and_the_walls_carried_in_the_band() {
        let m = map();
        let z = 0.029;
        // The lumen's edges move by their shifts, the walls with them.
        assert!((m.apply(-0.008 - 0.0057, z) - (-0.008 - 0.0067)).abs() < 1e-15);
        assert!((m.apply(-0.008 + 0.0057, z) - (-0.008 + 0.0059)).abs() < 1e-15);
        assert!((m.apply(-0.008 - 0.006, z) - (-0.008 - 0.007)).abs() < 1e-15);
        // Inside, a uniform stretch onto [−a − δ₀, a + δ₁].
        let s = (2.0 * 0.0057 + 1.2e-3) / (2.0 * 0.0057);
        let x = m.apply(-0.008, z);
        assert!((x - (-0.008 - 0.0067 + 0.0057 * s)).abs() < 1e-15);
    }

    #[test]
    fn remap_moves_whole_bins_with_the_density_factor() {
        let m = map();
        let (dx, dz) = (0.078e-3, 0.046e-3);
        let (bins, rows, pad) = (600, 900, 4);
        let pr = rows + 2 * pad;
        let u_first = -0.03;
        // Each bin's echo is its index: the remap's source is readable.
        let mut rf: Vec<[f32; 2]> = (0..bins * pr).map(|n| [(n / pr) as f32, 0.0]).collect();
        let mut scratch = RemapScratch::new(bins, rows);
        m.remap(&mut rf, pr, pad, rows, dz, u_first, dx, &mut scratch);
        for i in [0, 300, 500, 631, 700, 899] {
            let z = (i as f64 + 0.5) * dz;
            let w = m.weight(z);
            for b in 0..bins {
                let x = u_first + b as f64 * dx;
                let v = rf[b * pr + pad + i][0];
                let src = ((m.source(x, w) - u_first) / dx).round();
                // Outside the map's span or rows: untouched.
                if w == 0.0 || x - m.x0 <= m.s[0] || x - m.x0 >= m.s[5] {
                    assert_eq!(v, b as f32);
                    continue;
                }
                // The source bin, times √(dx_s/dx) ∈ [0.9, 1.23] (0.9:
                // the lumen stretched by 1.105; 1.23 = √(1/(1 − 0.2/0.6))).
                let g = v / src as f32;
                assert!((0.9..=1.23).contains(&g), "gain {g} at {b}, {i}");
            }
        }
    }
}
