//! How chronic post-thrombotic change looks inside a vein (issue 13): a
//! thick, irregular, echogenic wall, webs (synechiae: thin bright fibrous
//! bands across the lumen) and the lumen partly recanalized as several
//! small channels in the residual fibrous material.
//!
//! Numbers and sources:
//! - **Wall thickness**: post-thrombotic femoral, popliteal and calf vein
//!   walls measured with a high-resolution linear probe: 0.8 mm where the
//!   luminal surface is smooth, 1.1 mm in heterogeneous (irregular)
//!   segments, against 0.37 mm in controls; the heterogeneous regions are
//!   1.40× (1.25–1.48×) thicker than the adjacent post-thrombotic wall
//!   ("Heterogeneity in post-thrombotic vein wall remodeling", J Vasc Surg
//!   Venous Lymphat Disord; abstract at
//!   https://discovery.researcher.life/article/heterogeneity-in-post-thrombotic-vein-wall-remodeling/dac9f438e5b7320f848f1b6c27e67899).
//!   Here the condition's `wall_thickness` is the thickest (heterogeneous)
//!   wall — the chronic default 1.5 mm is the healthy 0.5 mm times
//!   1.1/0.37 = 2.97 — and the smooth wall is that over
//!   [`IRREGULAR_THICKENING`] (1.40×: 1.07 mm, i.e. 0.5 mm × 0.8/0.37),
//!   thickened over [`PLAQUES`] arcs around the circumference.
//! - **Echogenicity**: the post-thrombotic wall and the webs are fibrous
//!   (collagen) tissue; they are drawn at the condition's `wall_echo` (the
//!   chronic state's default: +12 dB re muscle, the echo of fascia, the
//!   other collagen sheet of the section, `Tissue::Fascia`; derived: no
//!   published backscatter of a post-thrombotic wall was found).
//! - **Webs**: thin bands across the lumen, [`WEB_THICKNESS`] thick
//!   (estimate: "thin echogenic bands", Rumack ch. 27; no measured
//!   thickness found), as chords of the lumen tilted a little (±15°).
//! - **Channels**: the recanalized part of the lumen as `webs + 1` small
//!   round channels of blood, one between each pair of webs, their total
//!   area the condition's open fraction `1 − fill` as far as each fits in
//!   its band (recanalisation "as several small channels", the reference's
//!   row 24; the mechanics keeps `fill` whatever the drawing fits).
//!
//! Geometry is in the lumen's normalised frame: `(x, y)` along the
//! ellipse's axes `a` and `b` divided by them (the lumen is the unit disc),
//! `y` towards depth for an unrotated ellipse. Deterministic in `seed`.

use crate::error::ImagingError;
use serde::{Deserialize, Serialize};

/// Thickening of the irregular (heterogeneous) wall regions relative to
/// the smooth post-thrombotic wall: 1.40 (source in the module docs).
pub const IRREGULAR_THICKENING: f64 = 1.40;
/// Number of thickened arcs around the circumference.
pub const PLAQUES: usize = 3;
/// Thickness of a web (m): 0.5 mm (estimate, module docs).
pub const WEB_THICKNESS: f64 = 0.5e-3;
/// Most webs drawn.
pub const MAX_WEBS: u8 = 3;

/// The post-thrombotic pattern of a chronic vein.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PostThrombotic {
    /// Webs across the lumen, 0 to 3 (the channels are `webs + 1`).
    pub webs: u8,
    /// Seed of the pattern's tilts, offsets and plaques.
    pub seed: u64,
}

/// Smooth bump `cos²` of half-width `w` (rad) around 0, for angle `d` (rad).
fn bump(d: f64, w: f64) -> f64 {
    let d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if d.abs() >= w {
        0.0
    } else {
        (0.5 * std::f64::consts::PI * d / w).cos().powi(2)
    }
}

/// A number in [0, 1) from `seed` and `k` (splitmix64; hand-written as
/// one hash of two integers, where a `rand` generator would need state).
fn unit(seed: u64, k: u64) -> f64 {
    let mut z = seed
        .wrapping_add(k.wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

impl PostThrombotic {
    /// Checks the fields, naming the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        if self.webs > MAX_WEBS {
            return Err(ImagingError::invalid(
                prefix,
                "webs",
                self.webs as f64,
                "must be at most 3",
            ));
        }
        Ok(())
    }

    /// Wall thickness (m) at polar angle `phi` (rad, around the vessel's
    /// centre) for the thickest wall `wall` (m):
    /// `wall (1 + 0.4 B(φ)) / 1.4`, `B` the sum (at most 1) of [`PLAQUES`]
    /// `cos²` bumps of half-width 0.5 rad at seeded angles.
    pub fn wall_at(&self, wall: f64, phi: f64) -> f64 {
        let b: f64 = (0..PLAQUES as u64)
            .map(|k| {
                let centre =
                    std::f64::consts::TAU * (k as f64 + unit(self.seed, 10 + k)) / PLAQUES as f64;
                bump(phi - centre, 0.5)
            })
            .sum::<f64>()
            .min(1.0);
        wall * (1.0 + (IRREGULAR_THICKENING - 1.0) * b) / IRREGULAR_THICKENING
    }

    /// Normalised depth `y` of web `k`'s chord at `x`: webs evenly spaced
    /// in `y` (`−1 + 2 (k + 1)/(webs + 1)`), each tilted by a seeded angle
    /// within ±15°.
    fn web_y(&self, k: u8, x: f64) -> f64 {
        let (y0, tilt) = self.web(k);
        y0 + x * tilt.tan()
    }

    /// Web `k`'s normalised depth at `x = 0` and its tilt (rad).
    fn web(&self, k: u8) -> (f64, f64) {
        let y0 = -1.0 + 2.0 * (k as f64 + 1.0) / (self.webs as f64 + 1.0);
        let tilt = (unit(self.seed, 20 + k as u64) - 0.5) * 30f64.to_radians();
        (y0, tilt)
    }

    /// Whether the normalised lumen point `(x, y)` lies on a web; `half_y`
    /// is half the web's thickness in normalised units (`WEB_THICKNESS / 2b`).
    pub fn on_web(&self, x: f64, y: f64, half_y: f64) -> bool {
        (0..self.webs).any(|k| (y - self.web_y(k, x)).abs() < half_y)
    }

    /// Whether the normalised lumen point `(x, y)` lies in a recanalized
    /// channel, for an open fraction `open` (0 to 1) of the lumen's area.
    /// Channel `k` (of `webs + 1`) sits mid-band at `y_k`, offset in `x` by
    /// a seeded amount within ±0.2; its radius is `√(open / n)` (area
    /// fraction `open / n` of the unit disc) capped to stay clear of the
    /// disc's edge and of every web (its distance to the web's line
    /// `|y_k − y₀ − x_k tan α| cos α`) by `margin` (normalised).
    pub fn in_channel(&self, x: f64, y: f64, open: f64, margin: f64) -> bool {
        if open <= 0.0 {
            return false;
        }
        let n = self.webs as f64 + 1.0;
        let band = 2.0 / n;
        let r_area = (open / n).sqrt();
        (0..=self.webs).any(|k| {
            let yc = -1.0 + band * (k as f64 + 0.5);
            let xc = (unit(self.seed, 30 + k as u64) - 0.5) * 0.4;
            let to_edge = 1.0 - xc.hypot(yc) - margin;
            let to_webs = (0..self.webs)
                .map(|w| {
                    let (y0, a) = self.web(w);
                    (yc - y0 - xc * a.tan()).abs() * a.cos() - margin
                })
                .fold(f64::INFINITY, f64::min);
            let r = r_area.min(to_edge).min(to_webs);
            r > 0.0 && (x - xc).hypot(y - yc) < r
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wall_between_smooth_and_irregular() {
        let p = PostThrombotic { webs: 2, seed: 7 };
        let w: Vec<f64> = (0..720)
            .map(|i| p.wall_at(1e-3, i as f64 * std::f64::consts::TAU / 720.0))
            .collect();
        let (lo, hi) = w
            .iter()
            .fold((f64::MAX, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
        // Smooth 1/1.4 of the thickest; the bumps' peaks (cos² = 1 at
        // their centres, sampled every 0.5°: within 1e-4 relative) reach it.
        assert!(
            (lo - 1e-3 / IRREGULAR_THICKENING).abs() < 1e-12,
            "smooth wall {lo}"
        );
        assert!((hi - 1e-3).abs() < 1e-7, "thickest {hi}");
    }

    #[test]
    fn channels_open_as_much_as_fits_and_avoid_the_webs() {
        let p = PostThrombotic { webs: 2, seed: 3 };
        let (mut inside, mut open, mut clash) = (0usize, 0usize, 0usize);
        let n = 400;
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (
                    -1.0 + 2.0 * (i as f64 + 0.5) / n as f64,
                    -1.0 + 2.0 * (j as f64 + 0.5) / n as f64,
                );
                if x.hypot(y) >= 1.0 {
                    continue;
                }
                inside += 1;
                let c = p.in_channel(x, y, 0.15, 0.05);
                open += usize::from(c);
                clash += usize::from(c && p.on_web(x, y, 0.05));
            }
        }
        // 0.15 of the disc fits (3 channels of radius 0.22 < the band's room):
        // the open area is 0.15 within the grid's error (~1/n per unit length).
        let frac = open as f64 / inside as f64;
        assert!((frac - 0.15).abs() < 0.01, "open fraction {frac}");
        assert_eq!(clash, 0);
    }
}
