//! `[thigh]`: the thigh segment's geometry and the surface mesh resolution.

use super::{count_range, in_range, range, ConfigError};
use serde::{Deserialize, Serialize};

/// Largest accepted mesh (nodes). The physics must step a mesh at its rate
/// (100 Hz in the paper) on one core: the default 1 008 nodes take a few ms
/// per step, so 20 000 nodes (20× the default, ~0.5 mm spacing on a whole
/// thigh segment) is far past real time already, and every per-node buffer
/// (matrix blocks, PCG vectors) stays in the tens of MB.
pub const MAX_NODES: usize = 20_000;

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
    /// Length of the segment along z (m), in [0.1, 1.0]: a human thigh
    /// segment (an adult femur is 0.4–0.5 m long). Default 0.30.
    pub length: f64,
    /// Lateral (x) semi-axis of the elliptic cross-section (m), in [0.03,
    /// 0.25]: adult mid-thigh circumferences run ~0.35–1.0 m (anthropometric
    /// surveys), i.e. radii 0.055–0.16 m; the range adds margin for
    /// children and the obese. Default 0.080.
    pub semi_axis_x: f64,
    /// Anterior (y) semi-axis of the elliptic cross-section (m), in [0.03,
    /// 0.25] (as `semi_axis_x`). Default 0.072 (with 0.080: circumference
    /// ≈ 0.48 m).
    pub semi_axis_y: f64,
    /// Femur radius (m), in [0.005, 0.03]: mid-shaft femoral diameters are
    /// 20–35 mm in adults (Duck 1990, ch. 5), 10 mm in small children.
    /// Default 0.013.
    pub femur_radius: f64,
    /// Position `[x, y]` of the femur's axis in the cross-section (m).
    /// Each component within ± the larger semi-axis (the femur lies inside
    /// the thigh). Exactly two elements. Default `[0.0, -0.010]` (slightly
    /// posterior).
    #[serde(deserialize_with = "super::exact_array")]
    pub femur_offset: [f64; 2],
    /// Rest length of the normal springs: distance from a surface node to its
    /// anchor along the inward normal (m), in [0.005, 0.2]: soft tissue over
    /// the femur is ~15–100 mm thick (skin + fat + muscle, imaging
    /// anatomy); the femur check below bounds it further. Default 0.040.
    pub tissue_thickness: f64,
    /// Number of nodes around the circumference (periodic in θ), in [6, 1000]
    /// (6: the coarsest ring that still has a top and sides; the node count
    /// `n_theta · n_z` is bounded by [`MAX_NODES`]). Default 48.
    pub n_theta: usize,
    /// Number of node rings along z, ends included, in [3, 1000] (3: one free
    /// ring between the held ends; the node count is bounded by
    /// [`MAX_NODES`]). Default 21.
    pub n_z: usize,
    /// Hold the two end rings fixed (Dirichlet). Default true.
    pub hold_ends: bool,
    /// The anatomical leg the mesh follows (issue 12): a patient preset of
    /// `echothigh_anatomy` (`lean-male`, `average-female`, `obese`), or `""`
    /// for the elliptic cylinder above. With a patient the skin is the
    /// patient's tapered leg (`semi_axis_*` and `femur_*` are unused), each
    /// normal spring's anchor is the nearest point of the oblique femur (its
    /// rest length varies along and around the leg), `tissue_thickness` is
    /// the reference layer thickness the `[tissue]` normal law holds for
    /// (scaled per node by rest length, see `TissueParams`), and the band
    /// over the adductor canal is `canal_stiffness` times stiffer (see
    /// `crate::leg`). Default `""`.
    pub patient: String,
    /// With a `patient`: the position along the leg of the segment's centre
    /// `z = 0`, `s` (m below the inguinal ligament; `s = centre_s − z`). The
    /// segment `[centre_s − length/2, centre_s + length/2]` must lie on the
    /// femur, `s ∈ [0, knee_s]`. Default 0.20 (mid-thigh of the default
    /// `lean-male`, knee_s/2).
    pub centre_s: f64,
    /// With a `patient`: factor on the normal springs' stiffness over the
    /// adductor canal, in [1, 4]. Default 1.5 (estimate: "the adductor
    /// canal is hard to compress", reference cus-exam-fidelity row 22,
    /// clinical practice; no measured ratio was retrieved, and 2× is the
    /// active-muscle factor of row 19, an upper bound for a passive leg).
    pub canal_stiffness: f64,
    /// With a `patient`: the patient's full description when a case sets it
    /// (a preset with overrides: variants, tense muscle, ...; issue 13),
    /// which then replaces the preset named by `patient`. Not a key of the
    /// scenario file: set in code (the runtime's `Scenario::with_case`).
    /// Default `None`.
    #[serde(skip)]
    pub patient_spec: Option<echothigh_anatomy::Patient>,
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
            patient: String::new(),
            centre_s: 0.20,
            canal_stiffness: 1.5,
            patient_spec: None,
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

    /// Validates every field against its documented range; errors name
    /// `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        range(
            prefix,
            "length",
            self.length,
            (0.1, 1.0),
            "m",
            "a human thigh segment",
        )?;
        let radius = "a human thigh's half-width; circumferences 0.2–1.5 m";
        range(
            prefix,
            "semi_axis_x",
            self.semi_axis_x,
            (0.03, 0.25),
            "m",
            radius,
        )?;
        range(
            prefix,
            "semi_axis_y",
            self.semi_axis_y,
            (0.03, 0.25),
            "m",
            radius,
        )?;
        let femur = "mid-shaft femoral radius of a child to a large adult";
        range(
            prefix,
            "femur_radius",
            self.femur_radius,
            (0.005, 0.03),
            "m",
            femur,
        )?;
        let thick = "soft tissue between skin and femur";
        range(
            prefix,
            "tissue_thickness",
            self.tissue_thickness,
            (0.005, 0.2),
            "m",
            thick,
        )?;
        let r_max = self.semi_axis_x.max(self.semi_axis_y);
        for (i, c) in self.femur_offset.iter().enumerate() {
            in_range(prefix, &format!("femur_offset[{i}]"), *c, -r_max, r_max)?;
        }
        let ring = "mesh resolution; the node count is bounded too";
        count_range(prefix, "n_theta", self.n_theta as u64, (6, 1000), ring)?;
        count_range(prefix, "n_z", self.n_z as u64, (3, 1000), ring)?;
        if self.node_count() > MAX_NODES {
            return Err(ConfigError::invalid(
                super::key(prefix, "n_theta"),
                format!(
                    "n_theta * n_z = {} exceeds the limit of {MAX_NODES} nodes (a mesh the \
                     physics cannot step in real time)",
                    self.node_count()
                ),
            ));
        }
        range(
            prefix,
            "centre_s",
            self.centre_s,
            (0.0, 1.0),
            "m",
            "a position along a leg",
        )?;
        range(
            prefix,
            "canal_stiffness",
            self.canal_stiffness,
            (1.0, 4.0),
            "",
            "the adductor canal is stiffer than the rest, at most ~2× twice over",
        )?;
        if self.patient.is_empty() {
            self.check_femur(prefix)
        } else {
            crate::leg::LegSurface::new(self, prefix).map(|_| ())
        }
    }

    /// The femur must lie inside the skin, and every anchor outside the femur.
    fn check_femur(&self, prefix: &str) -> Result<(), ConfigError> {
        let [fx, fy] = self.femur_offset;
        let inside = (fx / self.semi_axis_x).powi(2) + (fy / self.semi_axis_y).powi(2);
        let clearance = self.femur_radius / self.semi_axis_x.min(self.semi_axis_y);
        if inside.sqrt() + clearance >= 1.0 {
            return Err(ConfigError::invalid(
                super::key(prefix, "femur_radius"),
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
                    super::key(prefix, "tissue_thickness"),
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
