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
//! A lumen that expands in tissue coordinates (`c > 1`: a thrombosed vein
//! that keeps its height while the column around it is compressed,
//! [`compensated_ratio`], a systole, a distension) pushes its lower wall
//! down by `(c − 1) h`. Near the femur the tissue below cannot take all
//! of it: the decay below must end at the femur's top with slope ≥ 1/3,
//! so the lower wall may move down by at most `g/1.5` (`g` the gap from
//! the vessel's outer bottom to the femur's top); and an expanded lumen that crossed the femur's depth `B` would leave the
//! column map's linear part (`y = d + s (1 − d/B)` above `B`, the identity
//! below): its part below `B` escapes the column's compression and is
//! drawn `1/(1 − s/B)` times taller than the rest, a point at the bottom
//! (the pear-shaped thrombosed vein of issue 21 at 10–15 N). So the whole
//! lumen is lifted, `η ↦ δ + c η` with the walls moved by `k + δ` (above)
//! and `−k + δ` (below), by the one displacement of the vessel
//! `δ = min(0, g/1.5 − (c − 1) b)` (`b` the lumen's half-height, the
//! tallest chord's): an
//! incompressible lumen is displaced towards the probe as a whole and its
//! surroundings compress ([`VesselWarp::with_floor`]). Every column takes
//! the same `δ` and scales its chord by the same `c` about it, so the
//! lumen stays the rest ellipse scaled by `c` in height: convex.
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
    /// The whole lumen's displacement `δ` (m, positive downwards; ≤ 0:
    /// an expanding lumen lifted off the femur, [`VesselWarp::with_floor`]).
    lift: f64,
    /// The vessel's lumen half-height `b` (m, its tallest chord's).
    vessel_half_height: f64,
    /// The vessel's outer bottom at rest (m: its centre depth plus its
    /// wall-grown half-height).
    vessel_bottom: f64,
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
        let below = (2.0 * b).max(least);
        let mut w = VesselWarp {
            centre,
            half_height: h,
            ratio,
            shift,
            decay: 0.0,
            decay_below: below,
            wall,
            lo: 0.0,
            hi: centre + h + wall + below,
            band: 0.0,
            band_shift: 0.0,
            above: Carry::default(),
            below: Carry::default(),
            lift: 0.0,
            vessel_half_height: b,
            vessel_bottom: vessel.depth + crate::carry::outer_half_height(vessel),
        };
        w.set_decay_above();
        w
    }

    /// The decay above, `L = 2 b` at most 0.8 of the depth of the outer
    /// top (so the skin stays), at least `1.5 |k + δ|` for an upper wall
    /// moving up (slope `1 + (k + δ)/L ≥ 1/3`), and where it starts.
    fn set_decay_above(&mut self) {
        let top = self.centre - self.half_height - self.wall;
        let least = 1.5 * (-(self.shift + self.lift)).max(0.0);
        self.decay = (2.0 * self.vessel_half_height)
            .min(0.8 * top)
            .max(least)
            .max(1e-4);
        self.lo = top - self.decay;
    }

    /// The unheld displacement (m) of the decay above (`above`) or below
    /// at the distance `x` (m) from the outer wall.
    #[inline]
    fn decay_at(&self, above: bool, x: f64) -> f64 {
        if above {
            (self.shift + self.lift) * (1.0 - x / self.decay).max(0.0)
        } else {
            (self.lift - self.shift) * (1.0 - x / self.decay_below).max(0.0)
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
    /// (m) down (the femur's top: bone does not follow a vein's collapse,
    /// nor is it pushed by a lumen that expands). The lower decay ends at
    /// `floor`: a collapsing lumen (`k > 0`) keeps the slope `1 + k/L_b >
    /// 1` for any `L_b`; an expanding one (`c > 1`) is first lifted whole
    /// by `δ = min(0, g/1.5 − (c − 1) b)` (`g = floor −` the vessel's
    /// outer bottom; see the module's doc), which leaves its lower wall
    /// moving down by `K_b = (c − 1) h + δ ≤ g/1.5` in every column, so a
    /// decay of `1.5 K_b ≤ g` (slope ≥ 1/3) fits above the floor. The
    /// decay stays at least 0.1 mm (and `1.5 K_b` where the vessel
    /// already touches the floor, `g = 0`).
    pub fn with_floor(mut self, floor: f64) -> Self {
        if self.ratio > 1.0 {
            let gap = (floor - self.vessel_bottom).max(0.0);
            let push = (self.ratio - 1.0) * self.vessel_half_height;
            self.lift = (gap / 1.5 - push).min(0.0);
            self.set_decay_above();
        }
        let outer = self.centre + self.half_height + self.wall;
        let down = (self.lift - self.shift).max(0.0);
        let room = (floor - outer).max(1.5 * down).max(1e-4);
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
        (self.half_height > 0.0
            && (self.shift != 0.0 || self.band_shift != 0.0 || self.lift != 0.0))
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
        self.centre + self.lift + self.ratio * eta
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

    /// An expanding lumen 2 mm above the floor (a thrombosed vein keeping
    /// its height in a column compressed to 0.47, `c` = 1.72) is lifted
    /// whole: every column's chord maps to `δ + c η` about the axis with
    /// the same `δ = g/1.5 − (c − 1) b` (here −2.5 mm; to 1e-15 m, the
    /// rounding of 3e-2 m depths), the floor and the bone below it stay
    /// where they are, and the map stays increasing (slope ≥ 1/3, less
    /// 1e-9 of rounding over 1 µm steps).
    #[test]
    fn an_expanding_lumen_near_the_floor_is_lifted_whole() {
        let v = vessel();
        let c = 1.72;
        let floor = v.depth + v.radius + v.wall + 2e-3;
        let delta = 2e-3 / 1.5 - (c - 1.0) * v.radius;
        assert!(delta < -2e-3);
        for u in [0.0, 0.002, 0.004, 0.0049] {
            let w = VesselWarp::new(&v, u, c).with_floor(floor);
            let (centre, h) = v.chord(u, 0.0);
            for t in [-1.0, -0.5, 0.0, 0.7, 1.0] {
                let y = w.apply(centre + t * h);
                assert!((y - (v.depth + delta + c * t * h)).abs() < 1e-15, "u = {u}");
            }
            assert_eq!(w.apply(floor), floor);
            assert_eq!(w.apply(floor + 1e-3), floor + 1e-3);
            let mut last = f64::NEG_INFINITY;
            for i in 0..30_000 {
                let y = w.apply(0.005 + i as f64 * 1e-6);
                assert!(y - last >= 1e-6 / 3.0 - 1e-9, "u = {u}: slope at {i}");
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
