//! Levenberg–Marquardt least squares, generic over a residual function, with
//! a finite-difference Jacobian (used by the calibration, as the paper's
//! ref. [4] fitted its spring parameters to measurements).
//!
//! Minimizes `S(θ) = ½ Σ rᵢ(θ)²`. Each iteration solves the damped normal
//! equations with Marquardt's scaling
//!
//! `(JᵀJ + μ diag(JᵀJ)) δ = −Jᵀr`,
//!
//! accepts `θ + δ` if it lowers `S` (then `μ ← μ/3`), otherwise raises
//! `μ ← 4μ` and retries. The Jacobian is approximated by finite differences,
//! forward (`n` evaluations) or central (`2n`, second-order accurate), with a
//! step `ε · max(|θⱼ|, 1)`: the residuals of the calibration come from an
//! iterative solver, so `ε` must stay well above its tolerance (default
//! `1e-5`) rather than at `√machine-ε`. A trial point outside the residual's
//! domain returns non-finite residuals: it is rejected like an uphill step,
//! and a Jacobian column whose forward point is outside the domain is taken
//! by a backward difference instead (a fit that starts on a bound).

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

/// Options of [`levenberg_marquardt`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Maximum number of accepted-or-rejected iterations (default 50).
    pub max_iterations: usize,
    /// Initial Marquardt damping `μ` (default 1e-3).
    pub initial_damping: f64,
    /// Stop when the step is below `step_tolerance · (|θ| + step_tolerance)`
    /// (default 1e-8).
    pub step_tolerance: f64,
    /// Stop when the relative decrease of `S` in an accepted step is below
    /// this (default 1e-12).
    pub cost_tolerance: f64,
    /// Stop when `S` is below this absolute value (default 0).
    pub cost_floor: f64,
    /// Relative finite-difference step `ε` (default 1e-5).
    pub fd_step: f64,
    /// Central (true) or forward (false, default) differences.
    pub central: bool,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            initial_damping: 1e-3,
            step_tolerance: 1e-8,
            cost_tolerance: 1e-12,
            cost_floor: 0.0,
            fd_step: 1e-5,
            central: false,
        }
    }
}

/// Why the fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// The step became negligible.
    SmallStep,
    /// The cost stopped decreasing.
    SmallCostDecrease,
    /// The cost fell below the floor.
    CostFloor,
    /// The iteration cap was reached.
    MaxIterations,
}

/// Result of a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LmReport {
    /// Fitted parameters.
    pub params: Vec<f64>,
    /// Residuals at the fitted parameters.
    pub residuals: Vec<f64>,
    /// Final cost `½ Σ r²`.
    pub cost: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Residual evaluations, Jacobian columns included.
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
}

impl LmReport {
    /// Root-mean-square residual, in the residuals' unit.
    pub fn rms(&self) -> f64 {
        (2.0 * self.cost / self.residuals.len().max(1) as f64).sqrt()
    }
}

/// Failure of a fit.
#[derive(Debug, Error)]
pub enum LmError<E: std::error::Error + 'static> {
    /// The residual function failed.
    #[error("residual evaluation failed at parameters {params:?}")]
    Residual {
        /// Parameters at which it failed.
        params: Vec<f64>,
        /// The underlying error.
        #[source]
        source: E,
    },
    /// The residuals at the starting point are not finite.
    #[error("non-finite residual at the starting parameters {0:?}")]
    NonFiniteStart(Vec<f64>),
    /// More parameters than residuals, or none.
    #[error("ill-posed problem: {params} parameters, {residuals} residuals")]
    IllPosed {
        /// Number of parameters.
        params: usize,
        /// Number of residuals.
        residuals: usize,
    },
}

fn cost(r: &DVector<f64>) -> f64 {
    let c = 0.5 * r.norm_squared();
    if c.is_finite() {
        c
    } else {
        f64::INFINITY
    }
}

/// Fits `θ` (starting at `theta0`) so that the `m` residuals written by
/// `residual(θ, r)` are least in the squares sense. A residual evaluation that
/// returns an error at a trial point is an error of the fit; a trial point
/// with non-finite residuals is rejected like an uphill step.
pub fn levenberg_marquardt<E, F>(
    mut residual: F,
    theta0: &[f64],
    m: usize,
    opts: &LmOptions,
) -> Result<LmReport, LmError<E>>
where
    E: std::error::Error + 'static,
    F: FnMut(&[f64], &mut [f64]) -> Result<(), E>,
{
    let n = theta0.len();
    if n == 0 || m < n {
        return Err(LmError::IllPosed {
            params: n,
            residuals: m,
        });
    }
    let mut evals = 0usize;
    let mut eval = |th: &DVector<f64>, out: &mut DVector<f64>| {
        evals += 1;
        residual(th.as_slice(), out.as_mut_slice()).map_err(|source| LmError::Residual {
            params: th.as_slice().to_vec(),
            source,
        })
    };
    let mut theta = DVector::from_column_slice(theta0);
    let mut r = DVector::zeros(m);
    eval(&theta, &mut r)?;
    let mut s = cost(&r);
    if !s.is_finite() {
        return Err(LmError::NonFiniteStart(theta0.to_vec()));
    }
    let mut mu = opts.initial_damping;
    let mut jac = DMatrix::zeros(m, n);
    let (mut rp, mut rm, mut r_trial) = (DVector::zeros(m), DVector::zeros(m), DVector::zeros(m));
    let mut need_jacobian = true;
    let mut termination = Termination::MaxIterations;
    let mut iterations = 0;
    while iterations < opts.max_iterations {
        if s <= opts.cost_floor {
            termination = Termination::CostFloor;
            break;
        }
        iterations += 1;
        if need_jacobian {
            for j in 0..n {
                let hj = opts.fd_step * theta[j].abs().max(1.0);
                let mut tp = theta.clone();
                tp[j] += hj;
                eval(&tp, &mut rp)?;
                let forward_ok = rp.iter().all(|v| v.is_finite());
                if opts.central || !forward_ok {
                    let mut tm = theta.clone();
                    tm[j] -= hj;
                    eval(&tm, &mut rm)?;
                    let backward_ok = rm.iter().all(|v| v.is_finite());
                    let col = match (forward_ok, backward_ok) {
                        (true, true) => (&rp - &rm) / (2.0 * hj),
                        (true, false) => (&rp - &r) / hj,
                        (false, true) => (&r - &rm) / hj,
                        // Both neighbours outside the domain: no information.
                        (false, false) => DVector::zeros(m),
                    };
                    jac.set_column(j, &col);
                } else {
                    jac.set_column(j, &((&rp - &r) / hj));
                }
            }
            need_jacobian = false;
        }
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * &r;
        let mut a = jtj.clone();
        for j in 0..n {
            a[(j, j)] += mu * jtj[(j, j)].max(1e-300);
        }
        let Some(chol) = a.cholesky() else {
            mu *= 4.0;
            continue;
        };
        let delta = -chol.solve(&g);
        let trial = &theta + &delta;
        eval(&trial, &mut r_trial)?;
        let s_trial = cost(&r_trial);
        if s_trial < s {
            let decrease = (s - s_trial) / s.max(f64::MIN_POSITIVE);
            let small_step =
                delta.norm() <= opts.step_tolerance * (theta.norm() + opts.step_tolerance);
            theta = trial;
            std::mem::swap(&mut r, &mut r_trial);
            s = s_trial;
            mu = (mu / 3.0).max(1e-12);
            need_jacobian = true;
            if small_step {
                termination = Termination::SmallStep;
                break;
            }
            if decrease < opts.cost_tolerance {
                termination = Termination::SmallCostDecrease;
                break;
            }
        } else {
            if delta.norm() <= opts.step_tolerance * (theta.norm() + opts.step_tolerance) {
                termination = Termination::SmallStep;
                break;
            }
            mu *= 4.0;
        }
    }
    Ok(LmReport {
        params: theta.as_slice().to_vec(),
        residuals: r.as_slice().to_vec(),
        cost: s,
        iterations,
        evaluations: evals,
        termination,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    #[test]
    fn recovers_exponential_decay_parameters() {
        // y = A exp(−k t) + c sampled without noise: LM must recover (A, k, c).
        let truth = [2.5, 1.3, 0.4];
        let t: Vec<f64> = (0..30).map(|i| 0.1 * i as f64).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| truth[0] * (-truth[1] * t).exp() + truth[2])
            .collect();
        let f = |th: &[f64], r: &mut [f64]| -> Result<(), Infallible> {
            for i in 0..t.len() {
                r[i] = th[0] * (-th[1] * t[i]).exp() + th[2] - y[i];
            }
            Ok(())
        };
        for central in [false, true] {
            let opts = LmOptions {
                central,
                fd_step: 1e-7,
                ..LmOptions::default()
            };
            let rep = levenberg_marquardt(f, &[1.0, 0.5, 0.0], t.len(), &opts).unwrap();
            for (p, q) in rep.params.iter().zip(truth) {
                assert!((p - q).abs() < 1e-6, "{:?}", rep);
            }
            assert!(rep.rms() < 1e-8);
        }
    }

    #[test]
    fn rosenbrock_minimum() {
        // Rosenbrock as residuals (10(y − x²), 1 − x): minimum at (1, 1).
        let f = |th: &[f64], r: &mut [f64]| -> Result<(), Infallible> {
            r[0] = 10.0 * (th[1] - th[0] * th[0]);
            r[1] = 1.0 - th[0];
            Ok(())
        };
        let opts = LmOptions {
            max_iterations: 200,
            central: true,
            fd_step: 1e-6,
            ..LmOptions::default()
        };
        let rep = levenberg_marquardt(f, &[-1.2, 1.0], 2, &opts).unwrap();
        assert!(
            (rep.params[0] - 1.0).abs() < 1e-6 && (rep.params[1] - 1.0).abs() < 1e-6,
            "{rep:?}"
        );
    }

    #[test]
    fn ill_posed_is_an_error() {
        let f = |_: &[f64], _: &mut [f64]| -> Result<(), Infallible> { Ok(()) };
        assert!(matches!(
            levenberg_marquardt(f, &[1.0, 2.0], 1, &LmOptions::default()),
            Err(LmError::IllPosed { .. })
        ));
    }
}
