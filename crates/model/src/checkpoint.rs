//! The state checkpoint: a diverged model is detected and reported as a
//! typed error, not propagated (rapier's habit). A state diverges when an
//! unstable setting (e.g. λ < ½ before it was refused, issue 20) or a force
//! beyond what the integrator can carry makes a node's position or velocity
//! non-finite or fly away; the callers check after each step and stop.

use crate::thigh::ThighModel;

/// Largest plausible node coordinate (m): the thigh frame spans less than a
/// metre; 1 km is far past any state the tissue can reach, and the same bound
/// above which the contact's broad phase skips a point.
pub const MAX_POSITION: f64 = 1.0e3;

/// Largest plausible node speed (m/s): the fastest exam motions are below
/// 1 m/s and tissue waves (shear, ~1–10 m/s) are far slower than this bound
/// of 1e4 m/s (roughly the speed of sound in bone, 4 km/s, with margin).
pub const MAX_SPEED: f64 = 1.0e4;

/// The model's state left the plausible (finite, bounded) region.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the thigh model diverged at t = {time} s: node {node} is at {position:?} m moving at \
     {velocity:?} m/s (bounds: |x| <= {MAX_POSITION} m, |v| <= {MAX_SPEED} m/s)"
)]
pub struct DivergedError {
    /// Simulated time of the check (s).
    pub time: f64,
    /// Index of the first node out of bounds.
    pub node: usize,
    /// Its position (m).
    pub position: [f64; 3],
    /// Its velocity (m/s).
    pub velocity: [f64; 3],
}

impl ThighModel {
    /// Checks that every node's position and velocity are finite and within
    /// [`MAX_POSITION`] and [`MAX_SPEED`]; the error names the first node
    /// that is not. `O(n)`, allocates nothing.
    pub fn check_state(&self) -> Result<(), DivergedError> {
        let (x, v) = (self.positions(), self.velocities());
        let bad = x.iter().zip(v).position(|(p, u)| {
            !(p.iter().all(|c| c.abs() <= MAX_POSITION) && u.iter().all(|c| c.abs() <= MAX_SPEED))
        });
        match bad {
            None => Ok(()),
            Some(node) => Err(DivergedError {
                time: self.time(),
                node,
                position: x[node].into(),
                velocity: v[node].into(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ModelConfig, Vec3};

    /// A state with one NaN velocity, or one node 2 km away, is reported
    /// naming that node; the rest state passes.
    #[test]
    fn non_finite_or_far_nodes_are_reported_by_index() {
        let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
        assert_eq!(model.check_state(), Ok(()));
        let mut x: Vec<Vec3> = model.positions().to_vec();
        let mut v: Vec<Vec3> = model.velocities().to_vec();
        v[517].y = f64::NAN;
        model.set_state(&x, &v);
        let e = model.check_state().unwrap_err();
        assert_eq!(e.node, 517);
        assert!(e.to_string().contains("node 517"), "{e}");
        v[517].y = 0.0;
        x[500].x = 2.0e3;
        model.set_state(&x, &v);
        assert_eq!(model.check_state().unwrap_err().node, 500);
    }
}
