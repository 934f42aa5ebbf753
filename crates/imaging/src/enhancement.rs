//! The posterior enhancement (and any loss edge along the vessels) seen
//! through the beam (issue 21).
//!
//! The attenuation stage integrates the loss down each image line as if
//! the beam were a ray, so the enhancement below a vessel was a band with
//! the lumen's exact, sharp edges. The echo at image column `j` and depth
//! `z` comes through the beam's lateral extent: its intensity is weighted
//! across the neighbouring lines by the two-way lateral PSF at that depth,
//! `|h(k, z)|²`. Near the vessels' lateral margins (where neighbouring lines
//! see different losses) the loss exponent is averaged over the main lobe
//! with these weights,
//! `x̃_j(z) = Σ_k |h(k, z)|² x_{j+k}(z) / Σ_k |h(k, z)|²`,
//! `|k|` up to where `|h|²` falls 20 dB under its peak; the band then widens
//! and softens with depth as the beam does beyond its focus. Averaging the
//! exponent rather than the transmitted intensity is the first-order form
//! for losses of a few dB (the enhancement's ≈ 2–6 dB), and keeps the
//! frame's cost to a few columns at each margin.

use crate::psf::PsfTables;

/// Main lobe cut: `|h(k)|² ≥ 10^{−2} |h(0)|²` (−20 dB of the two-way
/// intensity).
const LOBE_CUT: f64 = 1e-2;
/// Largest half-width of the averaging (columns).
const MAX_HALF: usize = 24;

/// The lateral averaging weights per image row.
#[derive(Debug, Clone)]
pub(crate) struct LossBlur {
    /// Half-width `K` of the weights (columns), the largest of the rows'.
    pub half: usize,
    /// Each row's own half-width (columns).
    row_half: Vec<usize>,
    /// `weights[(k + K) · rows + i]`, normalized to sum 1 in each row,
    /// zero past the row's own half-width: by offset, so that a column's
    /// rows are averaged offset after offset over contiguous rows.
    weights: Vec<f64>,
}

impl LossBlur {
    /// The weights of the PSF tables `t` for `rows` image rows.
    pub fn new(t: &PsfTables, rows: usize) -> Self {
        let lim = (t.lat_half).min(MAX_HALF) as i64;
        let intensity = |k: i64, i: usize| (t.lateral_at(k, i) as f64).powi(2);
        let row_half: Vec<usize> = (0..rows)
            .map(|i| {
                let peak = intensity(0, i);
                (0..=lim)
                    .take_while(|&k| intensity(k, i) >= LOBE_CUT * peak)
                    .last()
                    .unwrap_or(0) as usize
            })
            .collect();
        let half = row_half.iter().copied().max().unwrap_or(0);
        let n = 2 * half + 1;
        let mut weights = vec![0.0; rows * n];
        let mut w = vec![0.0; n];
        for (i, &h) in row_half.iter().enumerate() {
            w.fill(0.0);
            for (kk, wk) in w.iter_mut().enumerate().skip(half - h).take(2 * h + 1) {
                *wk = intensity(kk as i64 - half as i64, i);
            }
            let sum: f64 = w.iter().sum();
            for (kk, &wk) in w.iter().enumerate() {
                weights[kk * rows + i] = if sum > 0.0 { wk / sum } else { wk };
            }
        }
        LossBlur {
            half,
            row_half,
            weights,
        }
    }

    /// Weight of offset `k` columns (`|k| ≤ half`) in row `i`.
    #[cfg(test)]
    fn weight(&self, k: i64, i: usize) -> f64 {
        let rows = self.row_half.len();
        self.weights[(k + self.half as i64) as usize * rows + i]
    }

    /// The loss of column `j` into `out` (one value per row) from the loss
    /// exponents of every column, `loss[c · rows + i]` (`columns =
    /// loss.len() / rows`; columns past the image's edges are taken as the
    /// edge column): averaged in the rows whose main lobe, widened by
    /// `margin` columns, reaches the nearest vessel margin `distance`
    /// columns away, from row `start` down (the vessels' top), the
    /// column's own elsewhere (its neighbours see the same loss there).
    ///
    /// The averaged rows lie between the first and the last row that
    /// qualifies; they are summed offset after offset (`k` increasing from
    /// a zero sum, over the largest of their half-widths) along contiguous
    /// rows, which the compiler vectorizes, then the rows between that do
    /// not qualify take their own loss back. Each row's sum adds the same
    /// products in the same order as a sum over its own offsets: the terms
    /// past its half-width have a zero weight, and adding `0 · x` (`x`
    /// finite: a loss exponent) leaves a sum unchanged, `+0` included.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn column(
        &self,
        loss: &[f64],
        rows: usize,
        j: usize,
        distance: f64,
        margin: f64,
        start: usize,
        out: &mut [f64],
    ) {
        let cols = loss.len() / rows;
        let out = &mut out[..rows];
        let own = &loss[j * rows..(j + 1) * rows];
        out.copy_from_slice(own);
        let averaged = |i: usize| distance <= (self.row_half[i] + 1) as f64 + margin;
        let start = start.min(rows);
        let Some(a) = (start..rows).find(|&i| averaged(i)) else {
            return;
        };
        let b = (a..rows).rfind(|&i| averaged(i)).map_or(a, |i| i + 1);
        let h = (a..b)
            .filter(|&i| averaged(i))
            .map(|i| self.row_half[i])
            .max()
            .unwrap_or(0);
        let span = &mut out[a..b];
        span.fill(0.0);
        for kk in self.half - h..=self.half + h {
            let c = (j + kk).saturating_sub(self.half).min(cols - 1);
            let w = &self.weights[kk * rows + a..kk * rows + b];
            let x = &loss[c * rows + a..c * rows + b];
            for ((o, &wk), &xk) in span.iter_mut().zip(w).zip(x) {
                *o += wk * xk;
            }
        }
        for (i, o) in span.iter_mut().enumerate() {
            if !averaged(a + i) {
                *o = own[a + i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ImagingConfig;

    #[test]
    fn weights_sum_to_one_and_widen_past_the_focus() {
        let cfg = ImagingConfig::default();
        let t = PsfTables::new(&cfg);
        let b = LossBlur::new(&t, cfg.rows);
        let n = 2 * b.half + 1;
        assert!(b.half >= 1);
        let spread = |i: usize| {
            let w: Vec<f64> = (0..n as i64)
                .map(|k| b.weight(k - b.half as i64, i))
                .collect();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            w.iter()
                .enumerate()
                .map(|(k, x)| x * (k as f64 - b.half as f64).powi(2))
                .sum::<f64>()
        };
        let row = |z: f64| (z / cfg.pixel_depth()) as usize;
        assert!(spread(row(40e-3)) > spread(row(cfg.beam.transmit_focus)));
        // A step of loss is softened: halfway at the step.
        let rows = cfg.rows;
        let cols = 4 * b.half + 2;
        let loss: Vec<f64> = (0..cols * rows)
            .map(|k| if k / rows < cols / 2 { -1.0 } else { 0.0 })
            .collect();
        let mut out = vec![0.0; rows];
        b.column(&loss, rows, cols / 2, 0.0, 0.0, 0, &mut out);
        let i = row(30e-3);
        assert!(out[i] < 0.0 && out[i] > -1.0, "{}", out[i]);
    }

    /// The average as first written, row after row over the row's own
    /// offsets (strided through the columns): the reference the
    /// offset-major [`LossBlur::column`] must equal bit for bit.
    fn column_by_rows(
        b: &LossBlur,
        loss: &[f64],
        rows: usize,
        j: usize,
        (distance, margin, start): (f64, f64, usize),
    ) -> Vec<f64> {
        let cols = loss.len() / rows;
        (0..rows)
            .map(|i| {
                let h = b.row_half[i];
                if i < start || distance > (h + 1) as f64 + margin {
                    return loss[j * rows + i];
                }
                let mut acc = 0.0;
                for k in -(h as i64)..=h as i64 {
                    let c = (j as i64 + k).clamp(0, cols as i64 - 1) as usize;
                    acc += b.weight(k, i) * loss[c * rows + i];
                }
                acc
            })
            .collect()
    }

    #[test]
    fn offset_major_average_is_the_row_by_row_sum_bit_for_bit() {
        let cfg = ImagingConfig::default();
        let t = PsfTables::new(&cfg);
        let b = LossBlur::new(&t, cfg.rows);
        let rows = cfg.rows;
        let cols = 3 * b.half + 7;
        // Smooth but irregular exponents (Np), negative as losses are.
        let loss: Vec<f64> = (0..cols * rows)
            .map(|k| {
                let (c, i) = ((k / rows) as f64, (k % rows) as f64);
                -1e-3 * i - 0.3 * (0.7 * c + 0.01 * i).sin().abs()
            })
            .collect();
        let mut out = vec![f64::NAN; rows];
        let mut averaged = 0;
        for j in [0, 1, b.half, cols / 2, cols - 2, cols - 1] {
            // From every row averaged to none, through the partial cases
            // where only the rows of the widest lobes are.
            for distance in [0.0, 2.0, 3.5, 6.0, 1e3] {
                for start in [0, rows / 3, rows] {
                    let args = (distance, 0.5, start);
                    b.column(&loss, rows, j, distance, 0.5, start, &mut out);
                    let want = column_by_rows(&b, &loss, rows, j, args);
                    for (i, (o, w)) in out.iter().zip(&want).enumerate() {
                        assert_eq!(o.to_bits(), w.to_bits(), "row {i}, column {j}, {args:?}");
                    }
                    averaged += want
                        .iter()
                        .zip(&loss[j * rows..(j + 1) * rows])
                        .filter(|(w, x)| w != x)
                        .count();
                }
            }
        }
        assert!(averaged > rows, "the cases average rows: {averaged}");
    }
}
