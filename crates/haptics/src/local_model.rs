//! Local models `φ(u, x)` of the buffer model (paper §4): the constraint
//! surface is `φ = 0`, `φ > 0` outside the thigh. Both of the models here
//! have `r = 4` parameters, so parameters are a `Vector4`.
//!
//! Jacobian convention: the paper writes `dφ'/du` as an `r × n` matrix; here
//! `gradient_du` returns its transpose, the `n × r` (3×4) matrix whose row
//! `i` is `∂φ'_i/∂u`, so that `[dφ/du; dφ'/du] du` is the paper's `J du`.

use nalgebra::{Matrix3, Matrix3x4, Vector4};

use crate::Vec3;

/// Parameters `u` of a local model.
pub type Params = Vector4<f64>;

/// A local model `φ(u, x)` and the derivatives the model manager needs.
pub trait LocalModel: Copy {
    /// The parameter vector `u` (units per model).
    fn params(&self) -> Params;
    /// The model with parameters `u`, normalized where the model needs it
    /// (a plane's normal is made unit).
    fn with_params(&self, u: &Params) -> Self;
    /// `φ(u, x)`, m: signed distance-like value, positive outside.
    fn value(&self, x: &Vec3) -> f64;
    /// `∇ₓφ(u, x)` (paper's `φ'`), dimensionless, unit length for both models.
    fn gradient(&self, x: &Vec3) -> Vec3;
    /// `∂φ/∂u` (paper's `dφ/du`), one entry per parameter.
    fn value_du(&self, x: &Vec3) -> Params;
    /// `∂(∇ₓφ)/∂u`: row `i` is `∂φ'_i/∂u` (transpose of the paper's `dφ'/du`).
    fn gradient_du(&self, x: &Vec3) -> Matrix3x4<f64>;
    /// True when every parameter is finite and the model is usable.
    fn is_valid(&self) -> bool;
}

/// Direction used where a gradient is undefined (the sphere's centre): `+y`,
/// anterior, towards the probe in the default pose.
const FALLBACK_NORMAL: Vec3 = Vec3::new(0.0, 1.0, 0.0);

/// The paper's spherical buffer model `φ = |x − c| − r`, `u = (c, r)` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Centre `c`, m.
    pub center: Vec3,
    /// Radius `r`, m.
    pub radius: f64,
}

impl Sphere {
    fn offset(&self, x: &Vec3) -> (Vec3, f64) {
        let d = x - self.center;
        let rho = d.norm();
        if rho > 1e-12 {
            (d / rho, rho)
        } else {
            (FALLBACK_NORMAL, rho)
        }
    }
}

impl LocalModel for Sphere {
    fn params(&self) -> Params {
        Params::new(self.center.x, self.center.y, self.center.z, self.radius)
    }
    fn with_params(&self, u: &Params) -> Self {
        Sphere {
            center: Vec3::new(u[0], u[1], u[2]),
            radius: u[3],
        }
    }
    fn value(&self, x: &Vec3) -> f64 {
        (x - self.center).norm() - self.radius
    }
    fn gradient(&self, x: &Vec3) -> Vec3 {
        self.offset(x).0
    }
    /// `∂φ/∂c = −n`, `∂φ/∂r = −1` with `n = (x − c)/|x − c|`.
    fn value_du(&self, x: &Vec3) -> Params {
        let n = self.gradient(x);
        Params::new(-n.x, -n.y, -n.z, -1.0)
    }
    /// `∂n/∂c = −(I − n nᵀ)/ρ`, `∂n/∂r = 0`: rank 2, so the 4×4 `J` at one
    /// sample has rank 3 (moving `c` along `n` while growing `r` by the same
    /// amount changes neither `φ` nor `φ'`).
    fn gradient_du(&self, x: &Vec3) -> Matrix3x4<f64> {
        let (n, rho) = self.offset(x);
        let p = (Matrix3::identity() - n * n.transpose()) / rho.max(1e-12);
        let mut j = Matrix3x4::zeros();
        j.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-p));
        j
    }
    fn is_valid(&self) -> bool {
        self.center.iter().all(|v| v.is_finite()) && self.radius.is_finite() && self.radius > 0.0
    }
}

/// A plane `φ = n·x − d`, `u = (n, d)` with `|n| = 1` (d in m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Unit outward normal `n`.
    pub normal: Vec3,
    /// Offset `d`, m: the plane is `{x : n·x = d}`.
    pub offset: f64,
}

impl LocalModel for Plane {
    fn params(&self) -> Params {
        Params::new(self.normal.x, self.normal.y, self.normal.z, self.offset)
    }
    /// Divides `(n, d)` by `|n|` so that `φ` stays a signed distance.
    fn with_params(&self, u: &Params) -> Self {
        let n = Vec3::new(u[0], u[1], u[2]);
        let len = n.norm();
        if len > 1e-12 && len.is_finite() {
            Plane {
                normal: n / len,
                offset: u[3] / len,
            }
        } else {
            Plane {
                normal: n,
                offset: u[3],
            }
        }
    }
    fn value(&self, x: &Vec3) -> f64 {
        self.normal.dot(x) - self.offset
    }
    fn gradient(&self, _x: &Vec3) -> Vec3 {
        self.normal
    }
    /// `∂φ/∂n = x`, `∂φ/∂d = −1`.
    fn value_du(&self, x: &Vec3) -> Params {
        Params::new(x.x, x.y, x.z, -1.0)
    }
    /// `∂φ'/∂n = I`, `∂φ'/∂d = 0` (full rank 4 with the value row).
    fn gradient_du(&self, _x: &Vec3) -> Matrix3x4<f64> {
        let mut j = Matrix3x4::zeros();
        j.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        j
    }
    fn is_valid(&self) -> bool {
        self.normal.iter().all(|v| v.is_finite())
            && self.offset.is_finite()
            && (self.normal.norm() - 1.0).abs() < 1e-6
    }
}

/// The buffer model's parameters, of either kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModelParams {
    /// The paper's sphere.
    Sphere(Sphere),
    /// A plane.
    Plane(Plane),
}

macro_rules! dispatch {
    ($self:expr, $m:ident => $e:expr) => {
        match $self {
            ModelParams::Sphere($m) => $e,
            ModelParams::Plane($m) => $e,
        }
    };
}

impl LocalModel for ModelParams {
    fn params(&self) -> Params {
        dispatch!(self, m => m.params())
    }
    fn with_params(&self, u: &Params) -> Self {
        match self {
            ModelParams::Sphere(s) => ModelParams::Sphere(s.with_params(u)),
            ModelParams::Plane(p) => ModelParams::Plane(p.with_params(u)),
        }
    }
    fn value(&self, x: &Vec3) -> f64 {
        dispatch!(self, m => m.value(x))
    }
    fn gradient(&self, x: &Vec3) -> Vec3 {
        dispatch!(self, m => m.gradient(x))
    }
    fn value_du(&self, x: &Vec3) -> Params {
        dispatch!(self, m => m.value_du(x))
    }
    fn gradient_du(&self, x: &Vec3) -> Matrix3x4<f64> {
        dispatch!(self, m => m.gradient_du(x))
    }
    fn is_valid(&self) -> bool {
        dispatch!(self, m => m.is_valid())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_derivatives<M: LocalModel>(m: M, x: Vec3) {
        let u = m.params();
        let h = 1e-6;
        let dv = m.value_du(&x);
        let dg = m.gradient_du(&x);
        for k in 0..4 {
            let mut up = u;
            up[k] += h;
            let mut um = u;
            um[k] -= h;
            let (mp, mm) = (m.with_params(&up), m.with_params(&um));
            let fd = (mp.value(&x) - mm.value(&x)) / (2.0 * h);
            assert!(
                (fd - dv[k]).abs() < 1e-7,
                "dφ/du[{k}]: fd {fd} vs {}",
                dv[k]
            );
            let gd = (mp.gradient(&x) - mm.gradient(&x)) / (2.0 * h);
            for i in 0..3 {
                assert!((gd[i] - dg[(i, k)]).abs() < 1e-6, "dφ'/du[{i},{k}]");
            }
        }
        // ∇ₓφ against finite differences in x.
        let g = m.gradient(&x);
        for i in 0..3 {
            let mut xp = x;
            xp[i] += h;
            let mut xm = x;
            xm[i] -= h;
            let fd = (m.value(&xp) - m.value(&xm)) / (2.0 * h);
            assert!((fd - g[i]).abs() < 1e-7);
        }
    }

    #[test]
    fn sphere_derivatives_match_finite_differences() {
        let s = Sphere {
            center: Vec3::new(0.01, -0.02, 0.03),
            radius: 0.08,
        };
        check_derivatives(s, Vec3::new(0.03, 0.07, 0.01));
        check_derivatives(s, Vec3::new(-0.01, 0.0, 0.05));
    }

    #[test]
    fn plane_derivatives_are_the_linear_form() {
        // `with_params` re-normalizes the normal, so finite differences of
        // the normalized model are not ∂φ/∂n of the raw form `n·x − d`;
        // check the analytic derivatives directly.
        let p = Plane {
            normal: Vec3::new(0.0, 1.0, 0.0),
            offset: 0.02,
        };
        let x = Vec3::new(0.01, 0.05, -0.02);
        assert!((p.value(&x) - 0.03).abs() < 1e-15);
        let dv = p.value_du(&x);
        assert_eq!(dv, Params::new(x.x, x.y, x.z, -1.0));
        assert_eq!(p.gradient(&x), Vec3::y());
        let mut expected = Matrix3x4::zeros();
        expected.fixed_view_mut::<3, 3>(0, 0).fill_with_identity();
        assert_eq!(p.gradient_du(&x), expected);
    }

    #[test]
    fn sphere_jacobian_has_rank_three_at_one_point() {
        let s = Sphere {
            center: Vec3::zeros(),
            radius: 0.1,
        };
        let x = Vec3::new(0.0, 0.12, 0.0);
        let mut j = nalgebra::Matrix4::zeros();
        j.row_mut(0).copy_from(&s.value_du(&x).transpose());
        j.fixed_view_mut::<3, 4>(1, 0).copy_from(&s.gradient_du(&x));
        assert_eq!(j.rank(1e-12), 3);
    }
}
