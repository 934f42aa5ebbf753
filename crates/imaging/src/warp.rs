//! The collapse (or pulsation) of a vessel, superposed on the column
//! compression of [`crate::deformation`].
//!
//! In the column `u`, let `h` be the half-height of the rest lumen's chord,
//! `η` the depth relative to the chord's centre and `c` the warp ratio (the
//! lumen's height, hence area, relative to rest). The lumen flattens about
//! its own axis, `η ↦ c η` for `|η| ≤ h`: in every column the chord keeps
//! its centre and scales by the same `c`, so a rest ellipse of semi-axes
//! `(a, b)` becomes the ellipse `(a, c b)` — a lens, then at `c = 0` a line
//! where the two walls meet. The walls (thickness `t` in the column: the
//! wall-grown chord's half-height minus `h`) move rigidly with the lumen's
//! edges, each by `k = (1 − c) h` towards the axis, so they keep their
//! scatterer density and the coapted walls stay a bright line; the tissue
//! beyond follows, the shift decaying linearly to 0 over `L` above the
//! upper wall and `L_b` below the lower one:
//! `η ↦ η + k (1 − max(x − t, 0)/L)` above (`x = −h − η ∈ [0, t + L]`),
//! `η ↦ η − k (1 − max(x − t, 0)/L_b)` below (`x = η − h ∈ [0, t + L_b]`).
//! The map is continuous (`±h ↦ ±c h` from both sides), increasing (slope
//! `c ≥ 0` inside, 1 in the walls, `1 + k/L` and `1 + k/L_b` beyond,
//! positive while `L`, `L_b > (c − 1) h`, enforced for an expanding lumen)
//! and the identity beyond `t + L` and `t + L_b`, so the skin keeps the
//! physics' displacement, the femur below [`VesselWarp::with_floor`] stays
//! where the column puts it, and the scatterers (fixed in tissue
//! coordinates) are carried, not torn. The tissue stretched by `1 + k/L`
//! echoes `10 log10(1 + k/L)` dB less (fewer scatterers per pixel): with
//! `L = 2 b` above, at most 1.5 dB for a closed vein (the old map, which
//! moved the upper wall by `2k` over `1.5 b`, stretched by up to 2.3, 3.7
//! dB, and the upper wall with it).
//!
//! The warp is vertical only (the scatterers are binned by column). The
//! lumen's widening as it flattens (a wall that keeps its length,
//! [`crate::widen`]) is drawn after the splat by a lateral map of the
//! echo across columns ([`crate::lateral_map`]); the ratio given here is
//! then the lumen's height ratio, not its area ratio.

use crate::anatomy::Vessel;
use crate::carry::Carry;

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
    /// Shift of each wall towards the axis, `k = (1 − c) h` (m).
    shift: f64,
    /// Decay length above the upper wall, `L` (m).
    decay: f64,
    /// Decay length below the lower wall, `L_b` (m).
    decay_below: f64,
    /// Wall thickness in this column, `t` (m): moves rigidly.
    wall: f64,
    lo: f64,
    hi: f64,
    /// Half-height of a central content band (m; 0: none).
    band: f64,
    /// Displacement of that band within the lumen (m).
    band_shift: f64,
    /// A neighbour carried through the decay above ([`crate::carry`]).
    above: Carry,
    /// A neighbour carried through the decay below.
    below: Carry,
}

impl VesselWarp {
    /// The warp of `vessel` in the column `u` with lumen ratio `ratio`; the
    /// tissue around follows over `L = 2 b` above (`b` the vessel's
    /// half-height; at most 0.8 of the depth of its outer top, so the skin
    /// stays) and `L_b = 2 b` below, each at least `1.5 |k|` if the lumen
    /// expands, which keeps the map increasing (slope ≥ 1/3).
    pub fn new(vessel: &Vessel, u: f64, ratio: f64) -> Self {
        let (centre, h) = vessel.chord(u, 0.0);
        let wall = (vessel.chord(u, vessel.wall).1 - h).max(0.0);
        let shift = (1.0 - ratio) * h;
        let least = 1.5 * (-shift).max(0.0);
        let b = vessel.half_height();
        let above = (2.0 * b)
            .min(0.8 * (centre - h - wall))
            .max(least)
            .max(1e-4);
        let below = (2.0 * b).max(least);
        VesselWarp {
            centre,
            half_height: h,
            ratio,
            shift,
            decay: above,
            decay_below: below,
            wall,
            lo: centre - h - wall - above,
            hi: centre + h + wall + below,
            band: 0.0,
            band_shift: 0.0,
            above: Carry::default(),
            below: Carry::default(),
        }
    }

    /// The unheld displacement (m) of the decay above (`above`) or below
    /// at the distance `x` (m) from the outer wall.
    #[inline]
    fn decay_at(&self, above: bool, x: f64) -> f64 {
        if above {
            self.shift * (1.0 - x / self.decay).max(0.0)
        } else {
            -self.shift * (1.0 - x / self.decay_below).max(0.0)
        }
    }

    /// This warp carrying `neighbour` rigidly by `target` (m) through its
    /// decay above (`above`) or below ([`crate::carry`]) in the column
    /// `u` (m, tissue frame). Only a collapsing lumen (ratio < 1) carries,
    /// one neighbour a side (the first given); below, nothing is carried
    /// past `floor` (m, the femur's top).
    pub fn carrying(
        mut self,
        neighbour: &Vessel,
        target: f64,
        u: f64,
        above: bool,
        floor: f64,
    ) -> Self {
        let taken = if above { &self.above } else { &self.below };
        if self.ratio >= 1.0 || taken.is_active() {
            return self;
        }
        let h = self.half_height;
        let wall = if above {
            self.centre - h - self.wall
        } else {
            self.centre + h + self.wall
        };
        let Some(c) = Carry::new(neighbour, target, u, wall, above, |x| {
            self.decay_at(above, x)
        }) else {
            return self;
        };
        if above {
            self.above = c;
            self.lo = self.lo.min(wall - c.reach());
        } else if wall + c.reach() < floor {
            self.below = c;
            self.hi = self.hi.max(wall + c.reach());
        }
        self
    }

    /// This warp with the tissue below the vessel held from depth `floor`
    /// (m) down (the femur's top: bone does not follow a vein's collapse).
    /// The lower decay ends at `floor` (a collapsing lumen, `k > 0`, keeps
    /// the slope `1 + k/L_b > 1` for any `L_b`), but stays at least
    /// `1.5 |k|` for an expanding one (slope ≥ 1/3) and at least 0.1 mm.
    pub fn with_floor(mut self, floor: f64) -> Self {
        let outer = self.centre + self.half_height + self.wall;
        let room = (floor - outer).max(1.5 * (-self.shift).max(0.0)).max(1e-4);
        self.decay_below = self.decay_below.min(room);
        self.hi = outer + self.decay_below;
        self
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
        (self.half_height > 0.0 && (self.shift != 0.0 || self.band_shift != 0.0))
            || self.above.is_active()
            || self.below.is_active()
    }

    /// The warped depth (m) of the tissue point at depth `depth` (m).
    #[inline]
    pub fn apply(&self, depth: f64) -> f64 {
        if depth <= self.lo || depth >= self.hi {
            return depth;
        }
        let h = self.half_height;
        if h <= 0.0 && !self.above.is_active() && !self.below.is_active() {
            return depth;
        }
        let mut eta = depth - self.centre;
        if eta < -h {
            let x = (-h - eta - self.wall).max(0.0);
            return depth + self.above.apply(x, self.decay_at(true, x));
        }
        if eta > h {
            let x = (eta - h - self.wall).max(0.0);
            return depth + self.below.apply(x, self.decay_at(false, x));
        }
        if self.band_shift != 0.0 {
            eta = self.tail_map(eta);
        }
        self.centre + self.ratio * eta
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

    /// The warped depth (m) of the tissue point at `depth` (m): the sum of
    /// the warps' displacements, each at the tissue point (each vessel's
    /// warp is defined about its rest axis; a carried neighbour,
    /// [`crate::carry`], then takes its own warp whole plus a translation).
    #[inline]
    pub fn apply(&self, depth: f64) -> f64 {
        match self.n {
            0 => depth,
            1 => self.w[0].apply(depth),
            _ => self.w[..self.n]
                .iter()
                .fold(depth, |y, w| y + (w.apply(depth) - depth)),
        }
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
            if ratio <= 1.6 {
                // Beyond 2 radii above and below the walls nothing moves.
                assert_eq!(w.apply(0.0144), 0.0144);
                assert_eq!(w.apply(0.0456), 0.0456);
            }
            // Held from the floor down while the lumen does not expand.
            let f = w.with_floor(0.038);
            if ratio <= 1.0 {
                assert_eq!(f.apply(0.038), 0.038);
            }
            let mut last = f64::NEG_INFINITY;
            for i in 0..4000 {
                let y = f.apply(0.015 + i as f64 * 1e-5);
                assert!(
                    y >= last - 1e-15,
                    "floored map not monotone for c = {ratio}"
                );
                last = y;
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
    fn lumen_flattens_about_its_axis_into_an_ellipse() {
        // An oval vein, 1.3 times wider than tall.
        let mut v = vessel();
        v.radius = 0.0057;
        v.radius_b = 0.0044;
        for c in [0.0, 0.25, 0.7, 1.2] {
            for u in [0.0, 0.002, 0.004, 0.0055] {
                let (centre, h) = v.chord(u, 0.0);
                let w = VesselWarp::new(&v, u, c);
                let (top, bottom) = (w.apply(centre - h), w.apply(centre + h));
                // Centred on the axis, of height c times the chord's: the
                // ellipse of semi-axes (a, c b).
                assert!((0.5 * (top + bottom) - v.depth).abs() < 1e-15);
                assert!(((bottom - top) - 2.0 * c * h).abs() < 1e-15);
                // The walls move rigidly, each by (1 − c) h towards the axis.
                let t = v.chord(u, v.wall).1 - h;
                let k = (1.0 - c) * h;
                for d in [centre - h - t, centre - h - 0.5 * t] {
                    assert!((w.apply(d) - (d + k)).abs() < 1e-15);
                }
                for d in [centre + h + t, centre + h + 0.5 * t] {
                    assert!((w.apply(d) - (d - k)).abs() < 1e-15);
                }
            }
        }
        // Outside the vessel's width nothing moves.
        let w = VesselWarp::new(&v, 0.006, 0.0);
        assert!(!w.is_active());
        assert_eq!(w.apply(0.03), 0.03);
    }
}
