//! `[tissue]`: lumped masses, linear membrane springs and dampers, nonlinear
//! normal springs (paper §3).

use super::{range, ConfigError};
use serde::{Deserialize, Serialize};

/// Tissue parameters, all resolution independent.
///
/// **Calibrated defaults.** `normal_a` and `normal_b` are the
/// Levenberg–Marquardt fit (`echothigh calibrate`, crate
/// `echothigh-contact`) of `data/indentation-default.csv` with
/// `tangential_stiffness` held at 1e6 and `structural_stiffness` at 1, the
/// lower bound a fit of it reaches (see `data/indentation-default.md`).
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
/// `thigh.tissue_thickness`. On a patient's leg (`thigh.patient`) the law
/// holds for the reference layer `thigh.tissue_thickness`; a node whose
/// layer is `λ` times thicker and `φ` times stiffer (regional factor) gets
/// the same law at the same strain, `a = normal_a/(φA)`, `b = λ
/// normal_b/(φA)` (asymptote `λ b/a`), and its shear tie `φ k_t A` (see
/// `crate::leg`).
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
    /// Mass per unit skin area carried by the surface nodes (kg/m²), in [1,
    /// 200]: soft tissue of density ~1 000 kg/m³ (Duck 1990) over 1 mm to
    /// 0.2 m of moving thickness. Default 10.
    pub areal_density: f64,
    /// Membrane modulus of the structural springs (θ and z neighbours)
    /// (N/m), in [1, 1e5]: skin's Young's modulus ~0.1–10 MPa (Duck 1990)
    /// times its ~2 mm thickness gives 2e2–2e4 N/m; the calibrated default is
    /// lower (the fat below is softer), and 1e5 leaves margin. Default 1.0,
    /// the lower bound (calibrated, see above: with the normal springs as
    /// columns along the rest normal, the indentation curve leaves the
    /// membrane nothing to carry; the shear and bending springs remain).
    pub structural_stiffness: f64,
    /// Membrane modulus of the shear springs (quad diagonals) (N/m), in [0,
    /// 1e5] (as `structural_stiffness`; 0 = no shear springs). Default 50.
    pub shear_stiffness: f64,
    /// Membrane modulus of the bending springs (second neighbours in θ and
    /// z) (N/m), in [0, 1e5] (as `structural_stiffness`). Default 20.
    pub bending_stiffness: f64,
    /// Damping modulus of the structural springs' dampers (N·s/m), in [0,
    /// 100]: with `areal_density` ≥ 1 kg/m² this spans from undamped to
    /// far past critical damping of the membrane modes at the mesh scale.
    /// Default 0.2.
    pub structural_damping: f64,
    /// Damping modulus of the shear springs' dampers (N·s/m), in [0, 100].
    /// Default 0.05.
    pub shear_damping: f64,
    /// Damping modulus of the bending springs' dampers (N·s/m), in [0, 100].
    /// Default 0.02.
    pub bending_damping: f64,
    /// Normal spring `a` per unit area (m²/N = 1/Pa), in [1e-7, 1e-2]: `1/a`
    /// is the tension the layer saturates at, from 100 Pa (fat) to 10 MPa
    /// (tendon); the asymptote `b/a` must also lie inside the tissue.
    /// Default 6.632e-5.
    pub normal_a: f64,
    /// Normal spring `b` per unit area (m³/N = m/Pa): `1/normal_b` is the
    /// initial stiffness per unit area, in [1e-9, 1e-3]: soft tissue moduli
    /// of 1 kPa–1 MPa (Duck 1990) over 1 mm–0.2 m of thickness give
    /// `E / L` of 5e3–1e9 Pa/m. Default 2.629e-6 (asymptote 39.64 mm).
    pub normal_b: f64,
    /// Normal damper per unit area (N·s/m³): node damping = this × node area,
    /// in [0, 1e6] (from none to ~100× critical damping of the default layer:
    /// `2 √(ρ_A / normal_b)` ≈ 3.7e3). Default 2000.
    pub normal_damping: f64,
    /// Tangential (shear) stiffness of the tissue layer per unit area (N/m³):
    /// node value = this × node area. Default 1.0e6 (raised from 1e5 by the
    /// calibration: with less, the skin under a pressed probe slides sideways
    /// past ~15 mm on the default mesh). In [0, 1e9] (as `1 / normal_b`).
    pub tangential_stiffness: f64,
    /// Tangential damping per unit area (N·s/m³), in [0, 1e6] (as
    /// `normal_damping`). Default 500.
    pub tangential_damping: f64,
    /// Gravity acceleration (m/s²), each component in [−20, 20] (up to ~2 g:
    /// the Earth's, tilted any way, with margin). Exactly three elements.
    /// Default `[0, 0, 0]`: the rest shape is the thigh as observed, i.e.
    /// already in equilibrium under gravity.
    #[serde(deserialize_with = "super::exact_array")]
    pub gravity: [f64; 3],
}

impl Default for TissueParams {
    fn default() -> Self {
        TissueParams {
            areal_density: 10.0,
            structural_stiffness: 1.0,
            shear_stiffness: 50.0,
            bending_stiffness: 20.0,
            structural_damping: 0.2,
            shear_damping: 0.05,
            bending_damping: 0.02,
            normal_a: 6.632e-5,
            normal_b: 2.629e-6,
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

    /// Validates every field against its documented range; errors name
    /// `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let p = prefix;
        let rho = "soft tissue ~1000 kg/m³ over 1 mm to 0.2 m";
        range(
            p,
            "areal_density",
            self.areal_density,
            (1.0, 200.0),
            "kg/m²",
            rho,
        )?;
        let membrane = "skin's modulus times its thickness, with margin";
        range(
            p,
            "structural_stiffness",
            self.structural_stiffness,
            (1.0, 1e5),
            "N/m",
            membrane,
        )?;
        range(
            p,
            "shear_stiffness",
            self.shear_stiffness,
            (0.0, 1e5),
            "N/m",
            membrane,
        )?;
        range(
            p,
            "bending_stiffness",
            self.bending_stiffness,
            (0.0, 1e5),
            "N/m",
            membrane,
        )?;
        let damp = "undamped to far past critical at the mesh scale";
        range(
            p,
            "structural_damping",
            self.structural_damping,
            (0.0, 100.0),
            "N·s/m",
            damp,
        )?;
        range(
            p,
            "shear_damping",
            self.shear_damping,
            (0.0, 100.0),
            "N·s/m",
            damp,
        )?;
        range(
            p,
            "bending_damping",
            self.bending_damping,
            (0.0, 100.0),
            "N·s/m",
            damp,
        )?;
        let sat = "1/a is the saturation tension, 100 Pa to 10 MPa";
        range(p, "normal_a", self.normal_a, (1e-7, 1e-2), "1/Pa", sat)?;
        let stiff = "1/b from 1e3 to 1e9 Pa/m: soft tissue moduli over its thickness";
        range(p, "normal_b", self.normal_b, (1e-9, 1e-3), "m/Pa", stiff)?;
        let ndamp = "none to ~100x the critical damping of the layer";
        range(
            p,
            "normal_damping",
            self.normal_damping,
            (0.0, 1e6),
            "N·s/m³",
            ndamp,
        )?;
        let tan = "as 1/normal_b";
        range(
            p,
            "tangential_stiffness",
            self.tangential_stiffness,
            (0.0, 1e9),
            "N/m³",
            tan,
        )?;
        range(
            p,
            "tangential_damping",
            self.tangential_damping,
            (0.0, 1e6),
            "N·s/m³",
            ndamp,
        )?;
        for (i, g) in self.gravity.iter().enumerate() {
            let field = format!("gravity[{i}]");
            range(p, &field, *g, (-20.0, 20.0), "m/s²", "up to ~2 g")?;
        }
        Ok(())
    }
}
