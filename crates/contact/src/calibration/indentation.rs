//! The indentation experiment (as the paper's ref. [4] measured a real
//! thigh): the flat probe, face normal along the inward skin normal, is
//! pressed into the thigh from first contact at a slow constant rate, and
//! the normal force on the probe is recorded against the depth.
//!
//! The experiment is the physics itself: [`ProbeContact::advance`] steps of
//! `time_step` with the probe moving `rate · time_step` per step. At the
//! default 5 mm/s with 50 ms steps the tissue's dampers carry a negligible
//! part of the force (the normal damper gives `2000 N·s/m³ × 4·10⁻⁴ m² ×
//! 5·10⁻³ m/s = 4 mN` under the face), so the curve is quasi-static, as a
//! slow clinical indentation.

use crate::calibration::data::IndentationCurve;
use crate::calibration::CalibrationError;
use crate::driver::ProbeContact;
use crate::params::ContactParams;
use crate::probe::Probe;
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

/// Settings of the indentation experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Indentation {
    /// Final depth past first contact, m (default 0.020).
    pub max_depth: f64,
    /// Indentation rate, m/s (default 0.005).
    pub rate: f64,
    /// Physics step, s (default 0.05).
    pub time_step: f64,
    /// Angle θ of the indentation site on the cross-section, rad (default
    /// π/2: the anterior line, the default exam site).
    pub theta: f64,
    /// Axial position of the site, m (default 0: mid-thigh).
    pub z: f64,
}

impl Default for Indentation {
    fn default() -> Self {
        Self {
            max_depth: 0.020,
            rate: 0.005,
            time_step: 0.05,
            theta: std::f64::consts::FRAC_PI_2,
            z: 0.0,
        }
    }
}

impl Indentation {
    /// Runs the experiment on a fresh model built from `config` and returns
    /// the force–depth record, one point per step (depth in m, force in N).
    pub fn run(
        &self,
        config: &ModelConfig,
        probe: Probe,
        contact: ContactParams,
    ) -> Result<IndentationCurve, CalibrationError> {
        let mut model =
            ThighModel::new(config).map_err(|e| CalibrationError::Model(e.to_string()))?;
        let mut pc =
            ProbeContact::new(&model, probe, contact).map_err(CalibrationError::Contact)?;
        let g = &config.thigh;
        let s = g.surface_point(self.theta, self.z);
        let n = g.surface_normal(self.theta);
        let normal = Vec3::new(n[0], n[1], n[2]);
        // Local −y along −normal: rotate the exam pose about z.
        let rot = UnitQuaternion::from_axis_angle(
            &Vec3::z_axis(),
            self.theta - std::f64::consts::FRAC_PI_2,
        );
        let start = Vec3::new(s[0], s[1], s[2]) + 0.01 * normal;
        let pose0 = Isometry3::from_parts(Translation3::from(start), rot);
        let gap = pc
            .gap_along_normal(&model, &pose0, 0.05)
            .ok_or(CalibrationError::NoSurface)?;
        let touch = start - gap * normal;
        let steps = (self.max_depth / (self.rate * self.time_step)).ceil() as usize;
        let mut curve = IndentationCurve {
            depth: Vec::with_capacity(steps + 1),
            force: Vec::with_capacity(steps + 1),
        };
        curve.depth.push(0.0);
        curve.force.push(0.0);
        for i in 1..=steps {
            let depth = (self.rate * self.time_step * i as f64).min(self.max_depth);
            let pose = Isometry3::from_parts(Translation3::from(touch - depth * normal), rot);
            let (stats, wrench) = pc.advance(&mut model, &pose, self.time_step);
            let force = wrench.force.dot(&normal);
            if !stats.finite || !force.is_finite() {
                return Err(CalibrationError::Diverged { depth });
            }
            curve.depth.push(depth);
            curve.force.push(force);
        }
        Ok(curve)
    }
}
