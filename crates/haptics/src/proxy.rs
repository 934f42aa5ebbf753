//! The god-object / virtual proxy (paper §4; Zilles & Salisbury, Ruspini et
//! al.): the proxy `x` is where the probe would be if the constraint surface
//! were infinitely stiff. Each tick it solves
//! `minimize ½|x − p|² s.t. φ(x) ≥ 0` approximately:
//!
//! 1. if `φ(p) ≥ 0`, `x = p` (free space);
//! 2. otherwise move `x` along its straight path towards `p` until contact;
//! 3. then minimize `½|x − p|²` on the plane tangent at `x` and re-project
//!    onto `φ = 0` (the paper's first-order constraint plane), repeated
//!    until stationary, and warm-started at the re-projection of `p`, which
//!    is already the minimum for signed-distance models like ours (one pass
//!    from the proxy converges only by a factor depth/radius per pass),
//!
//! where step 3 is limited by friction (static and kinetic cones with
//! hysteresis, CHAI3D's behaviour) and the surface carries a texture (a
//! height perturbation, Ruspini's "controlling the constraint plane").

use crate::local_model::LocalModel;
use crate::shading::ShadedModel;
use crate::Vec3;

/// Constraint surface `φ_eff(x) = φ(u, x) − h(x) = 0` with texture height
/// `h(x) = A · (sin 2πx/λ + sin 2πy/λ + sin 2πz/λ)/3`, m (|h| ≤ A).
#[derive(Debug, Clone, Copy)]
pub struct Surface {
    /// The buffer model, shaded between successive models (a single model
    /// converts with `.into()`).
    pub model: ShadedModel,
    /// Texture amplitude `A`, m.
    pub amplitude: f64,
    /// Texture wavelength `λ`, m.
    pub wavelength: f64,
}

impl Surface {
    /// Texture height `h(x)`, m.
    pub fn texture(&self, x: &Vec3) -> f64 {
        if self.amplitude == 0.0 {
            return 0.0;
        }
        let k = std::f64::consts::TAU / self.wavelength;
        self.amplitude * ((k * x.x).sin() + (k * x.y).sin() + (k * x.z).sin()) / 3.0
    }

    /// `∇h(x)`, dimensionless.
    pub fn texture_gradient(&self, x: &Vec3) -> Vec3 {
        if self.amplitude == 0.0 {
            return Vec3::zeros();
        }
        let k = std::f64::consts::TAU / self.wavelength;
        let c = self.amplitude * k / 3.0;
        Vec3::new(
            c * (k * x.x).cos(),
            c * (k * x.y).cos(),
            c * (k * x.z).cos(),
        )
    }

    /// `φ_eff(x)`, m: positive outside.
    pub fn value(&self, x: &Vec3) -> f64 {
        self.model.value(x) - self.texture(x)
    }

    /// Outward unit normal of the model at `x` (texture does not tilt it).
    /// Where a shaded blend's gradient vanishes (opposite normals in equal
    /// weights) the newest model's normal is used.
    pub fn normal(&self, x: &Vec3) -> Vec3 {
        self.model
            .gradient(x)
            .try_normalize(1e-9)
            .unwrap_or_else(|| self.model.newest().gradient(x))
    }

    /// Re-projects `x` onto `φ_eff = 0` along the normal `n`: Newton steps
    /// `s = φ_eff / (|∇φ| − n·∇h)` (one is exact for the untextured sphere
    /// and plane; a few for a shaded blend; the slope is floored at 0.2 for
    /// steep textures and blends of diverging normals).
    pub fn project(&self, x: &Vec3) -> Vec3 {
        let mut x = *x;
        for _ in 0..MAX_PROJECTION_STEPS {
            let f = self.value(&x);
            if f.abs() < 1e-13 {
                break;
            }
            let g = self.model.gradient(&x);
            let n = self.normal(&x);
            let slope = (g.dot(&n) - n.dot(&self.texture_gradient(&x))).max(0.2);
            x -= n * (f / slope);
        }
        x
    }

    /// First point of the segment `from → to` where `φ_eff` reaches 0, given
    /// `φ_eff(from) ≥ 0 > φ_eff(to)`; returns the outside end of the final
    /// bracket (bisection, ≤ 60 halvings, stops at 1e-13 m).
    pub fn first_contact(&self, from: &Vec3, to: &Vec3) -> Vec3 {
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        let d = to - from;
        let len = d.norm();
        for _ in 0..60 {
            if (hi - lo) * len < 1e-13 {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if self.value(&(from + d * mid)) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        from + d * lo
    }
}

/// Friction cone coefficients (dimensionless, `kinetic ≤ static`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// μ_s: the proxy sticks while `|f_t| ≤ μ_s |f_n|`.
    pub static_coefficient: f64,
    /// μ_k: while sliding, the proxy trails the device at `|f_t| = μ_k |f_n|`.
    pub kinetic_coefficient: f64,
}

/// Proxy state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proxy {
    /// Proxy position `x`, m.
    pub position: Vec3,
    /// The device is inside the constraint (the proxy is held on it).
    pub in_contact: bool,
    /// Friction state: sliding (kinetic cone) or sticking (static cone).
    pub sliding: bool,
}

/// Tangent-plane passes per tick when polishing the frictionless goal (one
/// is exact on a plane; curved surfaces converge by about depth/radius per
/// pass).
const MAX_PASSES: usize = 8;

/// Newton steps of a re-projection onto the surface.
const MAX_PROJECTION_STEPS: usize = 8;

/// Distance beyond which a proxy counts as off the surface, m.
const ON_SURFACE: f64 = 1e-9;

impl Proxy {
    /// A free proxy at `p`.
    pub fn new(p: Vec3) -> Self {
        Proxy {
            position: p,
            in_contact: false,
            sliding: false,
        }
    }

    /// The constrained minimum of `½|x − p|²` on `φ_eff = 0` near the proxy
    /// `x` (the frictionless proxy). Both local models are exact signed
    /// distances, so the re-projection of `p` is the minimum (nearly so for
    /// a shaded blend of two); it is accepted
    /// only on the proxy's side of the surface (normals within 90°: no
    /// pop-through), else the paper's tangent-plane steps start from `x`.
    /// Tangent-plane passes then polish it (textured surfaces).
    fn frictionless_goal(&self, surface: &Surface, p: &Vec3, x: &Vec3) -> Vec3 {
        let mut g = surface.project(p);
        let same_side = surface.normal(&g).dot(&surface.normal(x)) > 0.0;
        if !same_side || !g.iter().all(|c| c.is_finite()) {
            g = *x;
        }
        for _ in 0..MAX_PASSES {
            let n = surface.normal(&g);
            let v = p - g;
            let vt = v - v.dot(&n) * n;
            if vt.norm() < 1e-13 {
                break;
            }
            g = surface.project(&(g + vt));
        }
        g
    }

    /// One proxy update for device position `p` against `surface`.
    pub fn update(&mut self, surface: &Surface, p: &Vec3, friction: &Friction) {
        if surface.value(p) >= 0.0 {
            *self = Proxy::new(*p);
            return;
        }
        let mut x = self.position;
        let phi_x = surface.value(&x);
        if phi_x < 0.0 {
            // The surface moved over the proxy (new model): push it out.
            x = surface.project(&x);
        } else if phi_x > ON_SURFACE || !self.in_contact {
            // Free (or the surface receded): follow the path to contact.
            x = surface.first_contact(&x, p);
            self.sliding = false;
        }
        self.in_contact = true;
        let goal = self.frictionless_goal(surface, p, &x);
        // Friction cone at the proxy: stick while |f_t| ≤ μ |f_n| (μ_s when
        // sticking, μ_k when already sliding: the hysteresis).
        let n = surface.normal(&x);
        let v = p - x;
        let vn = v.dot(&n);
        let depth = (-vn).max(0.0);
        let dt = (v - vn * n).norm();
        let mu = if self.sliding {
            friction.kinetic_coefficient
        } else {
            friction.static_coefficient
        };
        if dt <= mu * depth + 1e-15 {
            self.sliding = false;
        } else {
            // Slide towards the frictionless goal, stopping at the kinetic
            // cone's edge: a tangential offset of μ_k · depth behind it.
            let ng = surface.normal(&goal);
            let d = x - goal;
            let d_t = d - d.dot(&ng) * ng;
            let len = d_t.norm();
            let keep = friction.kinetic_coefficient * (goal - p).dot(&ng).max(0.0);
            if len > keep {
                x = surface.project(&(goal + d_t * (keep / len)));
            }
            self.sliding = true;
        }
        self.position = x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local_model::{ModelParams, Plane, Sphere};

    fn floor() -> Surface {
        Surface {
            model: ModelParams::Plane(Plane {
                normal: Vec3::y(),
                offset: 0.0,
            })
            .into(),
            amplitude: 0.0,
            wavelength: 0.002,
        }
    }

    const FRICTIONLESS: Friction = Friction {
        static_coefficient: 0.0,
        kinetic_coefficient: 0.0,
    };

    #[test]
    fn free_proxy_follows_device() {
        let mut x = Proxy::new(Vec3::new(0.0, 0.02, 0.0));
        x.update(&floor(), &Vec3::new(0.01, 0.01, 0.0), &FRICTIONLESS);
        assert_eq!(x.position, Vec3::new(0.01, 0.01, 0.0));
        assert!(!x.in_contact);
    }

    #[test]
    fn frictionless_proxy_is_the_closest_surface_point() {
        let mut x = Proxy::new(Vec3::new(0.0, 0.01, 0.0));
        x.update(&floor(), &Vec3::new(0.02, -0.01, 0.0), &FRICTIONLESS);
        assert!((x.position - Vec3::new(0.02, 0.0, 0.0)).norm() < 1e-12);
        let sphere = Surface {
            model: ModelParams::Sphere(Sphere {
                center: Vec3::zeros(),
                radius: 0.1,
            })
            .into(),
            ..floor()
        };
        let mut x = Proxy::new(Vec3::new(0.0, 0.11, 0.0));
        let p = Vec3::new(0.02, 0.09, 0.0);
        for _ in 0..20 {
            x.update(&sphere, &p, &FRICTIONLESS);
        }
        assert!((x.position - p.normalize() * 0.1).norm() < 1e-9);
    }

    #[test]
    fn friction_sticks_then_slides_to_kinetic_edge() {
        let f = Friction {
            static_coefficient: 0.5,
            kinetic_coefficient: 0.25,
        };
        let mut x = Proxy::new(Vec3::new(0.0, 0.01, 0.0));
        x.update(&floor(), &Vec3::new(0.0, -0.01, 0.0), &f);
        // tangential 4 mm at 10 mm depth: inside the static cone, sticks.
        x.update(&floor(), &Vec3::new(0.004, -0.01, 0.0), &f);
        assert!(!x.sliding);
        assert!(x.position.norm() < 1e-12);
        // 6 mm: outside, slides to μ_k·depth = 2.5 mm behind the device.
        x.update(&floor(), &Vec3::new(0.006, -0.01, 0.0), &f);
        assert!(x.sliding);
        assert!((x.position.x - 0.0035).abs() < 1e-12);
        // Hysteresis: 3 mm offset (between the cones) keeps sliding.
        x.update(&floor(), &Vec3::new(0.0065, -0.01, 0.0), &f);
        assert!(x.sliding);
        assert!((x.position.x - 0.004).abs() < 1e-12);
    }

    #[test]
    fn texture_height_is_bounded_and_projection_lands_on_it() {
        let s = Surface {
            amplitude: 1e-4,
            ..floor()
        };
        let x = s.project(&Vec3::new(0.0011, 0.003, 0.0007));
        assert!(s.value(&x).abs() < 1e-12);
        assert!(x.y.abs() <= 1e-4 + 1e-15);
    }
}
