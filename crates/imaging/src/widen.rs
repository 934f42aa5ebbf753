//! The widening of a collapsing vessel (issue 21): a tube whose wall keeps
//! its length widens as it flattens.
//!
//! The vertical warp ([`crate::warp`]) flattens a lumen of rest semi-axes
//! `(a, b)` (`a` across, `b` in depth) into the ellipse `(a, c b)`, `c` the
//! height ratio. A thin-walled tube collapses by bending its wall, not by
//! stretching it (the bending stiffness of a wall of thickness `t` scales as
//! `t³`, its stretching stiffness as `t`), so its perimeter stays: the
//! flattened lumen is the ellipse `(a', c b)` with
//!
//! `P(a', c b) = P(a, b)`,
//!
//! `P` the perimeter, by Ramanujan's first approximation
//! `P(x, y) ≈ π [3 (x + y) − √((3x + y)(x + 3y))]` (exact for a circle;
//! `3.983 x` for the flat ellipse against the exact `4 x`, −0.4 %). A round
//! vein of radius `r` flattens into a line of half-width `2π r / 3.983 =
//! 1.577 r` (exact: `π r / 2 = 1.571 r`); the default oval vein (1.3 times
//! wider than tall) into one `1.40 a` wide.
//!
//! The lumen laws give the lumen's **area** ratio `A`; the drawn ellipse has
//! area `π a' c b`, so the height ratio is the `c` with `c a'(c) / a = A`
//! (solved by bisection: `c a'(c)` increases with `c` for a lumen wider
//! than tall, the case of a collapsing vein — an ellipse of fixed perimeter
//! encloses more the rounder it is).
//!
//! No published measurement of the compressed femoral vein's width was
//! found (a search of the stored pages for compression-ultrasound
//! diameters returned only areas under Valsalva and abdominal compression,
//! Rippey et al. 2008), so the inextensible wall is the model, an upper
//! bound: a wall that stretches would widen less.
//!
//! Two more rules, both stated where they apply:
//! - only the blood-filled part of a lumen collapses this way: a vein whose
//!   lumen holds thrombus over a fraction `fill` of its area widens by
//!   `(1 − fill)` of the law's widening (an occlusive thrombus, `fill = 1`,
//!   is a solid plug that keeps its shape);
//! - a lumen that expands (`A ≥ 1`: an artery's systole, a Valsalva
//!   distension) keeps its width (it distends, it does not unbuckle).
//!
//! The widening is shared between the lumen's two lateral edges, each moving
//! outwards by at most a third of the tissue between its wall and the next
//! vessel's (see [`side_caps`]), so that tissue is never squeezed below two
//! thirds of its width and a neighbour (the artery beside the femoral vein,
//! 0.6 mm away in the default section) is not pushed: the vein widens on
//! its free side.

use crate::anatomy::{Anatomy, Vessel};

/// Ramanujan's first approximation of the perimeter (m) of the ellipse of
/// semi-axes `x` and `y` (m): `π [3 (x + y) − √((3x + y)(x + 3y))]`.
pub fn ellipse_perimeter(x: f64, y: f64) -> f64 {
    let (x, y) = (x.max(0.0), y.max(0.0));
    std::f64::consts::PI * (3.0 * (x + y) - ((3.0 * x + y) * (x + 3.0 * y)).sqrt())
}

/// Bisection steps: the bracket shrinks by 2⁻⁴⁰ (below 1e-12 of it).
const STEPS: usize = 40;

/// The half-width `a'` (m) of the ellipse of half-height `c · b` with the
/// perimeter of the rest ellipse `(a, b)` (m): the lumen whose wall keeps
/// its length. `a` for `c ≥ 1` (no narrowing).
pub fn wall_length_half_width(a: f64, b: f64, c: f64) -> f64 {
    if c.is_nan() || c >= 1.0 || a <= 0.0 || b <= 0.0 {
        return a.max(0.0);
    }
    half_width_of_perimeter(ellipse_perimeter(a, b), a, c.max(0.0) * b)
}

/// The half-width (m), at least `a`, of the ellipse of half-height `y`
/// (m) and perimeter `p` (m). Bisection on `[a, p / (π (3 − √3))]`:
/// `P(x, y)` increases with `x` and at the upper end is at least `p` (the
/// flat ellipse's perimeter is `π (3 − √3) x`); `a` if `P(a, y) ≥ p`.
fn half_width_of_perimeter(p: f64, a: f64, y: f64) -> f64 {
    let hi = p / (std::f64::consts::PI * (3.0 - 3f64.sqrt()));
    if ellipse_perimeter(a, y) >= p || hi <= a {
        return a;
    }
    let (mut lo, mut hi) = (a, hi);
    for _ in 0..STEPS {
        let mid = 0.5 * (lo + hi);
        if ellipse_perimeter(mid, y) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// How one vessel's lumen is drawn in a frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LumenShape {
    /// Height ratio `c`: the lumen's height relative to rest.
    pub height_ratio: f64,
    /// Outward shift (m) of the lumen's medial (index 0, towards −u) and
    /// lateral (index 1) edges.
    pub shift: [f64; 2],
}

impl LumenShape {
    /// Half-width (m) of the drawn lumen of rest half-width `a` (m).
    pub fn half_width(&self, a: f64) -> f64 {
        a + 0.5 * (self.shift[0] + self.shift[1])
    }

    /// Lateral offset (m) of the drawn lumen's centre from the vessel's.
    pub fn centre_offset(&self) -> f64 {
        0.5 * (self.shift[1] - self.shift[0])
    }

    /// Whether the lumen is widened at all.
    pub fn is_widened(&self) -> bool {
        self.shift[0] > 0.0 || self.shift[1] > 0.0
    }
}

/// Splits the widening `total` (m) between the two edges: half each, at
/// most `caps[k]` each, the part one side cannot take going to the other
/// as far as its cap allows (a lumen hemmed in on both sides widens less
/// than the law).
fn split(total: f64, caps: [f64; 2]) -> [f64; 2] {
    let half = 0.5 * total.max(0.0);
    let mut d = [half.min(caps[0]), half.min(caps[1])];
    let rest = total.max(0.0) - d[0] - d[1];
    let extra = rest.min(caps[0] - d[0]).max(0.0);
    d[0] += extra;
    d[1] += (rest - extra).min(caps[1] - d[1]).max(0.0);
    d
}

/// The drawn shape of the lumen of `v` whose law gives the area ratio
/// `area_ratio`, with a fraction `blood` (0–1) of its lumen free to
/// collapse and the edges' shifts capped at `caps` (m, [`side_caps`]).
/// Solves `c (1 + (δ₀ + δ₁) / 2a) = A` for `c` by bisection on `[0, A]`
/// (the left side increases with `c`; `δ₀ + δ₁` is `blood · 2 (a'(c) − a)`
/// split by [`split`]), `a` the lumen's lateral half-width.
pub fn lumen_shape(v: &Vessel, area_ratio: f64, blood: f64, caps: [f64; 2]) -> LumenShape {
    let blood = blood.clamp(0.0, 1.0);
    // The rest wall's length, and the lumen's lateral and vertical
    // half-extents (the semi-axes themselves for an upright lumen, every
    // section's default; for a tilted one its bounding box).
    let p = ellipse_perimeter(v.radius, v.radius_b);
    let (a, b) = (v.half_width(), v.half_height());
    let shifts = |c: f64| {
        let widened = half_width_of_perimeter(p, a, c * b);
        split(blood * 2.0 * (widened - a), caps)
    };
    if area_ratio.is_nan() || area_ratio >= 1.0 || blood <= 0.0 || a <= 0.0 {
        return LumenShape {
            height_ratio: area_ratio.max(0.0),
            shift: [0.0, 0.0],
        };
    }
    let target = area_ratio.max(0.0);
    let drawn = |c: f64| {
        let d = shifts(c);
        c * (1.0 + 0.5 * (d[0] + d[1]) / a)
    };
    let (mut lo, mut hi) = (0.0, target);
    for _ in 0..STEPS {
        let mid = 0.5 * (lo + hi);
        if drawn(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c = 0.5 * (lo + hi);
    LumenShape {
        height_ratio: c,
        shift: shifts(c),
    }
}

/// The largest outward shift (m) of each lateral edge of vessel `i` of
/// `anatomy`: a third of its lateral decay length ([`decay_lengths`]), so
/// the tissue beside keeps at least two thirds of its width.
pub fn side_caps(anatomy: &Anatomy, i: usize) -> [f64; 2] {
    let l = decay_lengths(anatomy, i);
    [l[0] / 3.0, l[1] / 3.0]
}

/// The lengths (m) over which the lateral shift of vessel `i`'s edges
/// decays to 0 beside its wall, medially (0) and laterally (1): twice the
/// wall's outer half-width (as the vertical warp's `L = 2 b`), but no
/// further than the next vessel's wall on that side among those whose
/// depth span overlaps vessel `i`'s (that vessel stays where it is).
pub fn decay_lengths(anatomy: &Anatomy, i: usize) -> [f64; 2] {
    let vs = anatomy.vessels();
    let Some(me) = vs.get(i).map(|s| s.vessel) else {
        return [0.0, 0.0];
    };
    let half = me.chord_half_width(me.wall);
    let tall = me.half_height() + me.wall;
    let mut l = [2.0 * half, 2.0 * half];
    for (j, other) in vs.iter().enumerate() {
        let o = other.vessel;
        if j == i || (o.depth - me.depth).abs() >= tall + o.half_height() + o.wall {
            continue;
        }
        let o_half = o.chord_half_width(o.wall);
        if o.lateral > me.lateral {
            let gap = (o.lateral - o_half) - (me.lateral + half);
            l[1] = l[1].min(gap.max(0.0));
        } else {
            let gap = (me.lateral - half) - (o.lateral + o_half);
            l[0] = l[0].min(gap.max(0.0));
        }
    }
    l
}

/// The fraction of vessel `i`'s lumen that is blood free to collapse:
/// `1 − fill` for a vein with content, 1 for an artery.
pub fn blood_fraction(anatomy: &Anatomy, i: usize) -> f64 {
    anatomy
        .vessels()
        .get(i)
        .and_then(|s| s.condition())
        .map_or(1.0, |c| 1.0 - c.fill.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn perimeter_is_exact_for_a_circle_and_close_for_a_line() {
        assert!((ellipse_perimeter(0.005, 0.005) - 2.0 * PI * 0.005).abs() < 1e-15);
        // Flat: π (3 − √3) x = 3.983 x against 4 x (Ramanujan's worst case).
        let flat = ellipse_perimeter(0.01, 0.0) / 0.04;
        assert!((flat - PI * (3.0 - 3f64.sqrt()) / 4.0).abs() < 1e-15);
        assert!((flat - 1.0).abs() < 0.005);
    }

    #[test]
    fn a_round_tube_flattens_into_a_line_pi_r_over_two_wide() {
        let r = 0.005;
        // c = 1: no change; c = 0: 2π r / (π (3 − √3)) = 1.577 r, within
        // Ramanujan's 0.4 % of the exact π r / 2.
        assert_eq!(wall_length_half_width(r, r, 1.0), r);
        let line = wall_length_half_width(r, r, 0.0);
        assert!(
            (line - 2.0 * r / (3.0 - 3f64.sqrt())).abs() < 1e-14,
            "{line}"
        );
        assert!((line / (0.5 * PI * r) - 1.0).abs() < 0.005);
        // The perimeter is kept at every height, and the width rises as
        // the height falls.
        let mut last = r;
        for k in (0..20).rev() {
            let c = k as f64 / 20.0;
            let w = wall_length_half_width(r, r, c);
            // To the bisection: a bracket of < 1.6 r shrunk by 2⁻⁴⁰ (1.5e-12
            // r) times dP/dx ≤ π (3 − √3) ≈ 4: 6e-12 r of 2π r, < 1e-12.
            let p = ellipse_perimeter(w, c * r);
            assert!((p / (2.0 * PI * r) - 1.0).abs() < 1e-12);
            assert!(w > last);
            last = w;
        }
    }

    #[test]
    fn drawn_area_is_the_laws_and_blood_alone_widens() {
        let v = Vessel::oval(0.0, 0.03, 0.005, 1.3, 0.0005);
        let free = [1.0, 1.0];
        let mut last_width = v.half_width();
        for k in (0..20).rev() {
            let area = k as f64 / 20.0;
            let s = lumen_shape(&v, area, 1.0, free);
            let a = v.half_width();
            // The ellipse (a', c b) encloses the law's area, to the
            // bisection: c within 2⁻⁴⁰ (9e-13) of the root, times the
            // slope of c a'(c)/a, at most 1.5 (a' ≤ 1.4 a plus the
            // inner solve's 1e-12): 1.4e-12, so 3e-12.
            let drawn = s.height_ratio * s.half_width(a) / a;
            assert!((drawn - area).abs() < 3e-12, "{drawn} vs {area}");
            // Symmetric when free, and wider the flatter.
            assert!((s.shift[0] - s.shift[1]).abs() < 1e-15);
            assert!(s.half_width(a) >= last_width);
            last_width = s.half_width(a);
            // An occlusive thrombus neither widens nor flattens more.
            let plug = lumen_shape(&v, area, 0.0, free);
            assert_eq!(plug.shift, [0.0, 0.0]);
            assert_eq!(plug.height_ratio, area);
        }
        // Closed: the line of the law, P / (π (3 − √3)).
        let p = ellipse_perimeter(v.radius, v.radius_b);
        let line = p / (PI * (3.0 - 3f64.sqrt()));
        assert!((last_width - line).abs() < 1e-12);
        // Expanding lumens keep their width.
        assert_eq!(lumen_shape(&v, 1.2, 1.0, free).shift, [0.0, 0.0]);
    }

    #[test]
    fn a_hemmed_in_edge_leaves_the_widening_to_the_free_one() {
        let v = Vessel::oval(0.0, 0.03, 0.005, 1.3, 0.0005);
        let free = lumen_shape(&v, 0.3, 1.0, [1.0, 1.0]);
        let total = free.shift[0] + free.shift[1];
        let s = lumen_shape(&v, 0.3, 1.0, [1.0, 0.2e-3]);
        assert!((s.shift[1] - 0.2e-3).abs() < 1e-15);
        assert!((s.shift[0] + s.shift[1] - total).abs() < 1e-12);
        assert!(s.centre_offset() < 0.0);
        // Both hemmed in: less than the law, and still the law's area.
        let s = lumen_shape(&v, 0.3, 1.0, [0.1e-3, 0.2e-3]);
        assert_eq!(s.shift, [0.1e-3, 0.2e-3]);
        let a = v.half_width();
        assert!((s.height_ratio * s.half_width(a) / a - 0.3).abs() < 3e-12);
    }
}
