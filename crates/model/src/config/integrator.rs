//! `[integrator]`: implicit Euler (Eq. 1), Newton iterations, PCG.

use super::{count_range, range, ConfigError, WindowParams};
use crate::pcg::{PcgParams, Preconditioner};
use serde::{Deserialize, Serialize};

/// Settings of the implicit integrator (paper Eq. 1 with the blend λ) and of
/// its Newton and PCG solvers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IntegratorParams {
    /// Blend λ of Eq. 1: 1 = backward Euler, 0 = explicit Euler. Restricted
    /// to [0.5, 1]: the λ-scheme (θ-method) is unconditionally stable only
    /// for λ ≥ ½ (its amplification factor on `ẋ = −ω x` is `(1 − (1−λ) h ω)
    /// / (1 + λ h ω)`, of modulus ≤ 1 for every `h ω > 0` iff λ ≥ ½); below,
    /// the stiff normal springs (ω h ≫ 1 at 100 Hz) make the model diverge.
    /// Default 1.
    pub lambda: f64,
    /// Default physics time step h (s), in [1e-4, 0.1]: physics rates from
    /// 10 Hz (below, the haptic buffer model has nothing to interpolate) to
    /// 10 kHz (the fastest haptic loop; a smaller step only multiplies the
    /// work). Default 0.01 (the paper's 100 Hz).
    pub time_step: f64,
    /// Newton stops when the residual norm falls below this fraction of its
    /// value at the step's first iterate (dimensionless). Default 2e-2: with
    /// the defaults the positions of a step are within ~1 µm of the exactly
    /// solved step on the default mesh under a pressing probe; the remaining
    /// residual is carried into the next step, not accumulated. In [1e-12,
    /// 0.5]: a relative reduction (below 1e-12 is under the f64 round-off of
    /// the residual; above ½ Newton barely iterates).
    pub newton_tol: f64,
    /// Rounding floor of Newton (dimensionless): Newton also stops when the
    /// residual's position equivalent `h · max_i |r_i| / m_i` (m, an upper
    /// bound of the correction a solve would make, since every diagonal block
    /// of the system is ≥ `m_i`) is below this fraction of the model's size
    /// `max_i |x_i|∞` (m). It is not a physical tolerance (that is
    /// [`Self::newton_tol`], relative to the step's own first residual, so a
    /// 1e-4 N load is resolved as well as a 10 N one): it only stops Newton
    /// from chasing rounding noise at rest. Forces carry a rounding error of
    /// about `ε |x| k` per spring (`ε` = 2.2e-16), which the bound amplifies
    /// by `h² k / m` (≤ ~1e4 for the stiffest normal spring near its
    /// asymptote on the default mesh) and ~10 springs per node: ≈ 2e-11 of the
    /// size; the default leaves a factor 50 above that. Default 1e-9.
    pub newton_floor: f64,
    /// Cap on Newton iterations (linear solves) per step, in [1, 100]: the
    /// step's work is bounded by this × `cg_max_iterations` matrix products,
    /// and Newton converging at all does so in a few tens. Default 8.
    pub newton_max_iterations: u32,
    /// PCG relative residual tolerance `|A x − b| ≤ tol · |b|` of each Newton
    /// solve (inexact Newton: never tighter than `newton_tol / 2` of the
    /// step's first residual requires). In [1e-12, 0.5] (a relative
    /// reduction, as `newton_tol`). Default 1e-2.
    pub cg_tol: f64,
    /// PCG relative tolerance of [`crate::ThighModel::solve_stiffness`] (the
    /// local stiffness for the haptic side), in [1e-12, 0.5]. Default 1e-5.
    pub stiffness_tol: f64,
    /// Cap on PCG iterations per linear solve, in [1, 5000]: CG converges
    /// in at most `3 · nodes` iterations in exact arithmetic; 5000 covers
    /// the block-Jacobi preconditioned default mesh (3 024 unknowns) many
    /// times over while bounding a step's work. Default 200.
    pub cg_max_iterations: u32,
    /// PCG preconditioner. Default `block_jacobi`.
    pub preconditioner: Preconditioner,
    /// Asymptote margin `m ∈ (0, 1)`: Newton steps are limited so every normal
    /// spring's compression stays ≤ `(1 − m) · b/a`. In [0.001, 0.5]: below,
    /// a spring may sit within round-off of its pole; above, half the
    /// calibrated range of compression is cut off. Default 0.05.
    pub asymptote_margin: f64,
    /// Keep the geometric stiffness `(f/l)(I − d dᵀ)` of compressed springs
    /// (`f < 0`) in the Newton matrix. It is negative, and under a pressing
    /// probe it makes the matrix indefinite (PCG detects it, the step then
    /// retries with a larger mass term and `solve_stiffness` drops the term,
    /// which costs more than it saves). `false` drops it (Choi & Ko 2002): the
    /// matrix stays SPD and Newton, on the exact residual, converges
    /// linearly instead of quadratically. Default false.
    pub geometric_stiffness_in_compression: bool,
    /// The active window (issue 18): integrate only the nodes near the
    /// probe. Off by default.
    pub window: WindowParams,
}

impl Default for IntegratorParams {
    fn default() -> Self {
        IntegratorParams {
            lambda: 1.0,
            time_step: 0.01,
            newton_tol: 2e-2,
            newton_floor: 1e-9,
            newton_max_iterations: 8,
            cg_tol: 1e-2,
            stiffness_tol: 1e-5,
            cg_max_iterations: 200,
            preconditioner: Preconditioner::BlockJacobi,
            asymptote_margin: 0.05,
            geometric_stiffness_in_compression: false,
            window: WindowParams::default(),
        }
    }
}

impl IntegratorParams {
    /// The PCG settings.
    pub fn pcg(&self) -> PcgParams {
        PcgParams {
            tol: self.cg_tol,
            max_iterations: self.cg_max_iterations,
            preconditioner: self.preconditioner,
        }
    }

    /// Validates every field against its documented range; errors name
    /// `{prefix}.{field}`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        range(
            prefix,
            "lambda",
            self.lambda,
            (0.5, 1.0),
            "",
            "the λ-scheme is unconditionally stable only for λ >= 0.5",
        )?;
        let step = "physics rates from 10 Hz to 10 kHz";
        range(prefix, "time_step", self.time_step, (1e-4, 0.1), "s", step)?;
        let rel = "a relative residual reduction";
        range(prefix, "newton_tol", self.newton_tol, (1e-12, 0.5), "", rel)?;
        let floor = "a fraction of the model's size: 0 (no floor) to 1 µm in 1 m";
        range(
            prefix,
            "newton_floor",
            self.newton_floor,
            (0.0, 1e-6),
            "",
            floor,
        )?;
        let work = "bounds the work of one step";
        let newton = u64::from(self.newton_max_iterations);
        count_range(prefix, "newton_max_iterations", newton, (1, 100), work)?;
        range(prefix, "cg_tol", self.cg_tol, (1e-12, 0.5), "", rel)?;
        range(
            prefix,
            "stiffness_tol",
            self.stiffness_tol,
            (1e-12, 0.5),
            "",
            rel,
        )?;
        let cg = u64::from(self.cg_max_iterations);
        count_range(prefix, "cg_max_iterations", cg, (1, 5000), work)?;
        let margin = "a fraction of the springs' asymptote";
        range(
            prefix,
            "asymptote_margin",
            self.asymptote_margin,
            (0.001, 0.5),
            "",
            margin,
        )?;
        self.window.validate(&super::key(prefix, "window"))
    }
}
