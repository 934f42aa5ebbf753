//! The simulated hand's way to a far placement: over the skin, not through
//! the leg.
//!
//! The page places the probe anywhere on the leg with one command (a click,
//! a checklist's site, the exam test's jump from the groin to the back of
//! the knee). The hand slews to its target in a straight line
//! (`HAND_REACH_SPEED`), and a straight line to the other side of the leg
//! runs through the thigh: the probe is driven centimetres into the tissue
//! and the contact answers with tens of newtons (20–30 N seen in the
//! browser's exam, the one-sample spikes of issue 12) that no hand would
//! apply. A sonographer lifts, moves over the skin and presses again. So a
//! far move becomes a route: lifted above where the probe is, along the
//! lifted surface in steps small enough that each chord stays clear of the
//! skin, lifted above the new place, then down to it. The route is a
//! fixed-size value ([`HandRoute`]), handed to the haptic loop through the
//! same lock-free triple buffer as a single target, and followed there
//! without allocation ([`RouteFollower`]).

use super::shared::HandTarget;
use nalgebra::Vector3;

/// Most waypoints of a route: a lift, up to 20 steps over the surface, the
/// last one lifted, and the target.
pub(super) const MAX_WAYPOINTS: usize = 24;

/// Largest angle step (rad) between waypoints over the lifted surface: the
/// chord of a 0.15 rad arc of radius `r` dips `r (1 − cos 0.075)` ≈ 0.0028 r
/// below it, 0.3 mm on a 110 mm thigh, far inside the lift's 20 mm.
pub(super) const MAX_ANGLE_STEP: f64 = 0.15;
/// Largest step along the leg (m) between waypoints.
pub(super) const MAX_LENGTH_STEP: f64 = 0.03;
/// A move is far, and routed, when its angle changes by more than this
/// (rad, ≈ 11°: a drag on the page sends steps of a few hundredths)...
pub(super) const FAR_ANGLE: f64 = 0.2;
/// ... or its place along the leg by more than this (m).
pub(super) const FAR_LENGTH: f64 = 0.03;
/// A waypoint is reached when the hand's setpoint is this close (m).
pub(super) const REACHED: f64 = 2e-4;

/// A sequence of hand targets, the last the destination (1 to
/// [`MAX_WAYPOINTS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HandRoute {
    points: [HandTarget; MAX_WAYPOINTS],
    len: usize,
}

impl HandRoute {
    /// Straight to `t`.
    pub fn to(t: HandTarget) -> HandRoute {
        HandRoute {
            points: [t; MAX_WAYPOINTS],
            len: 1,
        }
    }

    /// Through `points` in order (at least one; the first
    /// [`MAX_WAYPOINTS`] − 1 and the last are kept).
    pub fn through(points: &[HandTarget]) -> Option<HandRoute> {
        let last = *points.last()?;
        let mut r = HandRoute::to(last);
        let head = &points[..points.len() - 1];
        let n = head.len().min(MAX_WAYPOINTS - 1);
        r.points[..n].copy_from_slice(&head[..n]);
        r.points[n] = last;
        r.len = n + 1;
        Some(r)
    }

    /// The destination.
    pub fn destination(&self) -> HandTarget {
        self.points[self.len - 1]
    }

    /// The waypoints, in order.
    pub fn points(&self) -> &[HandTarget] {
        &self.points[..self.len]
    }
}

/// Where the haptic loop's hand is heading along the latest route.
#[derive(Debug, Clone, Copy)]
pub(super) struct RouteFollower {
    route: HandRoute,
    next: usize,
}

impl RouteFollower {
    /// Following `route` from its first waypoint.
    pub fn new(route: HandRoute) -> RouteFollower {
        RouteFollower { route, next: 0 }
    }

    /// The waypoint to slew to with the hand's setpoint at `at` (m): a new
    /// route starts from its first; a reached waypoint gives way to the
    /// next. No allocation (the haptic tick calls it).
    pub fn target(&mut self, route: &HandRoute, at: [f64; 3]) -> HandTarget {
        if *route != self.route {
            *self = RouteFollower::new(*route);
        }
        let points = self.route.points();
        while self.next + 1 < points.len() {
            let p = points[self.next].position;
            let d = Vector3::from(p) - Vector3::from(at);
            if d.norm() > REACHED {
                break;
            }
            self.next += 1;
        }
        points[self.next]
    }
}

/// A placement on the page's surface: angle (rad), place along the leg
/// (m), depth along the inward normal (m; negative above the skin), tilt
/// (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Placement {
    pub theta: f64,
    pub z: f64,
    pub depth: f64,
    pub tilt: f64,
}

/// The route from `from` to `to` with `target_of` the hand target of a
/// placement: straight when the move is short; else lifted to `lift` (m,
/// negative: above the skin), over the surface in steps of at most
/// [`MAX_ANGLE_STEP`] and [`MAX_LENGTH_STEP`], and down to `to`.
pub(super) fn route(
    from: Placement,
    to: Placement,
    lift: f64,
    mut target_of: impl FnMut(Placement) -> Result<HandTarget, String>,
) -> Result<HandRoute, String> {
    let dt = to.theta - from.theta;
    let dz = to.z - from.z;
    let last = target_of(to)?;
    if dt.abs() <= FAR_ANGLE && dz.abs() <= FAR_LENGTH {
        return Ok(HandRoute::to(last));
    }
    let steps = ((dt.abs() / MAX_ANGLE_STEP).ceil())
        .max((dz.abs() / MAX_LENGTH_STEP).ceil())
        .clamp(1.0, (MAX_WAYPOINTS - 2) as f64) as usize;
    let mut points = [last; MAX_WAYPOINTS];
    let mut n = 0;
    for k in 0..=steps {
        let u = k as f64 / steps as f64;
        points[n] = target_of(Placement {
            theta: from.theta + u * dt,
            z: from.z + u * dz,
            depth: lift.min(from.depth),
            tilt: if k == steps { to.tilt } else { from.tilt },
        })?;
        n += 1;
    }
    points[n] = last;
    n += 1;
    HandRoute::through(&points[..n]).ok_or_else(|| "an empty route".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circular leg of radius 0.08 m about the z axis, the page's angle
    /// from +y towards +x, depth along the inward normal.
    fn circle(p: Placement) -> Result<HandTarget, String> {
        let r = 0.08 - p.depth;
        Ok(HandTarget {
            position: [r * p.theta.sin(), r * p.theta.cos(), p.z],
            orientation: [1.0, 0.0, 0.0, 0.0],
        })
    }

    fn at(theta: f64, z: f64, depth: f64) -> Placement {
        Placement {
            theta,
            z,
            depth,
            tilt: 0.0,
        }
    }

    /// Distance (m) of the segment a–b's closest point to the z axis.
    fn closest_to_axis(a: [f64; 3], b: [f64; 3]) -> f64 {
        let (a, b) = (Vector3::new(a[0], a[1], 0.0), Vector3::new(b[0], b[1], 0.0));
        let d = b - a;
        let t = if d.norm_squared() > 0.0 {
            (-a.dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a + d * t).norm()
    }

    /// A short move is straight; a move to the other side of the leg is
    /// routed so that no segment but the last descent comes nearer the
    /// axis than the skin (0.08 m), and it ends at the target.
    #[test]
    fn far_moves_go_over_the_skin() {
        let short = route(at(0.1, 0.0, 0.01), at(0.2, 0.01, 0.012), -0.02, circle).unwrap();
        assert_eq!(short.points().len(), 1);
        let to = at(std::f64::consts::PI, 0.2, 0.012);
        let far = route(at(0.0, 0.0, 0.012), to, -0.02, circle).unwrap();
        let p = far.points();
        assert!(p.len() > 3 && p.len() <= MAX_WAYPOINTS, "{}", p.len());
        assert_eq!(far.destination(), circle(to).unwrap());
        for w in p[..p.len() - 1].windows(2) {
            let d = closest_to_axis(w[0].position, w[1].position);
            assert!(d > 0.08, "a chord dips to {d} m from the axis");
        }
        // The straight line it replaces runs through the leg's axis region.
        let direct = closest_to_axis(
            circle(at(0.0, 0.0, 0.012)).unwrap().position,
            circle(to).unwrap().position,
        );
        assert!(direct < 0.01, "{direct}");
    }

    /// The follower walks the waypoints in order as each is reached, stays
    /// on the last, and starts over when the route changes.
    #[test]
    fn the_follower_advances_as_waypoints_are_reached() {
        let r = route(at(0.0, 0.0, 0.0), at(1.0, 0.0, 0.0), -0.02, circle).unwrap();
        let mut f = RouteFollower::new(HandRoute::to(r.points()[0]));
        let mut here = [1.0, 1.0, 1.0];
        let mut seen = Vec::new();
        for _ in 0..100 {
            let t = f.target(&r, here);
            if seen.last() != Some(&t) {
                seen.push(t);
            }
            here = t.position; // the hand arrives
        }
        assert_eq!(seen, r.points());
        let other = HandRoute::to(circle(at(0.5, 0.0, 0.0)).unwrap());
        assert_eq!(f.target(&other, here), other.destination());
    }
}
