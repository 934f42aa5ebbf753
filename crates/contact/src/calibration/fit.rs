//! Fitting the tissue springs to a force–indentation curve with
//! Levenberg–Marquardt ([`crate::lm`]).
//!
//! Residuals: `r_i = F_model(d_i) − F_data(d_i)` (N) at the data's depths,
//! the model curve from the [`Indentation`] experiment interpolated
//! linearly between its steps. Parameters are fitted by their logarithms,
//! which keeps them positive and makes the finite-difference step relative;
//! the normal springs' asymptote is fitted as the fraction
//! `r = (normal_b/normal_a) / thigh.tissue_thickness ∈ (0, 1)` through its
//! logit, so that the model's domain bound (asymptote shorter than the
//! tissue) can be approached but never crossed by a trial point.

use crate::calibration::data::IndentationCurve;
use crate::calibration::indentation::Indentation;
use crate::calibration::CalibrationError;
use crate::lm::{levenberg_marquardt, LmOptions, Termination};
use crate::params::ContactParams;
use crate::probe::Probe;
use echothigh_model::{ModelConfig, TissueParams};

/// A tissue parameter the calibration may adjust.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitParameter {
    /// `tissue.normal_a`, m²/N (sets the asymptote `normal_b/normal_a`).
    NormalA,
    /// `tissue.normal_b`, m³/N (`1/normal_b`: initial stiffness per area).
    NormalB,
    /// `tissue.structural_stiffness`, N/m (membrane modulus).
    StructuralStiffness,
    /// `tissue.tangential_stiffness`, N/m³ (shear of the layer).
    TangentialStiffness,
    /// The normal springs' asymptote as a fraction of the tissue thickness,
    /// `(normal_b/normal_a)/thigh.tissue_thickness` (sets `normal_a` from
    /// `normal_b`; applied after the other parameters).
    Asymptote,
}

impl FitParameter {
    /// The configuration key, e.g. `tissue.normal_a`.
    pub fn key(&self) -> &'static str {
        match self {
            Self::NormalA => "tissue.normal_a",
            Self::NormalB => "tissue.normal_b",
            Self::StructuralStiffness => "tissue.structural_stiffness",
            Self::TangentialStiffness => "tissue.tangential_stiffness",
            Self::Asymptote => "tissue.normal_b / tissue.normal_a / thigh.tissue_thickness",
        }
    }

    /// The parameter's value in `m`.
    pub fn value(&self, m: &ModelConfig) -> f64 {
        match self {
            Self::Asymptote => m.tissue.asymptote() / m.thigh.tissue_thickness,
            p => p.get(&m.tissue),
        }
    }

    /// Sets the parameter's value in `m`.
    pub fn set_value(&self, m: &mut ModelConfig, v: f64) {
        match self {
            Self::Asymptote => {
                m.tissue.normal_a = m.tissue.normal_b / (v * m.thigh.tissue_thickness)
            }
            p => p.set(&mut m.tissue, v),
        }
    }

    /// The fitted coordinate of a value: `ln v`, or `logit v` for the
    /// asymptote fraction. A starting fraction near a bound is moved to
    /// [0.05, 0.95] first: at the bound the logit's derivative vanishes
    /// (`dv/dc = v(1 − v)`) and the fitter could never leave it.
    fn coordinate_of(&self, v: f64) -> f64 {
        match self {
            Self::Asymptote => {
                let v = v.clamp(0.05, 0.95);
                (v / (1.0 - v)).ln()
            }
            _ => v.ln(),
        }
    }

    /// The value of a fitted coordinate.
    fn value_at(&self, c: f64) -> f64 {
        match self {
            Self::Asymptote => 1.0 / (1.0 + (-c).exp()),
            _ => c.exp(),
        }
    }

    /// The parameter's value in `t` (for the asymptote: `normal_b/normal_a`, m).
    pub fn get(&self, t: &TissueParams) -> f64 {
        match self {
            Self::NormalA => t.normal_a,
            Self::NormalB => t.normal_b,
            Self::StructuralStiffness => t.structural_stiffness,
            Self::TangentialStiffness => t.tangential_stiffness,
            Self::Asymptote => t.normal_b / t.normal_a,
        }
    }

    /// Sets the parameter's value in `t` (for the asymptote, in m: sets
    /// `normal_a`).
    pub fn set(&self, t: &mut TissueParams, v: f64) {
        match self {
            Self::NormalA => t.normal_a = v,
            Self::NormalB => t.normal_b = v,
            Self::StructuralStiffness => t.structural_stiffness = v,
            Self::TangentialStiffness => t.tangential_stiffness = v,
            Self::Asymptote => t.normal_a = t.normal_b / v,
        }
    }
}

/// What to fit and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The model; its tissue parameters are the starting point.
    pub model: ModelConfig,
    /// The probe of the experiment.
    pub probe: Probe,
    /// The contact parameters.
    pub contact: ContactParams,
    /// The experiment (its `max_depth` is set to the data's last depth).
    pub experiment: Indentation,
    /// Parameters to adjust (default: `normal_b` and the asymptote fraction;
    /// `structural_stiffness` is held at its calibrated value, see
    /// `data/indentation-default.md`).
    pub parameters: Vec<FitParameter>,
    /// Fitter options.
    pub lm: LmOptions,
}

impl Default for Calibration {
    fn default() -> Self {
        Self {
            model: ModelConfig::default(),
            probe: Probe::default(),
            contact: ContactParams::default(),
            experiment: Indentation::default(),
            // The membrane's structural modulus is held: fitted too, it goes
            // to its lower bound (1 N/m, the default), where every trial
            // step below the bound is rejected and the fitter stalls.
            parameters: vec![FitParameter::NormalB, FitParameter::Asymptote],
            lm: LmOptions {
                max_iterations: 30,
                fd_step: 1e-4,
                cost_tolerance: 1e-10,
                step_tolerance: 1e-7,
                ..LmOptions::default()
            },
        }
    }
}

/// The fitted parameters and the quality of the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationReport {
    /// Each fitted parameter and its value.
    pub fitted: Vec<(FitParameter, f64)>,
    /// The tissue parameters with the fitted values in place.
    pub tissue: TissueParams,
    /// Root-mean-square force residual, N.
    pub rms: f64,
    /// Largest absolute force residual, N.
    pub max_abs: f64,
    /// The model's curve at the fitted parameters (every step).
    pub model_curve: IndentationCurve,
    /// Fitter iterations.
    pub iterations: usize,
    /// Experiments run.
    pub evaluations: usize,
    /// Why the fitter stopped.
    pub termination: Termination,
}

/// The model's force at the data's depths, N.
fn model_forces(
    cal: &Calibration,
    model: &ModelConfig,
    data: &IndentationCurve,
) -> Result<(IndentationCurve, Vec<f64>), CalibrationError> {
    let mut exp = cal.experiment;
    exp.max_depth = data.depth.last().copied().unwrap_or(0.0);
    let curve = exp.run(model, cal.probe, cal.contact)?;
    let f = data.depth.iter().map(|&d| curve.force_at(d)).collect();
    Ok((curve, f))
}

/// Fits `cal.parameters` so that the model's indentation curve matches `data`.
pub fn calibrate(
    cal: &Calibration,
    data: &IndentationCurve,
) -> Result<CalibrationReport, CalibrationError> {
    if cal.parameters.is_empty() {
        return Err(CalibrationError::Fit("no parameter to fit".into()));
    }
    // The asymptote fraction depends on normal_b: apply it last.
    let mut order: Vec<usize> = (0..cal.parameters.len()).collect();
    order.sort_by_key(|&i| cal.parameters[i] == FitParameter::Asymptote);
    let theta0: Vec<f64> = cal
        .parameters
        .iter()
        .map(|p| p.coordinate_of(p.value(&cal.model)))
        .collect();
    let model_at = |theta: &[f64]| {
        let mut m = cal.model.clone();
        for &i in &order {
            let p = cal.parameters[i];
            p.set_value(&mut m, p.value_at(theta[i]));
        }
        m
    };
    let residual = |theta: &[f64], r: &mut [f64]| -> Result<(), CalibrationError> {
        let m = model_at(theta);
        // A trial point outside the valid parameter domain is an uphill step.
        if m.validate("").is_err() {
            r.fill(f64::INFINITY);
            return Ok(());
        }
        match model_forces(cal, &m, data) {
            Ok((_, f)) => {
                for ((ri, fi), di) in r.iter_mut().zip(f).zip(&data.force) {
                    *ri = fi - di;
                }
                Ok(())
            }
            // A trial point where the tissue cannot reach the depth is an
            // uphill step for the fitter, not a failure of the fit.
            Err(CalibrationError::Diverged { .. }) => {
                r.fill(f64::INFINITY);
                Ok(())
            }
            Err(e) => Err(e),
        }
    };
    let rep = levenberg_marquardt(residual, &theta0, data.depth.len(), &cal.lm).map_err(|e| {
        CalibrationError::Fit(format!(
            "{e}: {}",
            std::error::Error::source(&e)
                .map(|s| s.to_string())
                .unwrap_or_default()
        ))
    })?;
    let model = model_at(&rep.params);
    let (model_curve, f) = model_forces(cal, &model, data)?;
    let max_abs = f
        .iter()
        .zip(&data.force)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    Ok(CalibrationReport {
        fitted: cal
            .parameters
            .iter()
            .map(|p| (*p, p.value(&model)))
            .collect(),
        rms: rep.rms(),
        max_abs,
        tissue: model.tissue.clone(),
        model_curve,
        iterations: rep.iterations,
        evaluations: rep.evaluations,
        termination: rep.termination,
    })
}
