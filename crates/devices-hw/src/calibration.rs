//! The calibrated transform from a device's frame to the leg (thigh) frame,
//! and its least-squares fit from touched landmarks.
//!
//! `p_leg = R p_device + t`: a rigid motion (positions are not scaled, so the
//! stiffness felt is the rendered one; a small workspace covers the leg by
//! clutching). `R` is stored as a rotation vector (axis × angle, rad) and `t`
//! in m, both in the scenario's `[device.calibration]`.

use crate::Vec3;
use echothigh_device::ConfigError;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// Device → leg rigid transform (`[device.calibration]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeviceToLeg {
    /// Rotation leg ← device as a rotation vector (axis × angle, rad). Default 0 (axes aligned).
    pub rotation: [f64; 3],
    /// Position of the device's origin in the leg frame (m). Default (0, 0.1, 0):
    /// the stylus's home 10 cm anterior of the thigh's axis at mid-thigh, above the skin.
    pub translation: [f64; 3],
}

impl Default for DeviceToLeg {
    fn default() -> Self {
        DeviceToLeg {
            rotation: [0.0; 3],
            translation: [0.0, 0.1, 0.0],
        }
    }
}

/// Farthest a device origin may be placed from the leg (m): a desk's reach.
const MAX_TRANSLATION: f64 = 5.0;

impl DeviceToLeg {
    /// The transform as an isometry (leg ← device).
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(Vec3::from(self.translation)),
            UnitQuaternion::from_scaled_axis(Vec3::from(self.rotation)),
        )
    }

    /// The rotation leg ← device.
    pub fn rotation(&self) -> Rotation3<f64> {
        Rotation3::from_scaled_axis(Vec3::from(self.rotation))
    }

    /// From an isometry (leg ← device).
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        DeviceToLeg {
            rotation: iso.rotation.scaled_axis().into(),
            translation: iso.translation.vector.into(),
        }
    }

    /// Checks every component is finite and the origin within 5 m of the leg,
    /// naming the key as `"{prefix}.rotation"` / `"{prefix}.translation"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        ConfigError::finite3(prefix, "rotation", self.rotation)?;
        if !self
            .translation
            .iter()
            .all(|t| t.is_finite() && t.abs() <= MAX_TRANSLATION)
        {
            return Err(ConfigError::invalid(
                prefix,
                "translation",
                format!("{:?}", self.translation),
                "components must be finite and within ±5 m",
            ));
        }
        Ok(())
    }
}

/// The result of a landmark fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandmarkFit {
    /// The least-squares transform.
    pub transform: DeviceToLeg,
    /// Root-mean-square distance between mapped device points and leg landmarks (m).
    pub rms_residual: f64,
    /// Largest such distance (m).
    pub max_residual: f64,
}

/// Why a landmark fit failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    /// The two lists differ in length or hold fewer than 3 points.
    #[error("landmark fit needs at least 3 pairs of points in both lists (got {device} device and {leg} leg points)")]
    Count {
        /// Device points given.
        device: usize,
        /// Leg points given.
        leg: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("landmark {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the offending pair.
        index: usize,
    },
    /// The landmarks are (nearly) collinear: the rotation about their line is undetermined.
    #[error("landmarks are collinear or coincident (second singular value {sigma:.3e} m² of the spread): touch three points that span a triangle")]
    Degenerate {
        /// Second singular value of the cross-covariance.
        sigma: f64,
    },
}

/// Least-squares rigid fit `leg ≈ R device + t` (Kabsch 1976, "A solution
/// for the best rotation to relate two sets of vectors", Acta Cryst. A32;
/// with Umeyama's 1991 reflection correction, IEEE T-PAMI 13(4)): centre both
/// sets, SVD of the cross-covariance `H = Σ d_i l_iᵀ`, `R = V diag(1, 1,
/// sign det(V Uᵀ)) Uᵀ`, `t = l̄ − R d̄`. Positions in m.
pub fn fit_landmarks(device: &[Vec3], leg: &[Vec3]) -> Result<LandmarkFit, CalibrationError> {
    if device.len() != leg.len() || device.len() < 3 {
        return Err(CalibrationError::Count {
            device: device.len(),
            leg: leg.len(),
        });
    }
    for (index, (d, l)) in device.iter().zip(leg).enumerate() {
        if !(d.iter().chain(l.iter()).all(|c| c.is_finite())) {
            return Err(CalibrationError::NonFinite { index });
        }
    }
    let n = device.len() as f64;
    let dc = device.iter().sum::<Vec3>() / n;
    let lc = leg.iter().sum::<Vec3>() / n;
    let mut h = Matrix3::zeros();
    for (d, l) in device.iter().zip(leg) {
        h += (d - dc) * (l - lc).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(CalibrationError::Degenerate { sigma: 0.0 });
    };
    let mut sigmas: Vec<f64> = svd.singular_values.iter().copied().collect();
    sigmas.sort_by(|a, b| b.total_cmp(a));
    // Collinear points leave two singular values at zero: relative to the
    // largest, 1e-9 is far below any physical spread (1 µm over 1 m).
    if sigmas[1] <= 1e-9 * sigmas[0].max(f64::MIN_POSITIVE) {
        return Err(CalibrationError::Degenerate { sigma: sigmas[1] });
    }
    let v = v_t.transpose();
    let mut correction = Matrix3::identity();
    correction[(2, 2)] = (v * u.transpose()).determinant().signum();
    let r = Rotation3::from_matrix_unchecked(v * correction * u.transpose());
    let t = lc - r * dc;
    let iso = Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_rotation_matrix(&r),
    );
    let mut sum = 0.0;
    let mut max: f64 = 0.0;
    for (d, l) in device.iter().zip(leg) {
        let e = (iso * nalgebra::Point3::from(*d)).coords - l;
        sum += e.norm_squared();
        max = max.max(e.norm());
    }
    Ok(LandmarkFit {
        transform: DeviceToLeg::from_isometry(&iso),
        rms_residual: (sum / n).sqrt(),
        max_residual: max,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_known_transform_exactly() {
        let truth = DeviceToLeg {
            rotation: [0.3, -1.1, 0.7],
            translation: [0.02, 0.15, -0.3],
        };
        let iso = truth.isometry();
        let device = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.08, 0.0, 0.0),
            Vec3::new(0.0, 0.05, 0.01),
            Vec3::new(-0.03, 0.02, 0.06),
        ];
        let leg: Vec<Vec3> = device
            .iter()
            .map(|d| (iso * nalgebra::Point3::from(*d)).coords)
            .collect();
        let fit = fit_landmarks(&device, &leg).unwrap();
        // Exact data: the residual is round-off, ~1e-16 m × condition; 1e-12 m is 4 orders above.
        assert!(fit.rms_residual < 1e-12, "{}", fit.rms_residual);
        let got = fit.transform.isometry();
        assert!((got.translation.vector - iso.translation.vector).norm() < 1e-12);
        assert!(got.rotation.angle_to(&iso.rotation) < 1e-12);
    }

    #[test]
    fn fit_refuses_collinear_and_short_input() {
        let line: Vec<Vec3> = (0..4)
            .map(|i| Vec3::new(0.01 * i as f64, 0.0, 0.0))
            .collect();
        assert!(matches!(
            fit_landmarks(&line, &line),
            Err(CalibrationError::Degenerate { .. })
        ));
        assert!(matches!(
            fit_landmarks(&line[..2], &line[..2]),
            Err(CalibrationError::Count { .. })
        ));
        let mut bad = line.clone();
        bad[0].x = f64::NAN;
        assert!(matches!(
            fit_landmarks(&bad, &line),
            Err(CalibrationError::NonFinite { index: 0 })
        ));
    }

    #[test]
    fn validation_names_the_key() {
        let mut c = DeviceToLeg::default();
        c.translation[1] = 7.0;
        let e = c.validate("device.calibration").unwrap_err().to_string();
        assert!(e.contains("device.calibration.translation"), "{e}");
        c.translation[1] = 0.0;
        c.rotation[2] = f64::NAN;
        assert!(c.validate("device.calibration").is_err());
    }
}
