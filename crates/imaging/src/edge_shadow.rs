//! Refraction edge shadows below the lateral margins of the vessels
//! (issue 21).
//!
//! Where the beam grazes a curved vessel wall, at the lumen's lateral
//! margins, the rays meet the blood–wall interface near or beyond the
//! critical angle and are refracted or totally reflected away from the
//! beam's axis; less energy goes on below, and a narrow dark streak runs
//! down from each lateral edge of a round vessel (the "edge" or "refraction
//! shadow": Ziskin et al. 1982, "Refraction shadowing artifact",
//! J. Ultrasound Med. 1; Szabo 2014, ch. 3, refraction at a curved
//! boundary). It is modelled as an extra round-trip loss below each margin
//! of the deformed lumen, applied with the attenuation:
//! `L(u, z) = S exp(−(u − u_m)²/(2σ²)) (1 − e^{−Δ/ℓ₀}) e^{−Δ/ℓ}` dB of
//! intensity, `Δ = z − z_m > 0`, `(u_m, z_m)` the outer margin of the
//! vessel in the image (the lateral extreme of its wall, where the beam
//! grazes it, and the chord's centre depth there, through the skin
//! displacement, the column compression and the warps): the shadow builds
//! up over `ℓ₀` below the margin as the refracted rays leave the beam, then
//! fades over `ℓ` as the beam refills it; it fades too as the lumen
//! flattens (a lens, then a line, grazes the beam over less and less of its
//! edge). The parameters are estimates for the narrow shadows of clinical
//! scans: [`SHADOW_DB`], [`SHADOW_WIDTH`], [`SHADOW_ONSET`],
//! [`SHADOW_LENGTH`], [`SHADOW_FADE`]. No published depth, width or loss of
//! an edge shadow below a vein was found. Steel et al. 2004 ("Origins of
//! the edge shadowing artefact in medical ultrasound imaging", Ultrasound
//! Med. Biol. 30(9)) describe the shadows as narrow hypoechoic lines running
//! "a significant distance" below the lateral edges, parallel to the beam,
//! arising where the beam meets the cavity near the critical angle; their
//! phantom shows that the pattern depends on the sign of the speed
//! contrast.
//!
//! **Width, derived.** A ray at lateral offset `x` from the centre of a
//! round lumen of radius `a` meets the wall at incidence `θ`, `sin θ = x/a`;
//! going from a slower into a faster medium it is totally reflected beyond
//! `θ_c = arcsin(c₁/c₂)`, i.e. over a band `a (1 − sin θ_c)` at each edge.
//! From fat (1461–1488 m/s) into muscle-like tissue (1517–1600 m/s;
//! `src/published_acoustics.rs`), `θ_c` = 66–79° and the band is 2–9 % of
//! the radius: 0.1–0.45 mm for the default vein's 5 mm radius, of the
//! order of the beam's lateral FWHM (0.44 mm, `σ` ≈ 0.19 mm), so the
//! shadow's lateral `σ` would be ≈ 0.2–0.3 mm; [`SHADOW_WIDTH`] (0.5 mm) is
//! wider than this derivation (kept: a derivation, not a measurement).

use crate::warp::MAX_VESSELS;

/// Loss at the core of an edge shadow, just below the margin (dB of
/// intensity, round trip): the streak reads clearly darker than the tissue
/// beside it without reaching the bone's shadow (≥ 10 dB, [`crate::tissue`]).
pub const SHADOW_DB: f64 = 10.0;
/// Lateral Gaussian width `σ` of an edge shadow (m): 0.5 mm, the order of
/// the beam's lateral FWHM at the vessels' depth (0.4–0.6 mm), over which
/// the beam's energy falls on the grazing band of the wall.
pub const SHADOW_WIDTH: f64 = 0.5e-3;
/// Depth over which an edge shadow builds up below the margin (m): 1.5 mm,
/// a third of the vessels' half-height, so that the streak is formed by
/// the vessel's bottom.
pub const SHADOW_ONSET: f64 = 1.5e-3;
/// Depth over which an edge shadow fades by `e` (m): 20 mm, the streak
/// runs well below the vessel as the beam slowly refills it.
pub const SHADOW_LENGTH: f64 = 20e-3;
/// Lumen ratio (area over rest) below which an edge shadow fades linearly
/// to nothing at closure.
pub const SHADOW_FADE: f64 = 0.25;

/// Most margins in a frame.
const MAX_EDGES: usize = 2 * MAX_VESSELS;

/// One margin of a lumen in the image.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Edge {
    /// Lateral position (m, image frame).
    u: f64,
    /// Image depth where the shadow starts (m).
    z: f64,
    /// Image depth of the vessel's top (m): the shallowest depth its
    /// lumen changes the loss.
    top: f64,
    /// Core loss (Np of amplitude).
    np: f64,
}

/// The margins of a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct EdgeShadows {
    edges: [Edge; MAX_EDGES],
    n: usize,
}

/// The margins that reach one column: `(start depth (m), loss (Np))`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ColumnShadow {
    edges: [(f64, f64); MAX_EDGES],
    n: usize,
}

impl EdgeShadows {
    /// No margins.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// Adds the margin at lateral `u` (m, image frame) and image depth `z`
    /// (m) of a vessel whose top lies at image depth `top` (m) and whose
    /// lumen's area is `ratio` of its rest area.
    pub fn push(&mut self, u: f64, z: f64, top: f64, ratio: f64) {
        let fade = (ratio / SHADOW_FADE).clamp(0.0, 1.0);
        if self.n < MAX_EDGES && fade > 0.0 && u.is_finite() && z.is_finite() {
            let np = SHADOW_DB * fade * std::f64::consts::LN_10 / 20.0;
            self.edges[self.n] = Edge { u, z, top, np };
            self.n += 1;
        }
    }

    /// The distance (m) from lateral `u` (m, image frame) to the nearest
    /// margin, and the shallowest top (m) of the vessels with a margin
    /// within `reach` (m); `None` if no margin is within `reach`.
    pub fn near(&self, u: f64, reach: f64) -> Option<(f64, f64)> {
        self.edges[..self.n]
            .iter()
            .filter(|e| (u - e.u).abs() <= reach)
            .fold(None, |acc, e| {
                let d = (u - e.u).abs();
                Some(match acc {
                    None => (d, e.top),
                    Some((d0, t0)) => (d.min(d0), e.top.min(t0)),
                })
            })
    }

    /// The margins within `3σ` of the column at lateral `u` (m, image
    /// frame), with their lateral weight applied.
    pub fn column(&self, u: f64) -> ColumnShadow {
        let mut c = ColumnShadow::default();
        for e in &self.edges[..self.n] {
            let x = (u - e.u) / SHADOW_WIDTH;
            // Cut at 3σ: 1 % of the core loss (0.1 dB).
            if x.abs() < 3.0 {
                c.edges[c.n] = (e.z, e.np * (-0.5 * x * x).exp());
                c.n += 1;
            }
        }
        c
    }
}

impl ColumnShadow {
    /// Whether no margin reaches the column.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Adds the shadows' loss exponent (Np of amplitude, ≤ 0; the module's
    /// `L(u, z)`) to each row of `loss` (row `i` at image depth
    /// `(i + ½) dz`, m), the exponentials
    /// carried down the rows by their constant ratio per row (two
    /// multiplies a row, not two `exp`).
    pub fn add_to(&self, loss: &mut [f64], dz: f64) {
        let (ka, kb) = ((-dz / SHADOW_ONSET).exp(), (-dz / SHADOW_LENGTH).exp());
        for &(z0, np) in &self.edges[..self.n] {
            // First row strictly below z0.
            let mut i0 = (z0 / dz - 0.5).ceil().max(0.0) as usize;
            if (i0 as f64 + 0.5) * dz <= z0 {
                i0 += 1;
            }
            if i0 >= loss.len() {
                continue;
            }
            let d0 = (i0 as f64 + 0.5) * dz - z0;
            let (mut a, mut b) = ((-d0 / SHADOW_ONSET).exp(), (-d0 / SHADOW_LENGTH).exp());
            for x in &mut loss[i0..] {
                *x -= np * (1.0 - a) * b;
                a *= ka;
                b *= kb;
            }
        }
    }

    /// Round-trip loss exponent (Np of amplitude, ≤ 0) at image depth `z`
    /// (m), by the formula ([`ColumnShadow::add_to`]'s reference).
    #[cfg(test)]
    pub fn loss_np(&self, z: f64) -> f64 {
        let mut x = 0.0;
        for &(z0, np) in &self.edges[..self.n] {
            if z > z0 {
                let dz = z - z0;
                x -= np * (1.0 - (-dz / SHADOW_ONSET).exp()) * (-dz / SHADOW_LENGTH).exp();
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shadow_below_the_margin_only() {
        let mut s = EdgeShadows::default();
        s.push(5e-3, 20e-3, 15e-3, 1.0);
        let core = s.column(5e-3);
        let full = SHADOW_DB * std::f64::consts::LN_10 / 20.0;
        assert_eq!(core.loss_np(19e-3), 0.0);
        assert!(core.loss_np(20e-3 + 1e-9).abs() < 1e-5);
        let deep = core.loss_np(20e-3 + 10.0 * SHADOW_ONSET);
        assert!((deep + full * (-10.0 * SHADOW_ONSET / SHADOW_LENGTH).exp()).abs() < 1e-4 * full);
        assert!(s.column(5e-3 + 1.6e-3).is_empty());
        // The row recurrence gives the same loss as the formula.
        let dz = 78e-6;
        let mut rows = vec![0.0; 768];
        core.add_to(&mut rows, dz);
        for (i, x) in rows.iter().enumerate() {
            let exact = core.loss_np((i as f64 + 0.5) * dz);
            assert!((x - exact).abs() < 1e-9, "row {i}: {x} vs {exact}");
        }
        // A closed lumen leaves no shadow.
        s.clear();
        s.push(5e-3, 20e-3, 15e-3, 0.0);
        assert!(s.column(5e-3).is_empty());
    }
}
