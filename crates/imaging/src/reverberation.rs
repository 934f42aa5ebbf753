//! Reverberation (issue 21): echoes that bounced more than once on their
//! way back, in the near field and in the top of vessel lumens
//! (`[imaging.reverberation]`).
//!
//! An echo that reflects at an interface of reflection coefficient `R₁`,
//! back down at a second one `R₂` above it and again at the first returns
//! after the direct echo with its amplitude times `R₁ R₂` per extra round
//! trip (transmission losses ≈ 1 at soft-tissue interfaces), delayed by
//! the round trip between the two (Szabo 2014, "Diagnostic Ultrasound
//! Imaging: Inside Out", 2nd ed., ch. 10, reverberation artefacts). No
//! published level was found for the thigh; the levels here follow from
//! the reflection coefficients of the acoustic impedances (published
//! densities and speeds of sound, `src/published_acoustics.rs`, which
//! tests the coefficients: fat 1.35–1.41 MRayl, muscle 1.59–1.69, dense
//! collagen (tendon, ligament) 1.82–2.09, cortical bone 5.7–8.8):
//!
//! - **Near field**: between the probe's face and the skin, fat and fascia
//!   echoes. A layer at image depth `z` repeats at `n z` (`n` = 2, 3) with
//!   its echo times `(R_p R_i)^{n−1}`, `R_p` the face's reflection
//!   (an estimate: a silicone lens of Z ≈ 1.0 MRayl on skin,
//!   (1.6 − 1.0)/(1.6 + 1.0) ≈ 0.23; no published reflection coefficient of
//!   a probe's face was found, and the stack behind a thin lens may reflect
//!   more) and `R_i` the layer's (fibrous tissue on fat ≈ 0.10, within the
//!   published 0.060 (fat on muscle) to 0.214 (fat on collagen)): −33 dB
//!   per round trip. The copies
//!   are taken from the column's own echo above the deep fascia
//!   ([`Reverberation::near_field`]), before the attenuation: the
//!   reverberant path's round trip to `n z` is the length of the direct
//!   echo's to `n z`, so the frame's loss and TGC at `n z` apply.
//! - **Lumen**: the near wall of a vessel (adventitia on perivascular fat,
//!   `R_w` ≈ 0.10) and the fibrous sheath above it ([`ReverbConfig::lumen_spacing`]
//!   away, `R_s` ≈ 0.10) repeat the wall's echo into the lumen at
//!   multiples of their spacing, `(R_w R_s)^m` = −40 dB per round trip. The
//!   wall's echo is its specular reflection `R_w`, on the scale on which
//!   this model sets the femoral cortex (`R` = 0.64 at +35 dB re muscle,
//!   [`crate::Tissue::Cortex`]): `35 + 20 log₁₀(0.10/0.64)` ≈ +19 dB re
//!   muscle, so the first copy lies ≈ −21 dB re muscle, a haze in the top
//!   of the lumen over the −35 dB diffuse clutter, still ≥ 20 dB under
//!   muscle (the lumen stays anechoic to the eye). The copies carry a unit
//!   speckle fixed to the tissue ([`wall_speckle`]: by the column of the
//!   tissue, not of the image, and the row below the lumen's top), so that
//!   they pan and move with the wall, over the wall's thickness.

use crate::error::ImagingError;
use crate::tissue::Tissue;
use serde::{Deserialize, Serialize};

/// The reverberation's switch and reflection coefficients
/// (`[imaging.reverberation]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReverbConfig {
    /// Draw the reverberation. Default true.
    pub enabled: bool,
    /// Amplitude reflection coefficient of the probe's face. Default 0.23.
    /// Accepted: 0 to 0.9.
    pub probe_reflection: f64,
    /// Amplitude reflection coefficient of the soft-tissue interfaces
    /// (fascia, septa, vessel adventitia and sheath against fat). Default
    /// 0.10. Accepted: 0 to 0.5.
    pub interface_reflection: f64,
    /// Distance from a vessel's near wall to the sheath above it (m): the
    /// spacing of the lumen's copies. Default 1e-3. Accepted: 0.1 to 5 mm.
    pub lumen_spacing: f64,
}

impl Default for ReverbConfig {
    fn default() -> Self {
        ReverbConfig {
            enabled: true,
            probe_reflection: 0.23,
            interface_reflection: 0.10,
            lumen_spacing: 1e-3,
        }
    }
}

impl ReverbConfig {
    /// Checks the ranges (keys named under `prefix`).
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "probe_reflection",
            self.probe_reflection,
            0.0,
            0.9,
            "must be between 0 and 0.9",
        )?;
        ImagingError::in_range(
            prefix,
            "interface_reflection",
            self.interface_reflection,
            0.0,
            0.5,
            "must be between 0 and 0.5 (soft-tissue interfaces)",
        )?;
        ImagingError::in_range(
            prefix,
            "lumen_spacing",
            self.lumen_spacing,
            1e-4,
            5e-3,
            "must be between 0.1 and 5 mm",
        )
    }
}

/// Multiples of the near field drawn: `n` = 2 … `NEAR_ORDERS`.
pub const NEAR_ORDERS: usize = 3;
/// Copies of a vessel's near wall drawn into its lumen.
pub const LUMEN_ORDERS: usize = 2;
/// Amplitude reflection coefficient of the bone's surface that sets the
/// cortex's echo ([`crate::Tissue::Cortex`]: Z ≈ 7.4 against 1.6 MRayl;
/// published impedances of cortical bone and muscle give 0.545–0.693,
/// `src/published_acoustics.rs`).
pub(crate) const BONE_REFLECTION: f64 = 0.64;

/// A vessel's lumen in one column of a frame (image depths, m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct LumenSpan {
    /// Inner surface of the near wall.
    pub top: f64,
    /// Inner surface of the far wall.
    pub bottom: f64,
    /// Wall thickness.
    pub wall: f64,
}

/// The reverberation of a renderer: gains and the lumen copies' speckle.
#[derive(Debug, Clone)]
pub(crate) struct Reverberation {
    /// Amplitude factor of the near-field multiple `n` (index `n`; 0 and 1 unused).
    near_gain: [f32; NEAR_ORDERS + 1],
    /// Amplitude of the lumen copy `m` (index `m − 1`) relative to muscle's
    /// mean echo at its depth.
    lumen_gain: [f32; LUMEN_ORDERS],
    /// Spacing of the lumen copies (m).
    spacing: f64,
    /// Seed of the lumen copies' speckle.
    seed: u64,
}

/// A unit-power circular Gaussian sample fixed to tissue column `column`
/// (material index) and row `row` below a lumen's top, for copy `copy`
/// of seed `seed`: a SplitMix64 hash of the four, two uniforms, Box–Muller.
pub(crate) fn wall_speckle(seed: u64, column: i64, row: usize, copy: usize) -> [f32; 2] {
    let mut z = seed
        ^ (column as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (row as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ (copy as u64).wrapping_mul(0x1656_67b1_9e37_79f9);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    let u1 = ((z >> 40) as f32 + 0.5) * (1.0 / (1u64 << 24) as f32);
    let u2 = ((z & 0xff_ffff) as f32) * (1.0 / (1u64 << 24) as f32);
    let r = (-u1.ln()).sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    [r * c, r * s]
}

impl Reverberation {
    /// The reverberation of `cfg`, its lumen copies' speckle from `seed`.
    pub fn new(cfg: &ReverbConfig, seed: u64) -> Self {
        let g = cfg.probe_reflection * cfg.interface_reflection;
        let mut near_gain = [0.0f32; NEAR_ORDERS + 1];
        for (n, v) in near_gain.iter_mut().enumerate().skip(2) {
            *v = g.powi(n as i32 - 1) as f32;
        }
        let cortex = Tissue::Cortex.acoustics().echo_db.unwrap_or(0.0);
        let r = cfg.interface_reflection;
        let wall = 10f64.powf(cortex / 20.0) * r / BONE_REFLECTION;
        let mut lumen_gain = [0.0f32; LUMEN_ORDERS];
        for (m, v) in lumen_gain.iter_mut().enumerate() {
            *v = (wall * (r * r).powi(m as i32 + 1)) as f32;
        }
        Reverberation {
            near_gain,
            lumen_gain,
            spacing: cfg.lumen_spacing,
            seed,
        }
    }

    /// Level of the first lumen copy relative to muscle (dB).
    #[cfg(test)]
    pub fn lumen_db(&self) -> f64 {
        20.0 * (self.lumen_gain[0] as f64).log10()
    }

    /// Adds the near-field multiples to one column's echo `iq` (complex
    /// baseband before attenuation, row `i` at image depth `(i + ½) dz`):
    /// `iq[i] += Σ_n (R_p R_i)^{n−1} iq[i_n]`, `i_n` the row at depth
    /// `z_i / n`, for sources above image depth `near_limit` (m; the deep
    /// fascia). Rows are taken bottom-up, so each source is read before it
    /// is changed.
    pub fn near_field(&self, iq: &mut [[f32; 2]], dz: f64, near_limit: f64) {
        let limit = (near_limit / dz).max(0.0);
        if limit < 1.0 {
            return;
        }
        let rows = iq.len();
        let top = ((NEAR_ORDERS as f64 * limit).ceil() as usize).min(rows);
        for i in (0..top).rev() {
            let mut acc = [0.0f32; 2];
            for n in 2..=NEAR_ORDERS {
                // Row whose centre lies at depth (i + ½) dz / n.
                let src = (i as f64 + 0.5) / n as f64;
                if src >= limit {
                    continue;
                }
                let s = iq[src as usize];
                acc[0] += self.near_gain[n] * s[0];
                acc[1] += self.near_gain[n] * s[1];
            }
            iq[i][0] += acc[0];
            iq[i][1] += acc[1];
        }
    }

    /// Adds the copies of a vessel's near wall into its lumen `span` in
    /// the column of tissue column `column` (material index): copy `m` fills the wall's
    /// thickness ending `m · spacing` below the lumen's top, at the
    /// amplitude of the first copy `− 40 (m − 1)` dB re muscle's
    /// mean echo `muscle[i]` (per row), inside the lumen only.
    pub fn lumen(
        &self,
        iq: &mut [[f32; 2]],
        column: i64,
        dz: f64,
        muscle: &[f32],
        span: LumenSpan,
    ) {
        let rows = iq.len();
        let row = |z: f64| ((z / dz - 0.5).ceil().max(0.0) as usize).min(rows);
        let (lo, hi) = (row(span.top), row(span.bottom));
        for (m, &g) in self.lumen_gain.iter().enumerate() {
            let end = span.top + (m + 1) as f64 * self.spacing;
            let (a, b) = (row(end - span.wall).max(lo), row(end).min(hi));
            for i in a..b {
                let k = g * muscle[i];
                let f = wall_speckle(self.seed, column, i - lo, m);
                iq[i][0] += k * f[0];
                iq[i][1] += k * f[1];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_follow_the_reflection_coefficients() {
        let r = Reverberation::new(&ReverbConfig::default(), 7);
        // (0.23 · 0.10)² per extra round trip: −32.8 dB (R_i = 0.10 lies in
        // the published 0.060–0.214 of `published_acoustics.rs`; R_p = 0.23
        // is an estimate).
        let near = 20.0 * (r.near_gain[2] as f64).log10();
        assert!((near + 32.77).abs() < 0.05, "{near}");
        // +18.9 dB for the wall, −40 dB for the round trip.
        assert!((r.lumen_db() + 21.1).abs() < 0.1, "{}", r.lumen_db());
    }

    #[test]
    fn the_wall_speckle_has_unit_power() {
        let n = 20_000;
        let p: f64 = (0..n)
            .map(|k| {
                let v = wall_speckle(3, k as i64 - 100, k % 7, k % 2);
                (v[0] * v[0] + v[1] * v[1]) as f64
            })
            .sum::<f64>()
            / n as f64;
        // Exponential power: the mean of 20 000 has a 0.7 % spread.
        assert!((p - 1.0).abs() < 0.03, "{p}");
    }

    #[test]
    fn a_near_field_layer_repeats_at_twice_its_depth() {
        let r = Reverberation::new(&ReverbConfig::default(), 7);
        let mut iq = vec![[0.0f32; 2]; 100];
        iq[10] = [1.0, 0.0];
        r.near_field(&mut iq, 1e-4, 20e-4);
        // Row 10 (depth 1.05 mm) repeats n times as thick at n times its
        // depth: rows 20–21 and 30–32.
        assert!((iq[21][0] - r.near_gain[2]).abs() < 1e-9);
        assert!((iq[31][0] - r.near_gain[3]).abs() < 1e-9);
        assert_eq!(iq[10], [1.0, 0.0]);
        let others: f32 = iq
            .iter()
            .enumerate()
            .filter(|(i, _)| ![10, 20, 21, 30, 31, 32].contains(i))
            .map(|(_, v)| v[0].abs())
            .sum();
        assert_eq!(others, 0.0);
    }
}
