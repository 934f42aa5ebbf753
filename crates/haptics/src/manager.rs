//! The model manager (paper §4): fits the buffer model's parameters `u` to
//! the distance `D`, its gradient `D' = ∇D` and the local stiffness `k` that
//! the physics reports at the probe position, and publishes `(u, k)`.
//!
//! # Algorithm
//! Gauss–Newton corrections `du = J⁺ [D − φ; D' − φ']` (paper's fitting
//! equations), iterated at each sample, with two changes to the paper:
//!
//! 1. `J⁺` is an SVD pseudo-inverse (minimum norm, truncated at
//!    `rcond · σ_max`), never `(JᵀJ)⁻¹Jᵀ`: for the sphere the 4×4 `J` at one
//!    sample has rank 3.
//! 2. The newest sample is *interpolated*: the correction solves its
//!    equations exactly in the range of its `J` (so `φ(p) = D` and
//!    `∇φ(p) = ∇D` at convergence, and the rendered force equals the physics
//!    force at every sample, DESIGN §2), and the directions it leaves free
//!    (its null space: for the sphere, the radius) are fitted by weighted
//!    least squares over a window of older samples, sample `a` updates old
//!    weighted `forgetting^a`. The window is reduced by Givens rotations into
//!    a 4×4 triangle, so nothing allocates after construction.
//!
//! In contact the physics reports `D = −|F·n|/k < 0` and `∇D` along the
//! contact force: the same equations then place the constraint surface at
//! distance `|D|` outside `p`, so no special case is needed. A sample that
//! would put the sphere's centre at or beyond `p` (radius smaller than
//! `|D|`), a radius outside `[min_radius, max_radius]`, or a non-finite
//! result re-seats the model exactly on the newest sample with a clamped
//! radius (`FitReport::reseated`).

use crate::buffer::{BufferModel, ModelPublisher};
use crate::config::{ConfigError, FitConfig, ModelKind};
use crate::local_model::{LocalModel, ModelParams, Params, Plane, Sphere};
use crate::lsq::{QrAccumulator, Svd4};
use crate::Vec3;

/// Residual at the newest sample beyond which the fit is re-seated, m.
const INTERPOLATION_TOLERANCE: f64 = 1e-9;

/// What the physics reports each step (DESIGN §2), in the haptic crate's terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// When the physics computed it, s (physics clock).
    pub time: f64,
    /// Probe reference point, m (thigh frame).
    pub p: Vec3,
    /// `D`, m: > 0 outside; in contact `D = −|F·n|/k`.
    pub distance: f64,
    /// `∇D` with respect to `p`, unit.
    pub gradient: Vec3,
    /// Local stiffness `k`, N/m.
    pub stiffness: f64,
}

/// Why a sample was rejected (the model is left unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SampleError {
    /// A field is NaN or infinite.
    #[error("sample field `{0}` is not finite")]
    NonFinite(&'static str),
    /// `k ≤ 0`.
    #[error("sample stiffness must be > 0")]
    NonPositiveStiffness,
    /// `|∇D|` is too far from 1 to be a distance gradient.
    #[error("sample gradient is not a unit vector")]
    BadGradient,
}

impl Sample {
    /// Checks the sample and returns it with a normalized gradient.
    pub fn checked(&self) -> Result<Sample, SampleError> {
        if !self.time.is_finite() {
            return Err(SampleError::NonFinite("time"));
        }
        if !self.p.iter().all(|v| v.is_finite()) {
            return Err(SampleError::NonFinite("p"));
        }
        if !self.distance.is_finite() {
            return Err(SampleError::NonFinite("distance"));
        }
        if !self.gradient.iter().all(|v| v.is_finite()) {
            return Err(SampleError::NonFinite("gradient"));
        }
        if !self.stiffness.is_finite() {
            return Err(SampleError::NonFinite("stiffness"));
        }
        if self.stiffness <= 0.0 {
            return Err(SampleError::NonPositiveStiffness);
        }
        let g = self.gradient.norm();
        if !(0.5..=2.0).contains(&g) {
            return Err(SampleError::BadGradient);
        }
        Ok(Sample {
            gradient: self.gradient / g,
            ..*self
        })
    }
}

/// Outcome of one `ModelManager::update`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FitReport {
    /// Why the sample was rejected, if it was (then nothing was published).
    pub rejected: Option<SampleError>,
    /// Gauss–Newton iterations taken.
    pub iterations: u32,
    /// `|[D − φ; w(D' − φ')]|` at the newest sample after the fit, m.
    pub residual: f64,
    /// Weighted RMS of the same residual over the whole window, m.
    pub window_residual: f64,
    /// Rank of the combined correction (newest sample + window null space).
    pub rank: u32,
    /// The last correction's norm fell below the tolerance.
    pub converged: bool,
    /// The model was re-seated on the newest sample (see module docs).
    pub reseated: bool,
    /// Sequence number published (0 if rejected).
    pub sequence: u64,
}

/// Fits and publishes the buffer model (paper §4, "model manager").
pub struct ModelManager {
    config: FitConfig,
    publisher: ModelPublisher,
    window: Vec<Sample>,
    head: usize,
    len: usize,
    model: Option<ModelParams>,
    published: BufferModel,
    period: f64,
    last_time: Option<f64>,
    acc: QrAccumulator,
}

impl ModelManager {
    /// A manager publishing through `publisher`; preallocates the window.
    pub fn new(config: &FitConfig, publisher: ModelPublisher) -> Result<Self, ConfigError> {
        config.validate("haptics.fit")?;
        Ok(ModelManager {
            config: config.clone(),
            publisher,
            window: Vec::with_capacity(config.window),
            head: 0,
            len: 0,
            model: None,
            published: BufferModel::none(),
            period: config.initial_period,
            last_time: None,
            acc: QrAccumulator::default(),
        })
    }

    /// The last published model (`BufferModel::none()` before the first sample).
    pub fn model(&self) -> BufferModel {
        self.published
    }

    /// The estimated physics period, s.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Forgets the window and the model (the next sample re-seats).
    pub fn reset(&mut self) {
        self.window.clear();
        self.head = 0;
        self.len = 0;
        self.model = None;
        self.last_time = None;
    }

    /// Takes one physics sample: fits `u` (see module docs) and publishes
    /// `(u, k)`. Allocation-free; never panics on bad input (rejects it).
    pub fn update(&mut self, sample: &Sample) -> FitReport {
        let s = match sample.checked() {
            Ok(s) => s,
            Err(e) => {
                return FitReport {
                    rejected: Some(e),
                    ..FitReport::default()
                }
            }
        };
        self.estimate_period(s.time);
        self.push(s);
        let mut report = FitReport::default();
        let mut model = match self.model {
            Some(m) => m,
            None => {
                report.reseated = true;
                self.seat(&s, self.config.initial_radius)
            }
        };
        let fallback_radius = match model {
            ModelParams::Sphere(sp) => sp.radius,
            ModelParams::Plane(_) => self.config.initial_radius,
        };
        for it in 0..self.config.max_iterations {
            report.iterations = it as u32 + 1;
            let Some((du, rank)) = self.correction(&model, &s) else {
                break;
            };
            report.rank = rank as u32;
            let mut du = du;
            let norm = du.norm();
            if norm > self.config.max_step {
                du *= self.config.max_step / norm;
            }
            model = model.with_params(&(model.params() + du));
            if norm <= self.config.tolerance {
                report.converged = true;
                break;
            }
        }
        // The newest sample is always satisfiable (module docs): a residual
        // left at it means Gauss–Newton failed (e.g. the step limit on a deep
        // contact), so re-seat, keeping the fitted radius when it is sane.
        let unfitted = self.residual(&model, &s).norm() > INTERPOLATION_TOLERANCE;
        if unfitted || !self.acceptable(&model, &s) {
            report.reseated = true;
            let radius = match model {
                ModelParams::Sphere(sp) if self.acceptable(&model, &s) => sp.radius,
                _ => fallback_radius,
            };
            model = self.seat(&s, radius);
        }
        self.model = Some(model);
        report.residual = self.residual(&model, &s).norm();
        report.window_residual = self.window_rms(&model);
        self.published = BufferModel {
            params: model,
            stiffness: s.stiffness,
            sample_time: s.time,
            period: self.period,
            sequence: self.published.sequence + 1,
        };
        self.publisher.publish(self.published);
        report.sequence = self.published.sequence;
        report
    }

    fn estimate_period(&mut self, t: f64) {
        if let Some(t0) = self.last_time {
            let dt = t - t0;
            if dt > 1e-5 && dt < 1.0 {
                self.period = 0.75 * self.period + 0.25 * dt;
            }
        }
        self.last_time = Some(t);
    }

    fn push(&mut self, s: Sample) {
        let cap = self.config.window;
        if self.window.len() < cap {
            self.window.push(s);
            self.head = self.window.len() - 1;
        } else {
            self.head = (self.head + 1) % cap;
            self.window[self.head] = s;
        }
        self.len = self.window.len();
    }

    /// The window's samples, newest first.
    fn newest_first(&self) -> impl Iterator<Item = &Sample> + '_ {
        let cap = self.window.len();
        (0..self.len).map(move |a| &self.window[(self.head + cap - a) % cap])
    }

    /// A model that interpolates `s` exactly: a sphere of radius `radius`
    /// (clamped so that its centre stays behind `p`) or the tangent plane.
    fn seat(&self, s: &Sample, radius: f64) -> ModelParams {
        match self.config.model {
            ModelKind::Sphere => {
                let r = radius
                    .clamp(self.config.min_radius, self.config.max_radius)
                    .max(self.config.min_radius - s.distance);
                ModelParams::Sphere(Sphere {
                    center: s.p - (s.distance + r) * s.gradient,
                    radius: r,
                })
            }
            ModelKind::Plane => ModelParams::Plane(Plane {
                normal: s.gradient,
                offset: s.gradient.dot(&s.p) - s.distance,
            }),
        }
    }

    fn acceptable(&self, m: &ModelParams, s: &Sample) -> bool {
        if !m.is_valid() {
            return false;
        }
        match m {
            ModelParams::Sphere(sp) => {
                sp.radius >= self.config.min_radius
                    && sp.radius <= self.config.max_radius
                    && (s.p - sp.center).norm() >= self.config.min_radius
            }
            ModelParams::Plane(_) => true,
        }
    }

    /// Residual `[D − φ; w(D' − φ')]` of sample `s` under model `m`.
    fn residual(&self, m: &ModelParams, s: &Sample) -> Params {
        let w = self.config.gradient_weight;
        let g = (s.gradient - m.gradient(&s.p)) * w;
        Params::new(s.distance - m.value(&s.p), g.x, g.y, g.z)
    }

    /// `J = [∂φ/∂u; w ∂φ'/∂u]` of sample `s` under model `m` (rows).
    fn jacobian(&self, m: &ModelParams, s: &Sample) -> nalgebra::Matrix4<f64> {
        let mut j = nalgebra::Matrix4::zeros();
        j.row_mut(0).copy_from(&m.value_du(&s.p).transpose());
        j.fixed_view_mut::<3, 4>(1, 0)
            .copy_from(&(m.gradient_du(&s.p) * self.config.gradient_weight));
        j
    }

    /// One Gauss–Newton correction and its rank (see module docs).
    fn correction(&mut self, m: &ModelParams, newest: &Sample) -> Option<(Params, usize)> {
        let svd = Svd4::new(&self.jacobian(m, newest), self.config.rcond)?;
        let y_range = svd.solve_coords(&self.residual(m, newest));
        let rank_newest = svd.rank();
        let mut rank_window = 0;
        let mut y = y_range;
        if rank_newest < 4 && self.len > 1 {
            self.acc.clear();
            let lambda = self.config.forgetting;
            let mut weight = 1.0;
            for a in 1..self.len {
                weight *= lambda;
                let cap = self.window.len();
                let s = self.window[(self.head + cap - a) % cap];
                let (j, r) = (self.jacobian(m, &s), self.residual(m, &s));
                let sw = weight.sqrt();
                for row in 0..4 {
                    // Row in the right-singular basis; range coordinates are fixed.
                    let mut a_v = svd.v_t * j.row(row).transpose();
                    let mut rhs = r[row];
                    for i in 0..4 {
                        if svd.in_range(i) {
                            rhs -= a_v[i] * y_range[i];
                            a_v[i] = 0.0;
                        }
                    }
                    self.acc.add_row(&(a_v * sw), rhs * sw);
                }
            }
            // Rank is judged on the scale of the full Jacobian, not of the
            // (possibly tiny) reduced window rows.
            let floor = self.config.rcond * svd.sigma.max();
            let (z, rank) = self.acc.solve(self.config.rcond, floor)?;
            rank_window = rank;
            for i in 0..4 {
                if !svd.in_range(i) {
                    y[i] = z[i];
                }
            }
        }
        let du = svd.v_t.tr_mul(&y);
        du.iter()
            .all(|v| v.is_finite())
            .then_some((du, rank_newest + rank_window))
    }

    fn window_rms(&self, m: &ModelParams) -> f64 {
        let (mut sum, mut wsum, mut w) = (0.0, 0.0, 1.0);
        for s in self.newest_first() {
            sum += w * self.residual(m, s).norm_squared();
            wsum += w;
            w *= self.config.forgetting;
        }
        if wsum > 0.0 {
            (sum / wsum).sqrt()
        } else {
            0.0
        }
    }
}
