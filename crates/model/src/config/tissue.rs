//! `[tissue]`: lumped masses, linear membrane springs and dampers, nonlinear
//! normal springs (paper §3).

use super::{non_negative, positive, ConfigError};
use serde::{Deserialize, Serialize};

/// Tissue parameters, all resolution independent.
///
/// **Calibrated defaults.** `normal_a`, `normal_b` and `structural_stiffness`
/// are the Levenberg–Marquardt fit (`echothigh calibrate`, crate
/// `echothigh-contact`) of `data/indentation-default.csv` with
/// `tangential_stiffness` held at 1e6.
///
/// **Masses.** Node mass = `areal_density` × node area (kg).
///
/// **Linear springs** `f = a x` (paper §3) along the mesh edges, with a
/// damper along each. The parameters are membrane moduli (N/m): a spring of
/// rest length `L₀` whose endpoints represent the areas `A_i, A_j` gets
/// `a = stiffness · ½(A_i + A_j) / L₀²` (and the damping likewise), so the
/// membrane's response does not change when the mesh is refined.
///
/// **Normal springs** `f(x) = x / (a x + b)` (paper §3), `x` the change of
/// length (negative in compression), tension positive. The parameters are
/// per unit area: the pressure law `p(x) = x / (normal_a · x + normal_b)`
/// (Pa) times the node area `A` gives the node's spring, i.e. `a = normal_a /
/// A`, `b = normal_b / A`. The initial stiffness per unit area is
/// `1/normal_b` (N/m³) and the compression asymptote `normal_b / normal_a`
/// (m) does not depend on the area; it must be shorter than
/// `thigh.tissue_thickness`.
///
/// **Tangential support** (beyond the paper): the normal springs alone have
/// no shear stiffness, and compressed they are laterally unstable (their
/// geometric stiffness `f/l` is negative), so under a probe the skin could
/// twist around the femur, resisted only by the membrane's shear. The layer
/// of tissue between skin and bone resists that shear: each node is tied to
/// its rest position in the rest tangent plane by a linear spring
/// `−k_t A (I − n₀ n₀ᵀ)(x − x_rest)` with a damper alike (per unit area,
/// small tangential displacements).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TissueParams {
    /// Mass per unit skin area carried by the surface nodes (kg/m²). Default 10.
    pub areal_density: f64,
    /// Membrane modulus of the structural springs (θ and z neighbours) (N/m). Default 100.8 (calibrated, see below).
    pub structural_stiffness: f64,
    /// Membrane modulus of the shear springs (quad diagonals) (N/m). Default 50.
    pub shear_stiffness: f64,
    /// Membrane modulus of the bending springs (second neighbours in θ and z) (N/m). Default 20.
    pub bending_stiffness: f64,
    /// Damping modulus of the structural springs' dampers (N·s/m). Default 0.2.
    pub structural_damping: f64,
    /// Damping modulus of the shear springs' dampers (N·s/m). Default 0.05.
    pub shear_damping: f64,
    /// Damping modulus of the bending springs' dampers (N·s/m). Default 0.02.
    pub bending_damping: f64,
    /// Normal spring `a` per unit area (m²/N = 1/Pa). Default 7.638e-5.
    pub normal_a: f64,
    /// Normal spring `b` per unit area (m³/N = m/Pa): `1/normal_b` is the
    /// initial stiffness per unit area. Default 2.865e-6 (asymptote 37.5 mm).
    pub normal_b: f64,
    /// Normal damper per unit area (N·s/m³): node damping = this × node area. Default 2000.
    pub normal_damping: f64,
    /// Tangential (shear) stiffness of the tissue layer per unit area (N/m³):
    /// node value = this × node area. Default 1.0e6 (raised from 1e5 by the
    /// calibration: with less, the skin under a pressed probe slides sideways
    /// past ~15 mm on the default mesh).
    pub tangential_stiffness: f64,
    /// Tangential damping per unit area (N·s/m³). Default 500.
    pub tangential_damping: f64,
    /// Gravity acceleration (m/s²). Default `[0, 0, 0]`: the rest shape is the
    /// thigh as observed, i.e. already in equilibrium under gravity.
    pub gravity: [f64; 3],
}

impl Default for TissueParams {
    fn default() -> Self {
        TissueParams {
            areal_density: 10.0,
            structural_stiffness: 100.8,
            shear_stiffness: 50.0,
            bending_stiffness: 20.0,
            structural_damping: 0.2,
            shear_damping: 0.05,
            bending_damping: 0.02,
            normal_a: 7.638e-5,
            normal_b: 2.865e-6,
            normal_damping: 2000.0,
            tangential_stiffness: 1.0e6,
            tangential_damping: 500.0,
            gravity: [0.0, 0.0, 0.0],
        }
    }
}

impl TissueParams {
    /// The normal springs' compression asymptote `normal_b / normal_a` (m).
    pub fn asymptote(&self) -> f64 {
        self.normal_b / self.normal_a
    }

    /// Validates every field; errors name `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        positive(prefix, "areal_density", self.areal_density)?;
        positive(prefix, "structural_stiffness", self.structural_stiffness)?;
        non_negative(prefix, "shear_stiffness", self.shear_stiffness)?;
        non_negative(prefix, "bending_stiffness", self.bending_stiffness)?;
        non_negative(prefix, "structural_damping", self.structural_damping)?;
        non_negative(prefix, "shear_damping", self.shear_damping)?;
        non_negative(prefix, "bending_damping", self.bending_damping)?;
        positive(prefix, "normal_a", self.normal_a)?;
        positive(prefix, "normal_b", self.normal_b)?;
        non_negative(prefix, "normal_damping", self.normal_damping)?;
        non_negative(prefix, "tangential_stiffness", self.tangential_stiffness)?;
        non_negative(prefix, "tangential_damping", self.tangential_damping)?;
        for (i, g) in self.gravity.iter().enumerate() {
            if !g.is_finite() {
                return Err(ConfigError::invalid(
                    super::key(prefix, &format!("gravity[{i}]")),
                    format!("must be finite, got {g}"),
                ));
            }
        }
        Ok(())
    }
}
