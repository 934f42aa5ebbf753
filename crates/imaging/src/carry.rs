//! A vessel carried rigidly through a collapsing neighbour's decay (issue
//! 21: "the artery stays round until the pressure cue").
//!
//! The vertical warp of a collapsing vessel `i` ([`crate::warp`]) moves the
//! tissue above its upper wall down by `D(x) = k (1 − x/L)` (`x` the height
//! above the wall, m) and the tissue below its lower wall up likewise. A
//! second vessel `j` lying in that decay would be stretched by the slope
//! `k/L`: its far side moves less than its near side, and since `k` is
//! largest over `i`'s axis its lumen is drawn as a teardrop pointing at
//! `i`. A pressurised artery is stiffer than the fat and muscle around it:
//! it is carried as a body. So over `j` the displacement is one value for
//! all its columns, `D_j`, the one `i`'s warp gives the point of `j`'s wall
//! nearest to `i` in the column through `j`'s centre (a neighbour touching
//! `i` moves with `i`'s wall, a far one hardly at all), and it blends back
//! into `D` around `j`:
//!
//! `D'(x) = D(x) + β ψ(x) (D_j − D(x))`,
//!
//! - `β = 1 − λ/M` (clamped to [0, 1]) in a column at the lateral distance
//!   `λ` beyond `j`'s outer half-width `o_j`, `M = o_j`;
//! - `ψ(x) = min(x/g, 1)` up to `j`'s far wall `x_f` in the column (from
//!   0 at `i`'s wall, so `i`'s walls keep moving with its lumen; `g` is
//!   the height `x_n` of `j`'s near wall, or more where the monotonicity
//!   bound below asks), then `ψ(x_f) (1 − (x − x_f)/m)` down to 0 over
//!   `m ≥ o_j` above it.
//!
//! Where `β ψ = 1` (all of `j`'s lumen, and its wall but where `i`'s own
//! wall in a column sinks less than `j` is carried) the map is a
//! translation by `D_j`: `j` keeps its shape and takes only its own
//! warp. `D'` is continuous across columns (`β`, `j`'s chord and
//! `i`'s are) and in depth (`ψ` is), and equals `D` beyond `j`'s margin.
//!
//! The map stays increasing. With `z` the depth (`x` grows upwards) the
//! map's slope is `1 − dD'/dx = 1 − (1 − βψ) D_x − β ψ_x (D_j − D)`. For a
//! collapsing `i` (`k > 0`) `D` falls with `x` (`D_x = −k/L`), so the
//! first two terms are at least 1; the last is negative only where
//! `D_j > D` on the rising ramp (`ψ_x = 1/g`) or `D_j < D` on the falling
//! one (`ψ_x = −ψ(x_f)/m`). In the column through `j`'s centre
//! `D_j = D(x_n)`, so neither happens (`D ≥ D_j` below `x_n`, `D ≤ D_j`
//! above `x_f`); in the others `g ≥ 1.5 β (D_j − D(x_n))` and
//! `m ≥ 1.5 β (D(x_f) − D_j)` keep the term above −2/3 at the ramps' ends
//! (`crate::warp`'s bound of 1/3); this is a bound at the ramps' ends,
//! not everywhere, so `the_carried_map_is_increasing_continuous_and_local`
//! checks the slope over the whole map of the section where it matters.
//! The same holds below `i` with `x` the depth under its lower wall and
//! the signs of `D` and `D_j − D` flipped. A lumen that expands (`k < 0`:
//! a systole, a column-strain compensation, a Valsalva distension)
//! carries nothing: its decay is the old one.
//!
//! The warps of one column are summed, each at the tissue point
//! ([`crate::warp::WarpSet`]), so `j`'s own warp still acts about `j`'s
//! rest axis and is then translated by `D_j`.

use crate::anatomy::Vessel;

/// The carriage of one neighbour through one side of a warp's decay, in
/// one column (m; `x` measured from the warp's vessel's outer wall,
/// outwards).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Carry {
    /// Lateral weight `β` (0: no carriage in this column).
    weight: f64,
    /// The neighbour's displacement `D_j` (m, positive downwards).
    target: f64,
    /// Height of the neighbour's far wall `x_f` (m).
    far: f64,
    /// Length of the rising ramp `g` (m, > 0).
    ramp: f64,
    /// Length of the falling ramp `m` (m, > 0).
    fade: f64,
}

impl Carry {
    /// The carriage of `neighbour` (its wall included) by `target` (m) in
    /// the column `u` (m, tissue frame) on the side of a warp whose
    /// vessel's outer wall is at depth `wall` (m; its top for
    /// `above`, else its bottom) and whose unheld displacement is `decay`
    /// (`x ↦ D(x)`, m). `None` where `β = 0` or the neighbour's far wall is
    /// not beyond the wall in this column.
    pub fn new(
        neighbour: &Vessel,
        target: f64,
        u: f64,
        wall: f64,
        above: bool,
        decay: impl Fn(f64) -> f64,
    ) -> Option<Self> {
        let o = neighbour.chord_half_width(neighbour.wall);
        let lambda = ((u - neighbour.lateral).abs() - o).max(0.0);
        let weight = 1.0 - lambda / o.max(1e-9);
        if weight <= 0.0 {
            return None;
        }
        let (c, h) = neighbour.chord(u, neighbour.wall);
        let (near, far) = if above {
            (wall - (c + h), wall - (c - h))
        } else {
            ((c - h) - wall, (c + h) - wall)
        };
        if far <= 0.0 {
            return None;
        }
        // The side's sign: below, `x` grows with depth and `D` is negative
        // (the tissue moves up), so the harmful differences flip.
        let sign = if above { 1.0 } else { -1.0 };
        let near = near.max(0.0);
        let ramp = near
            .max(1.5 * weight * (sign * (target - decay(near))).max(0.0))
            .max(1e-6);
        let fade = o.max(1.5 * weight * (sign * (decay(far) - target)).max(0.0));
        Some(Carry {
            weight,
            target,
            far,
            ramp,
            fade,
        })
    }

    /// `ψ(x)` (see the module's doc).
    #[inline]
    fn psi(&self, x: f64) -> f64 {
        if x <= self.far {
            (x / self.ramp).min(1.0)
        } else {
            (self.far / self.ramp).min(1.0) * (1.0 - (x - self.far) / self.fade).max(0.0)
        }
    }

    /// The carried displacement `D'(x)` (m) from the unheld `d = D(x)`.
    #[inline]
    pub fn apply(&self, x: f64, d: f64) -> f64 {
        if self.weight <= 0.0 {
            return d;
        }
        d + self.weight * self.psi(x) * (self.target - d)
    }

    /// How far from the wall (m) the carriage moves anything.
    pub fn reach(&self) -> f64 {
        if self.weight > 0.0 {
            self.far + self.fade
        } else {
            0.0
        }
    }

    /// Whether it carries anything.
    #[inline]
    pub fn is_active(&self) -> bool {
        self.weight > 0.0
    }
}

/// Whether `neighbour`'s outer ellipse lies wholly above (`Some(true)`) or
/// below (`Some(false)`) `v`'s, with its centre over `v`'s span of columns
/// (so `v`'s decay on that side reaches it); `None` otherwise (a vessel
/// beside `v`, at its depth, is not in its vertical decay).
pub fn stacked(v: &Vessel, neighbour: &Vessel) -> Option<bool> {
    let o = v.chord_half_width(v.wall);
    if (neighbour.lateral - v.lateral).abs() >= o {
        return None;
    }
    let own = outer_half_height(v);
    let (vt, vb) = (v.depth - own, v.depth + own);
    let reach = outer_half_height(neighbour);
    if neighbour.depth + reach <= vt {
        Some(true)
    } else if neighbour.depth - reach >= vb {
        Some(false)
    } else {
        None
    }
}

/// Half of the vertical extent (m) of `v` with its wall.
pub(crate) fn outer_half_height(v: &Vessel) -> f64 {
    let (sn, cs) = v.angle.sin_cos();
    let (a, b) = (v.radius + v.wall, v.radius_b + v.wall);
    (a * a * sn * sn + b * b * cs * cs).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::warp::VesselWarp;

    /// The section of `cfv-free-floating` at 130 mm (lean male), where the
    /// artery lies on the vein, its wall 0.08 mm above the vein's.
    fn pair() -> (Vessel, Vessel) {
        let vein = Vessel {
            lateral: 0.0,
            depth: 0.0321,
            radius: 0.00389,
            radius_b: 0.00299,
            angle: 0.0,
            wall: 0.0005,
        };
        (vein, Vessel::circle(0.00087, 0.02497, 0.00285, 0.0007))
    }

    const FLOOR: f64 = 0.084;

    /// The vein's warp in column `u` at ratio `c`, carrying the artery as
    /// the renderer does (the target: the unheld warp at the artery's
    /// nearest wall point in its centre column), and without the carriage.
    fn warps(c: f64, u: f64) -> (VesselWarp, VesselWarp, f64) {
        let (vein, art) = pair();
        let (mid, h) = art.chord(art.lateral, art.wall);
        let at = VesselWarp::new(&vein, art.lateral, c).with_floor(FLOOR);
        let target = at.apply(mid + h) - (mid + h);
        let plain = VesselWarp::new(&vein, u, c).with_floor(FLOOR);
        let carried = plain.carrying(&art, target, u, true, FLOOR);
        (plain, carried, target)
    }

    #[test]
    fn the_pair_is_stacked() {
        let (vein, art) = pair();
        assert_eq!(stacked(&vein, &art), Some(true));
        assert_eq!(stacked(&art, &vein), Some(false));
        // Side by side at the same depth (the default section): not stacked.
        let beside = Vessel::circle(0.0099, 0.0321, 0.0035, 0.0007);
        assert_eq!(stacked(&vein, &beside), None);
    }

    /// Over every column of the artery, a collapsing vein moves its lumen
    /// by one displacement: the lumen keeps its shape (to 1e-15 m, the
    /// rounding of a 3e-2 m depth). Its wall moves with it except where
    /// the vein's own upper wall, curved, sinks less than the artery is
    /// carried (towards the vein's lateral tip): there the artery's wall
    /// gives way by at most that lag (the unheld decay's displacement at
    /// the artery's outer bottom, short of `D_j`; 0.37 mm at `c` = 0),
    /// rather than the artery overlapping the vein's wall. Without the
    /// carriage the same warp moves the artery's near wall further than
    /// its far wall (the teardrop), which the test shows first.
    #[test]
    fn a_stacked_artery_moves_whole() {
        let (_, art) = pair();
        let o = art.chord_half_width(art.wall);
        for c in [0.0, 0.3, 0.7] {
            let (plain, _, target) = warps(c, art.lateral);
            let (mid, h) = art.chord(art.lateral, art.wall);
            let stretch = (plain.apply(mid + h) - (mid + h)) - (plain.apply(mid - h) - (mid - h));
            assert!(stretch > 0.1e-3 * (1.0 - c), "c = {c}: stretch {stretch}");
            assert!(target > 0.0);
            let (mut wall_worst, mut lag) = (0.0f64, 0.0f64);
            for k in 0..=200 {
                let u = art.lateral - o + 2.0 * o * k as f64 / 200.0;
                let (plain, w, _) = warps(c, u);
                let (mid, h) = art.chord(u, 0.0);
                let (outer_mid, outer) = art.chord(u, art.wall);
                let bottom = outer_mid + outer;
                if w.apply(bottom) - bottom != target {
                    lag = lag.max(target - (plain.apply(bottom) - bottom));
                }
                for t in 0..=20 {
                    let d = mid - h + 2.0 * h * t as f64 / 20.0;
                    let moved = w.apply(d) - d;
                    assert!(
                        (moved - target).abs() < 1e-15,
                        "c = {c}, u = {u}, d = {d}: {moved} vs {target}"
                    );
                    let d = outer_mid - outer + 2.0 * outer * t as f64 / 20.0;
                    wall_worst = wall_worst.max((w.apply(d) - d - target).abs());
                }
            }
            eprintln!("c = {c}: carried by {target} m, wall within {wall_worst} m (lag {lag} m)");
            assert!(
                wall_worst <= lag.max(0.0) + 1e-15,
                "c = {c}: wall off by {wall_worst}"
            );
        }
    }

    /// The carried map stays increasing (slope ≥ 1/3, the warp's bound,
    /// outside the vein's lumen and `c` inside it, less 1e-9 of rounding
    /// over 1 µm steps), is continuous across
    /// columns and is the plain warp beyond the artery's margin. Continuity:
    /// the map is piecewise linear in depth with knots that move with the
    /// two vessels' chords and slopes under 1.5 (1 + the decay's `k/L` ≤
    /// 1/2), so from one column to the next (`du` apart) a point moves by
    /// at most 1.5 times the chords' changes plus 1.5 `du` (the lateral
    /// weight `β` and `k` change by at most `du/o` and `du` per `du`; the
    /// chords change like `√du` at the vessels' lateral tips, so the bound
    /// is per pair of columns, not a fixed gradient).
    #[test]
    fn the_carried_map_is_increasing_continuous_and_local() {
        let (vein, art) = pair();
        let o = art.chord_half_width(art.wall);
        let v_o = vein.chord_half_width(vein.wall);
        for c in [0.0, 0.3, 0.7, 0.99] {
            let mut last_column: Option<(Vec<f64>, [f64; 4])> = None;
            let n = 1200;
            for k in 0..=n {
                let u = -v_o - 1e-3 + (2.0 * v_o + 2e-3) * k as f64 / n as f64;
                let (plain, w, _) = warps(c, u);
                let depths: Vec<f64> = (0..=30_000).map(|i| 0.012 + i as f64 * 1e-6).collect();
                let ys: Vec<f64> = depths.iter().map(|&d| w.apply(d)).collect();
                for (i, pair) in ys.windows(2).enumerate() {
                    assert!(
                        pair[1] - pair[0] >= 1e-6 * c.min(1.0 / 3.0) - 1e-9,
                        "c = {c}, u = {u}: slope {} at {}",
                        (pair[1] - pair[0]) / 1e-6,
                        depths[i]
                    );
                }
                if (u - art.lateral).abs() > 2.0 * o {
                    for &d in depths.iter().step_by(100) {
                        assert_eq!(w.apply(d), plain.apply(d), "c = {c}, u = {u}");
                    }
                }
                let chords = [
                    vein.chord(u, 0.0).1,
                    vein.chord(u, vein.wall).1,
                    art.chord(u, 0.0).1,
                    art.chord(u, art.wall).1,
                ];
                if let Some((prev, prev_chords)) = &last_column {
                    let jump = ys
                        .iter()
                        .zip(prev)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    let du = (2.0 * v_o + 2e-3) / n as f64;
                    let moved: f64 = chords
                        .iter()
                        .zip(prev_chords)
                        .map(|(a, b)| (a - b).abs())
                        .sum();
                    let bound = 1.5 * (moved + du) + 1e-12;
                    assert!(jump < bound, "c = {c}, u = {u}: jump {jump} > {bound}");
                }
                last_column = Some((ys, chords));
            }
        }
    }
}
