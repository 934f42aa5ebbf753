//! Settings of colour flow (`[doppler.color]`).

use crate::error::DopplerError;
use serde::{Deserialize, Serialize};

/// Colour flow settings (SI units; the box in the image frame: lateral
/// from the image centre, positive to the image's right; depth from the
/// probe face).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ColorConfig {
    /// Left edge of the colour box (m). Default −15 mm.
    pub box_left: f64,
    /// Right edge (m). Default +15 mm.
    pub box_right: f64,
    /// Top (m). Default 5 mm.
    pub box_top: f64,
    /// Bottom (m). Default 50 mm.
    pub box_bottom: f64,
    /// Steering of the colour beams in the image plane (degrees, + towards
    /// the image's right). Default 0. Accepted ±30.
    pub steer_deg: f64,
    /// Doppler transmit frequency (Hz). Default 5 MHz.
    pub center_frequency: f64,
    /// Speed of sound (m/s). Default 1540.
    pub sound_speed: f64,
    /// Colour PRF (Hz): the velocity scale, Nyquist `c·prf/(4 f₀)` along
    /// the beam (11.6 cm/s at the defaults: venous scale). Default 1500.
    pub prf: f64,
    /// Pulses per ensemble (per colour line). Default 10. Accepted 4–32.
    pub ensemble: usize,
    /// Colour gain (dB): lowers the power threshold. Default 0.
    pub gain_db: f64,
    /// Power (after the wall filter) above the noise needed to show colour,
    /// before gain (dB). Default 6.
    pub threshold_db: f64,
    /// Priority: B-mode grey (0–255) above which the grey wins. Default 120.
    pub priority: u8,
    /// Smallest |velocity| shown, as a fraction of the Nyquist velocity
    /// (the display's wall-filter reject). Default 0.05.
    pub min_velocity: f64,
    /// Stationary tissue echo relative to the blood echo at full grey (dB). Default 40.
    pub clutter_db: f64,
    /// Electronic noise relative to the blood echo (dB). Default −20.
    pub noise_db: f64,
    /// Seed of the noise and speckle tables.
    pub seed: u64,
}

impl Default for ColorConfig {
    fn default() -> Self {
        ColorConfig {
            box_left: -0.015,
            box_right: 0.015,
            box_top: 0.005,
            box_bottom: 0.05,
            steer_deg: 0.0,
            center_frequency: 5e6,
            sound_speed: 1540.0,
            prf: 1500.0,
            ensemble: 10,
            gain_db: 0.0,
            threshold_db: 6.0,
            priority: 120,
            min_velocity: 0.05,
            clutter_db: 40.0,
            noise_db: -20.0,
            seed: 17,
        }
    }
}

impl ColorConfig {
    /// Checks every field, naming `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), DopplerError> {
        let r = DopplerError::in_range;
        r(
            prefix,
            "box_left",
            self.box_left,
            -0.1,
            0.1,
            "must be within ±100 mm",
        )?;
        r(
            prefix,
            "box_right",
            self.box_right,
            self.box_left + 1e-3,
            0.1,
            "must exceed box_left by 1 mm, within 100 mm",
        )?;
        r(
            prefix,
            "box_top",
            self.box_top,
            0.0,
            0.2,
            "must be 0 to 200 mm",
        )?;
        r(
            prefix,
            "box_bottom",
            self.box_bottom,
            self.box_top + 1e-3,
            0.3,
            "must exceed box_top by 1 mm",
        )?;
        r(
            prefix,
            "steer_deg",
            self.steer_deg,
            -30.0,
            30.0,
            "must be within ±30 degrees",
        )?;
        r(
            prefix,
            "center_frequency",
            self.center_frequency,
            1e6,
            2e7,
            "must be 1 to 20 MHz",
        )?;
        r(
            prefix,
            "sound_speed",
            self.sound_speed,
            1000.0,
            2000.0,
            "must be 1000 to 2000 m/s",
        )?;
        r(
            prefix,
            "prf",
            self.prf,
            100.0,
            2e4,
            "must be 100 Hz to 20 kHz",
        )?;
        if !(4..=32).contains(&self.ensemble) {
            return Err(DopplerError::Invalid {
                key: format!("{prefix}.ensemble"),
                value: self.ensemble.to_string(),
                reason: "must be 4 to 32 pulses",
            });
        }
        r(
            prefix,
            "gain_db",
            self.gain_db,
            -40.0,
            40.0,
            "must be within ±40 dB",
        )?;
        r(
            prefix,
            "threshold_db",
            self.threshold_db,
            0.0,
            40.0,
            "must be 0 to 40 dB",
        )?;
        r(
            prefix,
            "min_velocity",
            self.min_velocity,
            0.0,
            0.5,
            "must be 0 to 0.5 of Nyquist",
        )?;
        r(
            prefix,
            "clutter_db",
            self.clutter_db,
            -100.0,
            100.0,
            "must be within ±100 dB",
        )?;
        r(
            prefix,
            "noise_db",
            self.noise_db,
            -100.0,
            40.0,
            "must be -100 to 40 dB",
        )
    }

    /// Nyquist velocity along the beam (m/s): `c · prf / (4 f₀)`.
    pub fn nyquist_velocity(&self) -> f64 {
        self.sound_speed * self.prf / (4.0 * self.center_frequency)
    }
}
