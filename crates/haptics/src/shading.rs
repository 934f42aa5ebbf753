//! Force shading across model updates (paper §4, one of the effects of the
//! constraint-based framework: the surface is felt as continuous, not as a
//! sequence of 100 Hz models). When a new buffer model arrives the rendered
//! constraint is blended from the one displayed at that instant to the new
//! one over one physics period, so the force's direction and magnitude do
//! not jump (DESIGN §3; the 100 Hz steps of the paper's Fig. 4 become ramps).
//!
//! **What is blended.** The constraint *functions*, not the models'
//! parameters: `φ_α(x) = Σ wᵢ φᵢ(x)` with weights summing to 1. A blend of
//! parameters (sphere centres and radii) can bulge outwards: by the
//! triangle inequality `|x − c_α| − r_α ≤ (1 − α) φ_a(x) + α φ_b(x)`, so a
//! point outside both spheres can be inside their parameter blend. At
//! lift-off, where successive fits differ most, that rendered contact
//! bumps of several newtons while both the old and the new model said the
//! probe was free. A convex combination of the functions is positive
//! wherever all its terms are: shading never creates contact that no
//! blended model has.

use crate::local_model::{LocalModel, ModelParams};
use crate::Vec3;

/// Most models a shaded constraint holds at once. A blend holds two; a new
/// model arriving before the previous blend has finished makes three; the
/// next early arrival folds the oldest (lightest) term into its successor.
pub const MAX_TERMS: usize = 3;

/// A convex combination of buffer models' constraint functions,
/// `φ(x) = Σ wᵢ φᵢ(x)`, m (positive outside), oldest term first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadedModel {
    terms: [(ModelParams, f64); MAX_TERMS],
    len: usize,
}

impl From<ModelParams> for ShadedModel {
    fn from(m: ModelParams) -> Self {
        ShadedModel {
            terms: [(m, 1.0); MAX_TERMS],
            len: 1,
        }
    }
}

impl ShadedModel {
    /// The terms `(model, weight)`, oldest first.
    pub fn terms(&self) -> &[(ModelParams, f64)] {
        &self.terms[..self.len]
    }

    /// The newest model (the blend's target).
    pub fn newest(&self) -> &ModelParams {
        &self.terms[self.len - 1].0
    }

    /// `φ(x)`, m.
    pub fn value(&self, x: &Vec3) -> f64 {
        self.terms().iter().map(|(m, w)| w * m.value(x)).sum()
    }

    /// `∇φ(x)`: a convex combination of unit normals, so of length ≤ 1 (1
    /// for a single model).
    pub fn gradient(&self, x: &Vec3) -> Vec3 {
        self.terms()
            .iter()
            .fold(Vec3::zeros(), |g, (m, w)| g + m.gradient(x) * *w)
    }

    /// `(1 − α) self + α to`; a fourth term folds the oldest into the next
    /// (see [`ShadedModel::fold_oldest`]).
    pub fn towards(&self, to: ModelParams, alpha: f64) -> ShadedModel {
        let alpha = alpha.clamp(0.0, 1.0);
        if alpha >= 1.0 {
            return to.into();
        }
        if alpha <= 0.0 {
            return *self;
        }
        let mut out = *self;
        if out.len == MAX_TERMS {
            out.fold_oldest();
        }
        for t in &mut out.terms[..out.len] {
            t.1 *= 1.0 - alpha;
        }
        out.terms[out.len] = (to, alpha);
        out.len += 1;
        out
    }

    /// Gives the oldest term's weight to the next term and drops it. The
    /// displayed `φ` changes by `w₀ (φ₁ − φ₀)`: the oldest term is the one
    /// whose blend was interrupted earliest, so its weight is the smallest
    /// left (at most `1 − α` of the interrupted blend).
    fn fold_oldest(&mut self) {
        let w0 = self.terms[0].1;
        self.terms.copy_within(1..self.len, 0);
        self.len -= 1;
        self.terms[0].1 += w0;
    }
}

/// A blend in progress (or finished) from a displayed constraint to a new
/// model, with the rendered stiffness blended alike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shading {
    from: (ShadedModel, f64),
    to: (ModelParams, f64),
    start: f64,
    duration: f64,
}

impl Shading {
    /// A finished blend showing `(params, k)` (k in N/m).
    pub fn settled(params: ModelParams, stiffness: f64) -> Self {
        Shading {
            from: (params.into(), stiffness),
            to: (params, stiffness),
            start: f64::NEG_INFINITY,
            duration: 0.0,
        }
    }

    /// Starts blending from what is displayed at `now` (s) to `(params, k)`
    /// over `duration` (s; ≤ 0 switches at once).
    pub fn retarget(&mut self, params: ModelParams, stiffness: f64, now: f64, duration: f64) {
        let (mut shown, k, _) = self.at(now);
        if shown.len == MAX_TERMS {
            // Interrupted twice in a row: room for the new term.
            shown.fold_oldest();
        }
        *self = Shading {
            from: (shown, k),
            to: (params, stiffness),
            start: now,
            duration,
        };
    }

    /// Blend fraction α ∈ [0, 1] at time `now` (s).
    pub fn alpha(&self, now: f64) -> f64 {
        if self.duration <= 0.0 {
            return 1.0;
        }
        ((now - self.start) / self.duration).clamp(0.0, 1.0)
    }

    /// The displayed constraint, stiffness `k` (N/m) and `α` at time `now`
    /// (s): both linear in `α`.
    pub fn at(&self, now: f64) -> (ShadedModel, f64, f64) {
        let a = self.alpha(now);
        if a >= 1.0 {
            return (self.to.0.into(), self.to.1, 1.0);
        }
        let k = self.from.1 + (self.to.1 - self.from.1) * a;
        (self.from.0.towards(self.to.0, a), k, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local_model::Sphere;

    fn sphere(c: [f64; 3], r: f64) -> ModelParams {
        ModelParams::Sphere(Sphere {
            center: Vec3::new(c[0], c[1], c[2]),
            radius: r,
        })
    }

    /// Two spheres both below `p`, centres offset sideways: the parameter
    /// blend would contain `p`, the function blend does not.
    #[test]
    fn blend_never_contains_a_point_outside_both_models() {
        let a = sphere([0.05, 0.0, 0.0], 0.07);
        let b = sphere([-0.05, 0.0, 0.0], 0.07);
        let p = Vec3::new(0.0, 0.06, 0.0);
        assert!(a.value(&p) > 0.0 && b.value(&p) > 0.0);
        let params = Sphere {
            center: Vec3::zeros(),
            radius: 0.07,
        };
        assert!(params.value(&p) < 0.0, "the parameter blend bulges over p");
        for i in 0..=10 {
            let alpha = i as f64 / 10.0;
            let s = ShadedModel::from(a).towards(b, alpha);
            let want = (1.0 - alpha) * a.value(&p) + alpha * b.value(&p);
            assert!((s.value(&p) - want).abs() < 1e-15);
            assert!(s.value(&p) > 0.0, "α = {alpha}");
        }
    }

    #[test]
    fn shading_is_continuous_and_exact_at_the_ends() {
        let (a, b, c) = (
            sphere([0.0, 0.0, 0.0], 0.08),
            sphere([0.0, -0.01, 0.0], 0.09),
            sphere([0.002, -0.02, 0.0], 0.1),
        );
        let x = Vec3::new(0.01, 0.075, 0.003);
        let mut s = Shading::settled(a, 1000.0);
        assert_eq!(s.at(0.0).0.value(&x), a.value(&x));
        s.retarget(b, 2000.0, 0.0, 0.01);
        assert!((s.at(0.0).0.value(&x) - a.value(&x)).abs() < 1e-15);
        assert!((s.at(0.005).1 - 1500.0).abs() < 1e-9);
        // Interrupted at α = 0.6 by c: no jump at the switch.
        let before = s.at(0.006).0.value(&x);
        s.retarget(c, 3000.0, 0.006, 0.01);
        assert!((s.at(0.006).0.value(&x) - before).abs() < 1e-15);
        assert_eq!(s.at(0.007).0.terms().len(), 3);
        // Interrupted again: the oldest term folds; the jump is at most its
        // weight times the models' difference.
        let shown = s.at(0.008).0;
        let w0 = shown.terms()[0].1;
        s.retarget(a, 1000.0, 0.008, 0.01);
        let after = s.at(0.008).0;
        assert_eq!(after.terms().len(), 2);
        let jump = (after.value(&x) - shown.value(&x)).abs();
        assert!(jump <= w0 * (a.value(&x) - b.value(&x)).abs() + 1e-15);
        let w: f64 = after.terms().iter().map(|t| t.1).sum();
        assert!((w - 1.0).abs() < 1e-12);
        assert_eq!(s.at(0.02).0.value(&x), a.value(&x));
    }
}
