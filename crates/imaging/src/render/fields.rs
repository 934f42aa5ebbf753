//! The fields a frame adds to the scatterers' echo: reverberation and
//! smoke in the lumens, clutter and electronic noise; and the speckle
//! cell's correlation length.

use super::lumens::VesselLumen;
use crate::deformation::column_depth;
use crate::reverberation::Reverberation;
use crate::smoke::{Smoke, SmokePhase};
use crate::stages::{Additive, FrameGeometry};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The echoes added to a column's scatterer echo before its attenuation:
/// reverberation ([`crate::reverberation`]) and smoke ([`crate::smoke`]).
pub(super) struct ExtraEchoes<'a> {
    pub(super) reverb: Option<&'a Reverberation>,
    pub(super) smoke: Option<(&'a Smoke, SmokePhase)>,
    pub(super) lumens: &'a [VesselLumen],
    pub(super) muscle: &'a [f32],
    /// The frame's pan (columns): image column `j` is tissue column `j + pan`.
    pub(super) pan: i64,
    /// Depth of the deep fascia's bottom below the rest skin (m).
    pub(super) fascia: f64,
}

impl ExtraEchoes<'_> {
    /// Adds them to column `j` (lateral `u`, m, image frame; skin
    /// displacement `surface`, m).
    #[inline(always)]
    pub(super) fn column(
        &self,
        g: &FrameGeometry,
        j: usize,
        u: f64,
        surface: f64,
        iq: &mut [[f32; 2]],
    ) {
        if let Some(r) = self.reverb {
            r.near_field(
                iq,
                g.dz,
                column_depth(surface, g.bone, self.fascia) - g.face,
            );
            for l in self.lumens {
                if let Some(span) = l.span(u) {
                    r.lumen(iq, j as i64 + self.pan, g.dz, self.muscle, span);
                }
            }
        }
        if let (Some((s, phase)), Some(vein)) = (self.smoke, self.lumens.first()) {
            if let Some(span) = vein.span(u) {
                s.add(iq, j, phase, g.dz, self.muscle, (span.top, span.bottom));
            }
        }
    }
}

/// The frame's clutter and noise fields, shared by the column stages.
pub(super) struct Additives<'a> {
    pub(super) clutter: &'a [[f32; 2]],
    pub(super) clutter_amp: &'a [f32],
    pub(super) noise: &'a [[f32; 2]],
    pub(super) noise_amp: f32,
    pub(super) roll: usize,
    pub(super) rows: usize,
}

impl<'a> Additives<'a> {
    pub(super) fn column(&self, j: usize) -> Additive<'a> {
        let r = self.rows;
        let n = (j + self.roll) * r;
        Additive {
            clutter: &self.clutter[j * r..(j + 1) * r],
            clutter_amp: self.clutter_amp,
            noise: &self.noise[n..n + r],
            noise_amp: self.noise_amp,
        }
    }
}

/// `cols × rows` circular Gaussian samples (column-major) of unit mean
/// power after smoothing by `[¼, ½, ¼]` along the rows and, if `lateral`,
/// along the columns too (each pass divides the power by 3/8).
pub(super) fn smoothed_gaussian(
    rng: &mut ChaCha8Rng,
    cols: usize,
    rows: usize,
    lateral: bool,
) -> Vec<[f32; 2]> {
    let mut sample = || -> f32 { StandardNormal.sample(rng) };
    let raw: Vec<[f32; 2]> = (0..cols * rows).map(|_| [sample(), sample()]).collect();
    let at = |v: &[[f32; 2]], c: usize, r: usize| v[c * rows + r];
    let mut ax = vec![[0.0f32; 2]; cols * rows];
    for c in 0..cols {
        for r in 0..rows {
            let (a, b, d) = (
                at(&raw, c, r.saturating_sub(1)),
                at(&raw, c, r),
                at(&raw, c, (r + 1).min(rows - 1)),
            );
            for q in 0..2 {
                ax[c * rows + r][q] = 0.25 * a[q] + 0.5 * b[q] + 0.25 * d[q];
            }
        }
    }
    let mut power: f64 = 3.0 / 8.0 * 2.0; // two unit-variance quadratures
    if lateral {
        let mut lat = vec![[0.0f32; 2]; cols * rows];
        for c in 0..cols {
            for r in 0..rows {
                let (a, b, d) = (
                    at(&ax, c.saturating_sub(1), r),
                    at(&ax, c, r),
                    at(&ax, (c + 1).min(cols - 1), r),
                );
                for q in 0..2 {
                    lat[c * rows + r][q] = 0.25 * a[q] + 0.5 * b[q] + 0.25 * d[q];
                }
            }
        }
        ax = lat;
        power *= 3.0 / 8.0;
    }
    let scale = (1.0 / power).sqrt() as f32;
    for v in &mut ax {
        v[0] *= scale;
        v[1] *= scale;
    }
    ax
}

/// `Σ_Δ |R(Δ)|² / |R(0)|²` (samples) of a sampled complex kernel, `R` its
/// autocorrelation.
pub(super) fn correlation_length(h: &[[f64; 2]]) -> f64 {
    let n = h.len() as i64;
    let r = |d: i64| {
        let mut acc = [0.0, 0.0];
        for i in 0..n {
            let j = i + d;
            if (0..n).contains(&j) {
                let (a, b) = (h[i as usize], h[j as usize]);
                acc[0] += a[0] * b[0] + a[1] * b[1];
                acc[1] += a[0] * b[1] - a[1] * b[0];
            }
        }
        acc[0] * acc[0] + acc[1] * acc[1]
    };
    let r0 = r(0);
    (-(n - 1)..n).map(|d| r(d) / r0).sum()
}
