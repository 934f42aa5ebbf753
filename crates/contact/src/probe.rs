//! The rigid echographic probe: a box posed by an isometry (paper §3,
//! "Collision Detection": a rigid object of rectangular shape).
//!
//! Local frame (fixed by `docs/ARCHITECTURE.md`): the face is the plane
//! `y = 0`, the body extends to `+y` up to `height`; the face spans
//! `|x| ≤ half_width` (lateral, in the image plane) and `|z| ≤ half_elevation`.
//! The contact direction `k̂` of Eq. 2 is the face normal pointing into the
//! tissue, local `−y`. The reference point `p` sent to the haptic side is the
//! face centre, the local origin.

use crate::error::ConfigError;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Rigid probe geometry, the `[probe]` section of a scenario. Lengths in m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Probe {
    /// Half of the face's lateral width along local x, m, in [0.005, 0.05]:
    /// linear probes have apertures of ~10–100 mm. Default 0.020: a 40 mm
    /// linear vascular probe.
    pub half_width: f64,
    /// Half of the face's elevation thickness along local z, m, in [0.001,
    /// 0.02] (probe footprints are 2–40 mm thick). Default 0.005.
    pub half_elevation: f64,
    /// Height of the body above the face along local +y, m, in [0.01, 0.3]
    /// (a hand-held probe). Default 0.060.
    pub height: f64,
}

impl Default for Probe {
    fn default() -> Self {
        Self {
            half_width: 0.020,
            half_elevation: 0.005,
            height: 0.060,
        }
    }
}

/// A box given by its pose and half extents; points are tested in its frame,
/// where it is centred at the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedBox {
    /// Pose of the box centre in the thigh frame.
    pub pose: Isometry3<f64>,
    /// Half extents along the box's local axes, m.
    pub half_extents: Vector3<f64>,
}

impl OrientedBox {
    /// True if the world point `x` lies inside the box or on its boundary.
    pub fn contains(&self, x: &Vector3<f64>) -> bool {
        let l = self.pose.inverse_transform_point(&Point3::from(*x));
        l.x.abs() <= self.half_extents.x
            && l.y.abs() <= self.half_extents.y
            && l.z.abs() <= self.half_extents.z
    }

    /// Axis-aligned bounds `(min, max)` of the box in the thigh frame, m.
    pub fn aabb(&self) -> (Vector3<f64>, Vector3<f64>) {
        let r = self.pose.rotation.to_rotation_matrix();
        let m = r.matrix();
        // Extent along world axis i is Σ_j |R_ij| h_j.
        let ext = m.abs() * self.half_extents;
        let c = self.pose.translation.vector;
        (c - ext, c + ext)
    }
}

impl Probe {
    /// Checks every field; errors name the key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let width = "must be in [0.005, 0.05] m (linear probe apertures 10-100 mm)";
        ConfigError::in_range(p, "half_width", self.half_width, (0.005, 0.05), width)?;
        let elev = "must be in [0.001, 0.02] m (probe footprints 2-40 mm thick)";
        ConfigError::in_range(
            p,
            "half_elevation",
            self.half_elevation,
            (0.001, 0.02),
            elev,
        )?;
        let height = "must be in [0.01, 0.3] m (a hand-held probe)";
        ConfigError::in_range(p, "height", self.height, (0.01, 0.3), height)?;
        Ok(())
    }

    /// Face area, m².
    pub fn face_area(&self) -> f64 {
        4.0 * self.half_width * self.half_elevation
    }

    /// The reference point `p` (face centre) in the thigh frame, m.
    pub fn reference_point(pose: &Isometry3<f64>) -> Vector3<f64> {
        pose.translation.vector
    }

    /// The contact direction `k̂` of Eq. 2 in the thigh frame: the face
    /// normal pointing into the tissue (local `−y`), unit.
    pub fn contact_direction(pose: &Isometry3<f64>) -> Vector3<f64> {
        pose.rotation * -Vector3::y()
    }

    /// A world point in the probe's local frame, m.
    pub fn to_local(pose: &Isometry3<f64>, x: &Vector3<f64>) -> Vector3<f64> {
        pose.inverse_transform_point(&Point3::from(*x)).coords
    }

    /// True if the local point is inside the body: on or above the face, at
    /// most `height` above it, and within the face's rectangle.
    pub fn contains_local(&self, l: &Vector3<f64>) -> bool {
        l.y >= 0.0
            && l.y <= self.height
            && l.x.abs() <= self.half_width
            && l.z.abs() <= self.half_elevation
    }

    /// True if the local point lies over the face's rectangle (any height).
    pub fn in_footprint_local(&self, l: &Vector3<f64>) -> bool {
        l.x.abs() <= self.half_width && l.z.abs() <= self.half_elevation
    }

    /// Penetration depth of a world point along `k̂`, m: its height above
    /// the face plane (local `y`) if it is inside the body, `None` otherwise.
    pub fn depth(&self, pose: &Isometry3<f64>, x: &Vector3<f64>) -> Option<f64> {
        let l = Self::to_local(pose, x);
        self.contains_local(&l).then_some(l.y)
    }

    /// The body as an oriented box, inflated by `margin` (m) on every side.
    pub fn body_box(&self, pose: &Isometry3<f64>, margin: f64) -> OrientedBox {
        let centre = pose * Translation3::new(0.0, 0.5 * self.height, 0.0);
        OrientedBox {
            pose: centre,
            half_extents: Vector3::new(
                self.half_width + margin,
                0.5 * self.height + margin,
                self.half_elevation + margin,
            ),
        }
    }

    /// The default exam pose with the face centre at `p`: face normal along
    /// thigh `−y` (pointing down into the thigh), width along thigh `x`
    /// (transverse section), elevation along the thigh axis `z`. With these
    /// choices the local axes coincide with the thigh's: the identity
    /// rotation.
    pub fn exam_pose(p: Vector3<f64>) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::from(p), UnitQuaternion::identity())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_direction_points_down_in_exam_pose() {
        let pose = Probe::exam_pose(Vector3::new(0.0, 0.1, 0.0));
        assert!((Probe::contact_direction(&pose) + Vector3::y()).norm() < 1e-15);
    }

    #[test]
    fn depth_is_height_above_face_inside_body() {
        let probe = Probe::default();
        let rot = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.7);
        let pose = Isometry3::from_parts(Translation3::new(0.01, 0.02, 0.03), rot);
        let up = -Probe::contact_direction(&pose);
        let p = Probe::reference_point(&pose);
        let x = p + 0.003 * up + rot * Vector3::new(0.019, 0.0, -0.004);
        assert!((probe.depth(&pose, &x).unwrap() - 0.003).abs() < 1e-14);
        // Outside the face rectangle laterally, below the face, above the body.
        assert!(probe
            .depth(&pose, &(p + rot * Vector3::new(0.021, 0.001, 0.0)))
            .is_none());
        assert!(probe.depth(&pose, &(p - 0.001 * up)).is_none());
        assert!(probe.depth(&pose, &(p + 0.061 * up)).is_none());
    }

    #[test]
    fn body_box_matches_contains_local_and_aabb_bounds_it() {
        let probe = Probe::default();
        let rot = UnitQuaternion::from_euler_angles(-0.5, 0.4, 0.1);
        let pose = Isometry3::from_parts(Translation3::new(0.0, 0.05, 0.1), rot);
        let obb = probe.body_box(&pose, 0.0);
        let (lo, hi) = obb.aabb();
        for i in 0..9 {
            for j in 0..9 {
                for k in 0..9 {
                    let l = Vector3::new(
                        -0.025 + 0.00625 * i as f64,
                        -0.0105 + 0.01 * j as f64,
                        -0.008 + 0.002 * k as f64,
                    );
                    let x = (pose * Point3::from(l)).coords;
                    assert_eq!(obb.contains(&x), probe.contains_local(&l), "{l:?}");
                    if obb.contains(&x) {
                        assert!((0..3).all(|a| x[a] >= lo[a] - 1e-12 && x[a] <= hi[a] + 1e-12));
                    }
                }
            }
        }
    }

    #[test]
    fn validate_names_the_key() {
        let p = Probe {
            half_width: f64::NAN,
            ..Probe::default()
        };
        let e = p.validate("probe").unwrap_err();
        assert_eq!(e.key, "probe.half_width");
    }
}
