//! The pulse-echo point spread function in complex baseband, as tables.
//!
//! The echo of a scatterer at image depth `d`, lateral offset `x` from the
//! line and elevation `y`, demodulated at `f₀` and read at depth `z`, is
//! `e^{−i 2 k₀ d} p_z(z − d) h_z(x) w_z(y)`: the axial kernel of the
//! down-shifted pulse ([`crate::pulse`]) times the lateral profile and the
//! elevation weight of the focused array ([`crate::beam`]), both tabulated
//! per depth once from the geometry (the separable approximation of a
//! pulse-echo PSF, Szabo 2014, ch. 7). The baseband needs no carrier
//! sampling: a few taps per scatterer at the image's own pixel pitch.
//!
//! Normalization: a unit point on the axis at the transmit focus gives an
//! envelope of 1; elsewhere the envelope follows the beam (focal gain).

use crate::beam::{BeamProfiles, MAX_HALF_WIDTH};
use crate::config::ImagingConfig;
use crate::pulse::{AxialTables, Spectrum};
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

/// Entries of the phase table (one turn).
pub(crate) const PHASE_STEPS: usize = 4096;
/// Rows per block of the lateral convolution (one half-width per block).
pub(crate) const BLOCK_ROWS: usize = 16;

/// Precomputed PSF tables of one image geometry and probe.
#[derive(Debug)]
pub(crate) struct PsfTables {
    /// Axial kernels per depth knot.
    pub axial: AxialTables,
    /// Largest lateral half-width (taps), the halo of the scatterer field.
    pub lat_half: usize,
    /// Lateral half-width of each block of `BLOCK_ROWS` rows.
    pub block_half: Vec<usize>,
    /// `lateral[(k + lat_half) · rows + i]`: lateral weight at offset `k`
    /// columns for image row `i` (zero past the row's support).
    pub lateral: Vec<f32>,
    /// `lateral` with each weight twice, `[w, w]`, at the same index: the
    /// factor of a complex sample's two floats, loaded as is by the AVX2
    /// convolution (no shuffle per tap).
    pub lateral_pairs: Vec<[f32; 2]>,
    /// Elevation weight per splat row (`row + pad`) for tissue (slice average).
    pub elev_diffuse: Vec<f32>,
    /// Elevation weight per splat row for point targets on the image plane.
    pub elev_point: Vec<f32>,
    /// Elevation width per splat row (m): the `σ` of the Gaussian
    /// `w(y) = w(0) e^{−y²/(2σ²)}` with the slice's own `w(0)` and
    /// `∫ w² dy` (`∫ w² = w(0)² σ √π`, so `σ = (√∫w² / w(0))² / √π`),
    /// for tissue scatterers placed across the slice
    /// ([`crate::Renderer::in_tissue`]).
    pub slice_sigma: Vec<f64>,
    /// Mean echo intensity of a unit-power medium of unit density (per m²)
    /// at each image row (envelope² · m²), before attenuation.
    pub speckle_unit: Vec<f64>,
    /// The image row of the transmit focus (clamped into the image).
    pub focus_row: usize,
    /// `phase[i] = e^{−i 2π i / 4096}` as `[re, im]`.
    pub phase: Vec<[f32; 2]>,
    /// Phase-table index per metre of depth: `2 k₀ / (2π) · 4096`.
    pub phase_per_metre: f64,
}

impl PsfTables {
    /// Padding rows of the splat buffer above and below the image.
    pub fn pad(&self) -> usize {
        2 * self.axial.half
    }

    /// The tables of `cfg` (assumed validated), computed once per distinct
    /// probe and image geometry in the process and shared.
    pub fn shared(cfg: &ImagingConfig) -> Arc<PsfTables> {
        type Cache = Mutex<Vec<(String, Arc<PsfTables>)>>;
        static CACHE: Cache = Mutex::new(Vec::new());
        let key = format!(
            "{:?}",
            (
                &cfg.beam,
                cfg.columns,
                cfg.rows,
                cfg.width.to_bits(),
                cfg.depth.to_bits(),
                cfg.center_frequency.to_bits(),
                cfg.sound_speed.to_bits(),
                cfg.tgc_attenuation.to_bits(),
            )
        );
        // A poisoned cache only lost an insertion: recover its contents.
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, t)) = cache.iter().find(|(k, _)| *k == key) {
            return Arc::clone(t);
        }
        let t = Arc::new(Self::new(cfg));
        if cache.len() >= 8 {
            cache.remove(0);
        }
        cache.push((key, Arc::clone(&t)));
        t
    }

    /// Tables for `cfg` (assumed validated).
    pub fn new(cfg: &ImagingConfig) -> Self {
        let (dx, dz, rows) = (cfg.pixel_width(), cfg.pixel_depth(), cfg.rows);
        let c = cfg.sound_speed;
        let sp = Spectrum::new(
            cfg.center_frequency,
            cfg.beam.bandwidth,
            cfg.beam.pulse_cycles,
            cfg.tgc_attenuation,
        );
        let axial = AxialTables::new(&sp, dz, rows, c);
        let pad = 2 * axial.half;
        let cap = ((MAX_HALF_WIDTH / dx).ceil() as usize).clamp(1, 96);
        let prof = BeamProfiles::new(&cfg.beam, &sp, c, cfg.depth, dx, cap);
        let focus_z = cfg.beam.transmit_focus.min(cfg.depth - 0.5 * dz);
        let lat_norm = BeamProfiles::interp(&column(&prof.lateral, 0), focus_z).abs();
        let point_norm = BeamProfiles::interp(&prof.point, focus_z);
        // Per-row lateral profiles, normalized, and their supports.
        let mut rows_lat = vec![vec![0.0f64; cap + 1]; rows];
        let mut support = vec![0usize; rows];
        for (i, (lat, sup)) in rows_lat.iter_mut().zip(&mut support).enumerate() {
            let z = (i as f64 + 0.5) * dz;
            for (k, v) in lat.iter_mut().enumerate() {
                *v = BeamProfiles::interp(&column(&prof.lateral, k), z) / lat_norm;
            }
            let peak = lat.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            *sup = lat.iter().rposition(|v| v.abs() > 1e-3 * peak).unwrap_or(0);
        }
        let block_half: Vec<usize> = support
            .chunks(BLOCK_ROWS)
            .map(|b| b.iter().copied().max().unwrap_or(0).max(1))
            .collect();
        let lat_half = block_half.iter().copied().max().unwrap_or(1);
        let mut lateral = vec![0.0f32; (2 * lat_half + 1) * rows];
        for (i, lat) in rows_lat.iter().enumerate() {
            let h = block_half[i / BLOCK_ROWS];
            for k in 0..=h {
                let v = lat[k] as f32;
                lateral[(lat_half + k) * rows + i] = v;
                lateral[(lat_half - k) * rows + i] = v;
            }
        }
        // Elevation weights per splat row; the diffuse weight equals the
        // point weight at the transmit focus (the display reference).
        let diffuse_norm = BeamProfiles::interp(&prof.diffuse, focus_z) / point_norm;
        let splat_z = |r: usize| ((r as f64 - pad as f64 + 0.5) * dz).max(0.0);
        let elev_point: Vec<f32> = (0..rows + 2 * pad)
            .map(|r| (BeamProfiles::interp(&prof.point, splat_z(r)) / point_norm) as f32)
            .collect();
        let elev_diffuse: Vec<f32> = (0..rows + 2 * pad)
            .map(|r| (BeamProfiles::interp(&prof.diffuse, splat_z(r)) / diffuse_norm) as f32)
            .collect();
        let slice_sigma: Vec<f64> = (0..rows + 2 * pad)
            .map(|r| {
                let z = splat_z(r);
                let ratio =
                    BeamProfiles::interp(&prof.diffuse, z) / BeamProfiles::interp(&prof.point, z);
                ratio * ratio / PI.sqrt()
            })
            .collect();
        let speckle_unit = (0..rows)
            .map(|i| {
                let lat_e: f64 = (-(lat_half as i64)..=lat_half as i64)
                    .map(|k| (lateral[(k + lat_half as i64) as usize * rows + i] as f64).powi(2))
                    .sum::<f64>()
                    * dx;
                let w = elev_diffuse[i + pad] as f64;
                let ax = axial.energy[axial.knot(i as f64)];
                w * w * lat_e * ax
            })
            .collect();
        let phase = (0..PHASE_STEPS)
            .map(|i| {
                let a = -2.0 * PI * i as f64 / PHASE_STEPS as f64;
                [a.cos() as f32, a.sin() as f32]
            })
            .collect();
        let k0 = 2.0 * PI * cfg.center_frequency / c;
        let lateral_pairs = lateral.iter().map(|&w| [w, w]).collect();
        PsfTables {
            axial,
            lat_half,
            block_half,
            lateral,
            lateral_pairs,
            elev_diffuse,
            elev_point,
            slice_sigma,
            speckle_unit,
            focus_row: ((focus_z / dz) as usize).min(rows - 1),
            phase,
            phase_per_metre: 2.0 * k0 / (2.0 * PI) * PHASE_STEPS as f64,
        }
    }

    /// Lateral weight at offset `k` columns (`|k| ≤ lat_half`) in image row `i`.
    pub fn lateral_at(&self, k: i64, i: usize) -> f32 {
        let rows = self.speckle_unit.len();
        self.lateral[(k + self.lat_half as i64) as usize * rows + i]
    }
}

/// Knot values of lateral tap `k`.
fn column(lat: &[Vec<f64>], k: usize) -> Vec<f64> {
    lat.iter().map(|l| l[k]).collect()
}

/// `log₂ x`, with `x` floored at 1e-30 (silence maps to −99.7, far below
/// any displayed dynamic range).
#[inline]
pub(crate) fn safe_log2(x: f32) -> f32 {
    x.max(1e-30).log2()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_of_silence_is_finite() {
        assert!(safe_log2(0.0).is_finite() && safe_log2(0.0) < -99.0);
        assert_eq!(safe_log2(8.0), 3.0);
    }

    #[test]
    fn tables_are_symmetric_and_normalized_at_the_focus() {
        let cfg = ImagingConfig::default();
        let t = PsfTables::shared(&cfg);
        let rows = cfg.rows;
        // Every row, bit for bit: the convolution adds the sources at ±k
        // before weighting them once (`stages::convolve_tail`).
        for i in 0..rows {
            for k in 1..=t.lat_half as i64 {
                assert_eq!(t.lateral_at(k, i).to_bits(), t.lateral_at(-k, i).to_bits());
            }
        }
        // Row of the focus: the axis weight is 1 within the interpolation
        // between the row centre and the focus (half a row of 78 µm: < 1 %).
        let f = t.focus_row;
        assert!((t.lateral_at(0, f) - 1.0).abs() < 0.01);
        let p = t.phase[PHASE_STEPS / 4];
        assert!(p[0].abs() < 1e-6 && (p[1] + 1.0).abs() < 1e-6);
    }
}
