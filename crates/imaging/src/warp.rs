//! The collapse (or pulsation) of a vessel, superposed on the column
//! compression of [`crate::deformation`].
//!
//! In the column `u`, let `h` be the half-height of the rest lumen, `η` the
//! depth relative to the vessel's centre and `c` the lumen ratio (area and
//! height relative to rest). The lower wall stays on its bed; the lumen
//! shrinks towards it, `η ↦ h − c (h − η)` for `|η| ≤ h`; the tissue above
//! follows, shifted down by `k = 2 (1 − c) h` at the upper wall and by a
//! linearly decaying amount up to a distance `L` above it:
//! `η ↦ η + k (1 − x/L)` with `x = −h − η ∈ [0, L]`. The map is continuous
//! and increasing (its slope `1 + k/L` is positive for `L > 2 (c − 1) h`, true
//! for the pulsation), leaves the tissue below the vessel and above `L` in
//! place, so the skin keeps the physics' displacement, and carries the
//! scatterers and the walls with the lumen: a collapsed healthy vein shows
//! its two walls meeting in a bright line.

use crate::anatomy::Vessel;

/// The warp ratio that gives a lumen of height ratio `ratio` in space in a
/// column compressed by the skin displacement `surface` (m) towards the femur
/// at `bone_depth` (m): the column map scales heights by `1 − s/B`, so the
/// warp must scale them by `ratio / (1 − s/B)` (the fluid-filled lumen does
/// not take the column's strain; the tissue around it does).
pub fn compensated_ratio(ratio: f64, surface: f64, bone_depth: f64) -> f64 {
    ratio / (1.0 - surface / bone_depth).max(0.05)
}

/// The vertical map of one vessel's collapse in one column, in tissue
/// coordinates (depths below the undeformed skin, m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VesselWarp {
    centre: f64,
    half_height: f64,
    ratio: f64,
    shift: f64,
    decay: f64,
    lo: f64,
    hi: f64,
    /// Half-height of a central content band (m; 0: none).
    band: f64,
    /// Displacement of that band within the lumen (m).
    band_shift: f64,
}

impl VesselWarp {
    /// The warp of `vessel` in the column `u` with lumen ratio `ratio`; the
    /// tissue above follows over `1.5` radii (or `1.5 |k|` if the lumen expands and that is larger, which
    /// keeps the map increasing).
    pub fn new(vessel: &Vessel, u: f64, ratio: f64) -> Self {
        let (centre, h) = vessel.chord(u, 0.0);
        let decay = (1.5 * vessel.half_height()).max(3.0 * (ratio - 1.0) * h);
        VesselWarp {
            centre,
            half_height: h,
            ratio,
            shift: 2.0 * (1.0 - ratio) * h,
            decay,
            lo: centre - h - decay,
            hi: centre + h,
            band: 0.0,
            band_shift: 0.0,
        }
    }

    /// This warp with a central content band of `fill` of the chord (a
    /// floating tail, `|η| < fill h`) moved by `shift · h` within the
    /// lumen before the collapse: the piecewise-linear map of the chord
    /// through `(−h, −h)`, `(∓b, ∓b + δ)`, `(h, h)` (`b = fill h`,
    /// `δ = shift h`), which keeps the band's shape, squeezes the blood on
    /// one side and stretches it on the other, and stays increasing while
    /// `|δ| < h − b` (`shift` is clamped to 0.95 of that).
    pub fn with_tail(mut self, fill: f64, shift: f64) -> Self {
        let h = self.half_height;
        if h <= 0.0 || fill <= 0.0 || fill >= 1.0 || shift == 0.0 {
            return self;
        }
        let room = 0.95 * (1.0 - fill);
        self.band = fill * h;
        self.band_shift = shift.clamp(-room, room) * h;
        self
    }

    /// The tail's map of the chord coordinate `eta` (m, |eta| ≤ h).
    #[inline]
    fn tail_map(&self, eta: f64) -> f64 {
        let (h, b, d) = (self.half_height, self.band, self.band_shift);
        if eta < -b {
            -h + (eta + h) * (h - b + d) / (h - b)
        } else if eta <= b {
            eta + d
        } else {
            h - (h - eta) * (h - b - d) / (h - b)
        }
    }

    /// Whether the warp moves anything in this column.
    #[inline]
    pub fn is_active(&self) -> bool {
        self.half_height > 0.0 && (self.shift != 0.0 || self.band_shift != 0.0)
    }

    /// The warped depth (m) of the tissue point at depth `depth` (m).
    #[inline]
    pub fn apply(&self, depth: f64) -> f64 {
        if depth <= self.lo || depth > self.hi || self.half_height <= 0.0 {
            return depth;
        }
        let h = self.half_height;
        let mut eta = depth - self.centre;
        if self.band_shift != 0.0 && eta.abs() <= h {
            eta = self.tail_map(eta);
        }
        if eta >= -h {
            self.centre + h - self.ratio * (h - eta)
        } else {
            let x = -h - eta;
            depth + self.shift * (1.0 - x / self.decay)
        }
    }
}

/// Most vessels in one section: the studied pair and the extra structures.
pub const MAX_VESSELS: usize = 2 + crate::structure_config::MAX_STRUCTURES;

/// The active warps of one column, applied in order (each map is
/// increasing, so their composition is too).
#[derive(Debug, Clone, Copy, Default)]
pub struct WarpSet {
    n: usize,
    w: [VesselWarp; MAX_VESSELS],
}

impl WarpSet {
    /// Empties the set.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// Adds `w` if it moves anything in this column.
    pub fn push(&mut self, w: VesselWarp) {
        if w.is_active() && self.n < MAX_VESSELS {
            self.w[self.n] = w;
            self.n += 1;
        }
    }

    /// Whether the set moves anything.
    #[inline]
    pub fn is_active(&self) -> bool {
        self.n > 0
    }

    /// The warped depth (m) of the tissue point at `depth` (m).
    #[inline]
    pub fn apply(&self, depth: f64) -> f64 {
        self.w[..self.n].iter().fold(depth, |d, w| w.apply(d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vessel() -> Vessel {
        Vessel::circle(0.0, 0.03, 0.005, 0.0005)
    }

    #[test]
    fn continuous_increasing_and_local() {
        for ratio in [0.0, 0.3, 1.0, 1.07, 1.6, 4.0] {
            let w = VesselWarp::new(&vessel(), 0.001, ratio);
            let mut last = f64::NEG_INFINITY;
            for i in 0..4000 {
                let d = 0.015 + i as f64 * 1e-5;
                let y = w.apply(d);
                assert!(y >= last - 1e-15, "not monotone at {d} for c = {ratio}");
                if i > 0 {
                    assert!(y - last < 1e-4, "jump at {d}");
                }
                last = y;
            }
            assert_eq!(w.apply(0.04), 0.04);
            if ratio <= 1.6 {
                assert_eq!(w.apply(0.015), 0.015);
            }
        }
    }

    #[test]
    fn tail_band_moves_whole_and_map_stays_increasing() {
        let v = vessel();
        let h = v.radius;
        for shift in [-0.3, 0.2, 0.5] {
            let w = VesselWarp::new(&v, 0.0, 1.0).with_tail(0.35, shift);
            assert!(w.is_active());
            // The band |η| < 0.35 h moves by shift·h as a block.
            for eta in [-0.3 * h, 0.0, 0.3 * h] {
                let y = w.apply(v.depth + eta);
                assert!((y - (v.depth + eta + shift * h)).abs() < 1e-15);
            }
            // The walls stay; the map is increasing across the lumen.
            assert!((w.apply(v.depth - h) - (v.depth - h)).abs() < 1e-15);
            assert!((w.apply(v.depth + h) - (v.depth + h)).abs() < 1e-15);
            let mut last = f64::NEG_INFINITY;
            for i in 0..=1000 {
                let y = w.apply(v.depth - h + 2.0 * h * i as f64 / 1000.0);
                assert!(y > last);
                last = y;
            }
        }
    }

    #[test]
    fn lumen_height_scales_by_the_ratio() {
        let v = vessel();
        let w = VesselWarp::new(&v, 0.0, 0.25);
        let top = w.apply(v.depth - v.radius);
        let bottom = w.apply(v.depth + v.radius);
        assert!((bottom - (v.depth + v.radius)).abs() < 1e-15);
        assert!(((bottom - top) - 0.25 * 2.0 * v.radius).abs() < 1e-12);
        // Outside the vessel's width nothing moves.
        let w = VesselWarp::new(&v, 0.006, 0.0);
        assert!(!w.is_active());
        assert_eq!(w.apply(0.03), 0.03);
    }
}
