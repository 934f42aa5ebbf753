//! `[thigh]`: the thigh segment's geometry and the surface mesh resolution.

use super::{in_range, key, positive, ConfigError};
use serde::{Deserialize, Serialize};

/// Largest accepted mesh (nodes), so a typo cannot ask for terabytes.
pub const MAX_NODES: usize = 2_000_000;

/// Geometry of the thigh segment (a generalized cylinder around the femur)
/// and the resolution of its surface mesh.
///
/// Frame: `z` along the thigh's axis (the segment spans `z ∈ [−length/2,
/// length/2]`), `x` lateral, `y` anterior. The skin's cross-section is the
/// ellipse `x = semi_axis_x cos θ, y = semi_axis_y sin θ`, centred on the
/// z axis; `θ = π/2` is the anterior (top) line.
///
/// Inner layer: each surface node's anchor lies on its inward rest normal at
/// the distance `tissue_thickness` (the normal spring's rest length, uniform
/// so that one calibration holds everywhere). Every anchor must stay outside
/// the femur (a cylinder of `femur_radius` around `femur_offset`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ThighGeometry {
    /// Length of the segment along z (m). Default 0.30.
    pub length: f64,
    /// Lateral (x) semi-axis of the elliptic cross-section (m). Default 0.080.
    pub semi_axis_x: f64,
    /// Anterior (y) semi-axis of the elliptic cross-section (m). Default 0.072
    /// (with 0.080: circumference ≈ 0.48 m).
    pub semi_axis_y: f64,
    /// Femur radius (m). Default 0.013.
    pub femur_radius: f64,
    /// Position `[x, y]` of the femur's axis in the cross-section (m).
    /// Default `[0.0, -0.010]` (slightly posterior).
    pub femur_offset: [f64; 2],
    /// Rest length of the normal springs: distance from a surface node to its
    /// anchor along the inward normal (m). Default 0.040.
    pub tissue_thickness: f64,
    /// Number of nodes around the circumference (periodic in θ). Default 48.
    pub n_theta: usize,
    /// Number of node rings along z, ends included. Default 21.
    pub n_z: usize,
    /// Hold the two end rings fixed (Dirichlet). Default true.
    pub hold_ends: bool,
}

impl Default for ThighGeometry {
    fn default() -> Self {
        ThighGeometry {
            length: 0.30,
            semi_axis_x: 0.080,
            semi_axis_y: 0.072,
            femur_radius: 0.013,
            femur_offset: [0.0, -0.010],
            tissue_thickness: 0.040,
            n_theta: 48,
            n_z: 21,
            hold_ends: true,
        }
    }
}

impl ThighGeometry {
    /// Number of surface nodes, `n_theta · n_z`.
    pub fn node_count(&self) -> usize {
        self.n_theta.saturating_mul(self.n_z)
    }

    /// Angle θ (rad) of ring column `i_theta`: `2π i_theta / n_theta`.
    pub fn theta(&self, i_theta: usize) -> f64 {
        std::f64::consts::TAU * i_theta as f64 / self.n_theta as f64
    }

    /// Axial coordinate z (m) of ring `i_z`: `−length/2 + length · i_z / (n_z − 1)`.
    pub fn z(&self, i_z: usize) -> f64 {
        -0.5 * self.length + self.length * i_z as f64 / (self.n_z - 1) as f64
    }

    /// Rest point on the skin at angle θ (rad) and height z (m).
    pub fn surface_point(&self, theta: f64, z: f64) -> [f64; 3] {
        [
            self.semi_axis_x * theta.cos(),
            self.semi_axis_y * theta.sin(),
            z,
        ]
    }

    /// Outward unit normal of the skin at angle θ (independent of z).
    pub fn surface_normal(&self, theta: f64) -> [f64; 3] {
        let nx = self.semi_axis_y * theta.cos();
        let ny = self.semi_axis_x * theta.sin();
        let n = nx.hypot(ny);
        [nx / n, ny / n, 0.0]
    }

    /// Anchor (inner-layer point) of the surface point at angle θ: the skin
    /// point moved `tissue_thickness` along the inward normal (x, y only).
    pub fn anchor_xy(&self, theta: f64) -> [f64; 2] {
        let p = self.surface_point(theta, 0.0);
        let n = self.surface_normal(theta);
        [
            p[0] - self.tissue_thickness * n[0],
            p[1] - self.tissue_thickness * n[1],
        ]
    }

    /// Validates every field; errors name `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        positive(prefix, "length", self.length)?;
        positive(prefix, "semi_axis_x", self.semi_axis_x)?;
        positive(prefix, "semi_axis_y", self.semi_axis_y)?;
        positive(prefix, "femur_radius", self.femur_radius)?;
        positive(prefix, "tissue_thickness", self.tissue_thickness)?;
        let r_max = self.semi_axis_x.max(self.semi_axis_y);
        for (i, c) in self.femur_offset.iter().enumerate() {
            in_range(prefix, &format!("femur_offset[{i}]"), *c, -r_max, r_max)?;
        }
        if self.n_theta < 6 {
            return Err(ConfigError::invalid(
                key(prefix, "n_theta"),
                format!("must be >= 6, got {}", self.n_theta),
            ));
        }
        if self.n_z < 3 {
            return Err(ConfigError::invalid(
                key(prefix, "n_z"),
                format!("must be >= 3, got {}", self.n_z),
            ));
        }
        if self.node_count() > MAX_NODES {
            return Err(ConfigError::invalid(
                key(prefix, "n_theta"),
                format!(
                    "n_theta * n_z = {} exceeds the limit of {MAX_NODES} nodes",
                    self.node_count()
                ),
            ));
        }
        self.check_femur(prefix)
    }

    /// The femur must lie inside the skin, and every anchor outside the femur.
    fn check_femur(&self, prefix: &str) -> Result<(), ConfigError> {
        let [fx, fy] = self.femur_offset;
        let inside = (fx / self.semi_axis_x).powi(2) + (fy / self.semi_axis_y).powi(2);
        let clearance = self.femur_radius / self.semi_axis_x.min(self.semi_axis_y);
        if inside.sqrt() + clearance >= 1.0 {
            return Err(ConfigError::invalid(
                key(prefix, "femur_radius"),
                format!(
                    "the femur (radius {} m at [{fx}, {fy}]) does not fit inside the skin",
                    self.femur_radius
                ),
            ));
        }
        for i in 0..self.n_theta {
            let theta = self.theta(i);
            let [ax, ay] = self.anchor_xy(theta);
            let dist = (ax - fx).hypot(ay - fy);
            if dist <= self.femur_radius {
                return Err(ConfigError::invalid(
                    key(prefix, "tissue_thickness"),
                    format!(
                        "= {} m puts the anchor at θ = {theta:.3} rad inside the femur \
                         ({dist:.4} m from its axis < femur_radius {} m)",
                        self.tissue_thickness, self.femur_radius
                    ),
                ));
            }
        }
        Ok(())
    }
}
