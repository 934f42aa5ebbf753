//! The spring laws of the paper (§3) and the force and tangent stiffness of
//! a spring between two points.
//!
//! A spring from `x_i` to `x_j` with rest length `L₀`, current length
//! `l = |x_j − x_i|`, direction `d = (x_j − x_i)/l`, elongation `e = l − L₀`
//! and scalar law `f(e)` (tension positive) pulls node `i` with
//! `f_i = f(e) d` and node `j` with `−f_i`. Its tangent stiffness is
//!
//! `∂f_i/∂x_j = S = f′(e) d dᵀ + (f(e)/l)(I − d dᵀ)` (axial + geometric term),
//! `∂f_i/∂x_i = ∂f_j/∂x_j = −S`, `∂f_j/∂x_i = S`.
//!
//! A damper `c` along the spring adds `c ((v_j − v_i)·d) d` to `f_i`, with
//! `∂f_i/∂v_j = c d dᵀ`, `∂f_i/∂v_i = −c d dᵀ`.

use crate::Vec3;
use nalgebra::Matrix3;

/// Linear spring law `f(x) = a x` (paper §3), `a` in N/m, `x` in m, `f` in N.
#[inline]
pub fn linear_force(a: f64, x: f64) -> f64 {
    a * x
}

/// Nonlinear normal spring law `f(x) = x / (a x + b)` (paper §3), `x` the
/// change of length (m, negative in compression), `a` in 1/N, `b` in m/N,
/// tension positive. Valid for `a x + b > 0`, i.e. compression below the
/// asymptote `b/a`.
#[inline]
pub fn normal_force(a: f64, b: f64, x: f64) -> f64 {
    x / (a * x + b)
}

/// Derivative `f′(x) = b / (a x + b)²` (N/m) of [`normal_force`].
#[inline]
pub fn normal_stiffness(a: f64, b: f64, x: f64) -> f64 {
    let den = a * x + b;
    b / (den * den)
}

/// Potential energy `∫₀ˣ f = x/a − (b/a²) ln(1 + a x / b)` (J) of the normal spring.
#[inline]
pub fn normal_energy(a: f64, b: f64, x: f64) -> f64 {
    x / a - b / (a * a) * (a * x / b).ln_1p()
}

/// Force on endpoint `i` and the block `S = ∂f_i/∂x_j` of a spring between
/// `xi` and `xj` whose scalar force (N) and derivative (N/m) at elongation `e`
/// are `force_law(e) = (f, f′)`.
///
/// `geometric_in_compression = false` drops the geometric term when `f < 0`
/// (it is negative there and can make the Newton matrix indefinite).
/// A zero-length spring returns zero force and an axial-free block.
#[inline]
pub fn spring_force_jacobian(
    xi: &Vec3,
    xj: &Vec3,
    rest: f64,
    force_law: impl Fn(f64) -> (f64, f64),
    geometric_in_compression: bool,
) -> (Vec3, Matrix3<f64>) {
    let delta = xj - xi;
    let l = delta.norm();
    if l <= f64::MIN_POSITIVE {
        return (Vec3::zeros(), Matrix3::zeros());
    }
    let d = delta / l;
    let (f, df) = force_law(l - rest);
    let ddt = d * d.transpose();
    let g = if f < 0.0 && !geometric_in_compression {
        0.0
    } else {
        f / l
    };
    let s = ddt * (df - g) + Matrix3::from_diagonal_element(g);
    (d * f, s)
}

/// Force on endpoint `i` of a spring (N): `f(e) d`, no Jacobian.
#[inline]
pub fn spring_force(xi: &Vec3, xj: &Vec3, rest: f64, force_law: impl Fn(f64) -> f64) -> Vec3 {
    let delta = xj - xi;
    let l = delta.norm();
    if l <= f64::MIN_POSITIVE {
        return Vec3::zeros();
    }
    delta * (force_law(l - rest) / l)
}

/// Damper force on endpoint `i` (N): `c ((v_j − v_i)·d) d`, `c` in N·s/m.
#[inline]
pub fn damper_force(xi: &Vec3, xj: &Vec3, vi: &Vec3, vj: &Vec3, c: f64) -> Vec3 {
    let delta = xj - xi;
    let l2 = delta.norm_squared();
    if l2 <= f64::MIN_POSITIVE {
        return Vec3::zeros();
    }
    delta * (c * (vj - vi).dot(&delta) / l2)
}

/// Damper block `∂f_i/∂v_j = c d dᵀ` (N·s/m).
#[inline]
pub fn damper_jacobian(xi: &Vec3, xj: &Vec3, c: f64) -> Matrix3<f64> {
    let delta = xj - xi;
    let l2 = delta.norm_squared();
    if l2 <= f64::MIN_POSITIVE {
        return Matrix3::zeros();
    }
    delta * delta.transpose() * (c / l2)
}
