//! Device limits per model (with sources), the force ramp-in, the
//! continuous-force (thermal) limiter and the clutch.

use crate::Vec3;
use serde::Serialize;

/// Force and stiffness limits of one device model (SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModelLimits {
    /// Model name as the SDK reports it.
    pub model: &'static str,
    /// Peak force (N).
    pub peak_force: f64,
    /// Continuous force (N), sustained without overheating.
    pub continuous_force: f64,
    /// Largest stiffness rendered stably at the servo rate (N/m).
    pub max_stiffness: f64,
    /// Where the numbers come from.
    pub source: &'static str,
}

/// The documented limits table. Stiffness is the manufacturer's nominal
/// value on the weakest axis.
pub const LIMITS: &[ModelLimits] = &[
    ModelLimits {
        model: "Touch",
        peak_force: 3.3,
        continuous_force: 0.88,
        max_stiffness: 1020.0,
        source: "3D Systems Touch specifications: 3.3 N peak, 0.88 N continuous, stiffness x 1.26 / y 2.31 / z 1.02 N/mm",
    },
    ModelLimits {
        model: "Touch X",
        peak_force: 7.9,
        continuous_force: 1.75,
        max_stiffness: 1480.0,
        source: "3D Systems Touch X specifications: 7.9 N peak, 1.75 N continuous, stiffness x 1.86 / y 2.35 / z 1.48 N/mm",
    },
    ModelLimits {
        model: "PHANTOM Premium 1.5",
        peak_force: 8.5,
        continuous_force: 1.4,
        max_stiffness: 3500.0,
        source: "SensAble PHANTOM Premium 1.5 specifications: 8.5 N peak, 1.4 N continuous, 3.5 N/mm",
    },
    ModelLimits {
        model: "omega.3",
        peak_force: 12.0,
        continuous_force: 12.0,
        max_stiffness: 14_500.0,
        source: "Force Dimension omega.3/6/7 specifications: 12 N continuous, 14.5 N/mm closed-loop stiffness",
    },
    ModelLimits {
        model: "omega.6",
        peak_force: 12.0,
        continuous_force: 12.0,
        max_stiffness: 14_500.0,
        source: "Force Dimension omega.3/6/7 specifications: 12 N continuous, 14.5 N/mm closed-loop stiffness",
    },
    ModelLimits {
        model: "omega.7",
        peak_force: 12.0,
        continuous_force: 12.0,
        max_stiffness: 14_500.0,
        source: "Force Dimension omega.3/6/7 specifications: 12 N continuous, 14.5 N/mm closed-loop stiffness",
    },
];

/// Limits used for a model absent from [`LIMITS`] and not reported by its
/// SDK: those of the weakest device in the table (the Touch), so that no
/// unknown device is driven beyond what a known one safely renders.
pub const UNKNOWN_MODEL: ModelLimits = ModelLimits {
    model: "unknown",
    peak_force: 3.3,
    continuous_force: 0.88,
    max_stiffness: 1020.0,
    source: "model not in the table: the Touch's limits (the weakest listed device)",
};

impl ModelLimits {
    /// The table's entry for `model` (case-insensitive), or [`UNKNOWN_MODEL`].
    pub fn for_model(model: &str) -> ModelLimits {
        LIMITS
            .iter()
            .find(|l| l.model.eq_ignore_ascii_case(model.trim()))
            .copied()
            .unwrap_or(UNKNOWN_MODEL)
    }

    /// The tighter of these limits and the ones an SDK reports (N, N, N/m);
    /// non-finite or non-positive reported values are ignored.
    pub fn tightened(self, peak: f64, continuous: f64, stiffness: f64) -> ModelLimits {
        let tighter = |table: f64, sdk: f64| {
            if sdk.is_finite() && sdk > 0.0 {
                table.min(sdk)
            } else {
                table
            }
        };
        ModelLimits {
            peak_force: tighter(self.peak_force, peak),
            continuous_force: tighter(self.continuous_force, continuous),
            max_stiffness: tighter(self.max_stiffness, stiffness),
            ..self
        }
    }
}

/// Linear force ramp-in: gain `min(1, (t − t₀) / T)` from a (re)start at `t₀`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceRamp {
    duration: f64,
    elapsed: f64,
}

impl ForceRamp {
    /// A ramp of `duration` s, starting now.
    pub fn new(duration: f64) -> Self {
        ForceRamp {
            duration,
            elapsed: 0.0,
        }
    }
    /// Restarts from zero gain (start, re-engaging after a clutch).
    pub fn restart(&mut self) {
        self.elapsed = 0.0;
    }
    /// Advances by `dt` s.
    pub fn advance(&mut self, dt: f64) {
        self.elapsed += dt;
    }
    /// The gain in [0, 1].
    pub fn gain(&self) -> f64 {
        if self.duration <= 0.0 {
            1.0
        } else {
            (self.elapsed / self.duration).clamp(0.0, 1.0)
        }
    }
}

/// Continuous-force limiter: a first-order thermal model of the motors.
///
/// Heating goes as current², i.e. force²; the filtered mean square
/// `m ← m + (|F|² − m) dt / τ` stands for the winding temperature rise. The
/// allowed force falls linearly with it from the peak (cold, `m = 0`) to the
/// continuous force (`m ≥ F_c²`): `F_c + (F_peak − F_c) max(0, 1 − m / F_c²)`,
/// so a sustained overload settles at exactly `F_c` (the fixed point
/// `F² = m = F_c²`). τ defaults to 10 s (winding thermal time constants of
/// the small DC motors of desktop devices are 10–40 s, Maxon RE-series data
/// sheets); the shortest keeps the limiter on the safe side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalLimiter {
    peak: f64,
    continuous: f64,
    tau: f64,
    mean_square: f64,
}

impl ThermalLimiter {
    /// Default thermal time constant (s).
    pub const DEFAULT_TAU: f64 = 10.0;

    /// A cold limiter for the given peak and continuous forces (N).
    pub fn new(peak: f64, continuous: f64, tau: f64) -> Self {
        ThermalLimiter {
            peak,
            continuous,
            tau,
            mean_square: 0.0,
        }
    }

    /// The force (N) allowed now.
    pub fn allowed(&self) -> f64 {
        let c2 = self.continuous * self.continuous;
        let cold = (1.0 - self.mean_square / c2).max(0.0);
        self.continuous + (self.peak - self.continuous).max(0.0) * cold
    }

    /// Limits `force` to [`allowed`](Self::allowed) (direction kept) and
    /// accounts `dt` s of rendering it.
    pub fn limit(&mut self, force: Vec3, dt: f64) -> Vec3 {
        let allowed = self.allowed();
        let n = force.norm();
        let out = if n > allowed {
            force * (allowed / n)
        } else {
            force
        };
        self.mean_square += (out.norm_squared() - self.mean_square) * (dt / self.tau).min(1.0);
        out
    }
}

/// Clutch: while engaged the probe stays where it was and the force is
/// zero; on release the device → leg offset absorbs the hand's
/// repositioning, so the probe does not jump.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clutch {
    engaged: bool,
    held: Vec3,
    offset: Vec3,
}

impl Default for Clutch {
    fn default() -> Self {
        Clutch {
            engaged: false,
            held: Vec3::zeros(),
            offset: Vec3::zeros(),
        }
    }
}

impl Clutch {
    /// Updates with the button state and the calibrated (un-offset) leg
    /// position (m) of the device. Returns `true` when the clutch was just
    /// released (the caller restarts its force ramp).
    pub fn update(&mut self, pressed: bool, calibrated: Vec3) -> bool {
        match (self.engaged, pressed) {
            (false, true) => {
                self.held = calibrated + self.offset;
                self.engaged = true;
                false
            }
            (true, false) => {
                self.offset = self.held - calibrated;
                self.engaged = false;
                true
            }
            _ => false,
        }
    }
    /// Whether the clutch is engaged (force zero, probe held).
    pub fn engaged(&self) -> bool {
        self.engaged
    }
    /// The probe position (m, leg frame) for a calibrated device position.
    pub fn probe(&self, calibrated: Vec3) -> Vec3 {
        if self.engaged {
            self.held
        } else {
            calibrated + self.offset
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_linear_over_its_duration() {
        let mut r = ForceRamp::new(0.5);
        assert_eq!(r.gain(), 0.0);
        r.advance(0.125);
        assert!((r.gain() - 0.25).abs() < 1e-15);
        r.advance(1.0);
        assert_eq!(r.gain(), 1.0);
        r.restart();
        assert_eq!(r.gain(), 0.0);
    }

    #[test]
    fn thermal_limiter_settles_at_the_continuous_force() {
        // A sustained 10 N command on a 3.3 N / 0.88 N device: the peak while
        // cold, then the fixed point F² = m = F_c², i.e. F = 0.88 N.
        let mut t = ThermalLimiter::new(3.3, 0.88, 10.0);
        let cmd = Vec3::new(0.0, 10.0, 0.0);
        assert!((t.limit(cmd, 1e-3).norm() - 3.3).abs() < 1e-12);
        for _ in 0..200_000 {
            t.limit(cmd, 1e-3);
        }
        let expected = 0.88;
        // 200 s = 20 τ: the transient has decayed by e^-20 and the fixed point is stable.
        assert!(
            (t.limit(cmd, 1e-3).norm() - expected).abs() < 1e-3,
            "{}",
            t.allowed()
        );
    }

    #[test]
    fn clutch_holds_the_probe_and_reengages_without_a_jump() {
        let mut c = Clutch::default();
        let p0 = Vec3::new(0.0, 0.1, 0.0);
        assert!(!c.update(false, p0));
        assert!(!c.update(true, p0));
        // The hand moves the device 5 cm along z while clutched: the probe stays.
        let moved = p0 + Vec3::new(0.0, 0.0, 0.05);
        assert_eq!(c.probe(moved), p0);
        assert!(c.update(false, moved));
        assert_eq!(c.probe(moved), p0);
        // After re-engaging, motion maps one-to-one again.
        let d = Vec3::new(0.01, 0.0, 0.0);
        assert!((c.probe(moved + d) - (p0 + d)).norm() < 1e-15);
    }

    #[test]
    fn unknown_models_get_the_weakest_limits() {
        assert_eq!(ModelLimits::for_model("touch").peak_force, 3.3);
        assert_eq!(ModelLimits::for_model("mystery"), UNKNOWN_MODEL);
        let t = ModelLimits::for_model("Touch").tightened(3.0, f64::NAN, 2000.0);
        assert_eq!(
            (t.peak_force, t.continuous_force, t.max_stiffness),
            (3.0, 0.88, 1020.0)
        );
    }
}
