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
    /// `weights[i · (2K + 1) + k + K]`, normalized to sum 1 in each row.
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
        for (i, w) in weights.chunks_mut(n).enumerate() {
            let h = row_half[i];
            for (kk, wk) in w.iter_mut().enumerate().skip(half - h).take(2 * h + 1) {
                *wk = intensity(kk as i64 - half as i64, i);
            }
            let sum: f64 = w.iter().sum();
            if sum > 0.0 {
                w.iter_mut().for_each(|x| *x /= sum);
            }
        }
        LossBlur {
            half,
            row_half,
            weights,
        }
    }

    /// The loss of column `j` into `out` (one value per row) from the loss
    /// exponents of every column, `loss[c · rows + i]` (`columns =
    /// loss.len() / rows`; columns past the image's edges are taken as the
    /// edge column): averaged in the rows whose main lobe, widened by
    /// `margin` columns, reaches the nearest vessel margin `distance`
    /// columns away, from row `start` down (the vessels' top), the
    /// column's own elsewhere (its neighbours see the same loss there).
    #[allow(clippy::too_many_arguments)]
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
        let n = 2 * self.half + 1;
        for (i, o) in out.iter_mut().enumerate().take(rows) {
            let h = self.row_half[i];
            if i < start || distance > (h + 1) as f64 + margin {
                *o = loss[j * rows + i];
                continue;
            }
            let w = &self.weights[i * n..(i + 1) * n];
            let mut acc = 0.0;
            let first = self.half - h;
            for (kk, &wk) in w.iter().enumerate().skip(first).take(2 * h + 1) {
                let c = (j + kk).saturating_sub(self.half).min(cols - 1);
                acc += wk * loss[c * rows + i];
            }
            *o = acc;
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
            let w = &b.weights[i * n..(i + 1) * n];
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
}
