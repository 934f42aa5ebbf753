//! Settings of the pulsed-wave spectral Doppler (`[doppler.pw]`).

use crate::error::DopplerError;
use serde::{Deserialize, Serialize};

/// Pulsed-wave Doppler settings (SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PwConfig {
    /// Doppler transmit frequency f₀ (Hz). Default 5 MHz (a linear array's
    /// Doppler frequency is below its imaging centre, here 7.5 MHz). Accepted 1–20 MHz.
    pub center_frequency: f64,
    /// Speed of sound c (m/s). Default 1540.
    pub sound_speed: f64,
    /// Pulse repetition frequency (Hz). Default 4 kHz. Accepted 250 Hz – 30 kHz.
    pub prf: f64,
    /// Sample gate length along the beam (m, FWHM). Default 4 mm. Accepted 0.5–20 mm.
    pub gate_length: f64,
    /// Beam width at the gate (m, FWHM). Default 1 mm (≈ λ F# at F/3). Accepted 0.2–5 mm.
    pub beam_width: f64,
    /// Doppler angle θ between the flow and the beam towards the probe
    /// (degrees). Default 60. Accepted 0–90.
    pub angle_deg: f64,
    /// FFT length (slow-time samples per spectral line, a power of two). Default 128.
    pub fft_size: usize,
    /// Interval between spectral lines (s). Default 5 ms (200 lines/s).
    pub line_interval: f64,
    /// Wall filter cut-off (Hz). Default 50. Accepted 0 (off) to prf/4.
    pub wall_filter: f64,
    /// Moving scatterers in the sample volume. Default 512. Accepted 16–4096.
    pub scatterers: usize,
    /// Stationary clutter relative to the blood echo (dB). Default 40.
    pub clutter_db: f64,
    /// Electronic noise relative to the blood echo (dB). Default −30.
    pub noise_db: f64,
    /// Seed of the scatterers and noise.
    pub seed: u64,
}

impl Default for PwConfig {
    fn default() -> Self {
        PwConfig {
            center_frequency: 5e6,
            sound_speed: 1540.0,
            prf: 4000.0,
            gate_length: 4e-3,
            beam_width: 1e-3,
            angle_deg: 60.0,
            fft_size: 128,
            line_interval: 5e-3,
            wall_filter: 50.0,
            scatterers: 512,
            clutter_db: 40.0,
            noise_db: -30.0,
            seed: 17,
        }
    }
}

impl PwConfig {
    /// Checks every field, naming `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), DopplerError> {
        let r = DopplerError::in_range;
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
            250.0,
            3e4,
            "must be 250 Hz to 30 kHz",
        )?;
        r(
            prefix,
            "gate_length",
            self.gate_length,
            5e-4,
            2e-2,
            "must be 0.5 to 20 mm",
        )?;
        r(
            prefix,
            "beam_width",
            self.beam_width,
            2e-4,
            5e-3,
            "must be 0.2 to 5 mm",
        )?;
        r(
            prefix,
            "angle_deg",
            self.angle_deg,
            0.0,
            90.0,
            "must be 0 to 90 degrees",
        )?;
        if !(16..=4096).contains(&self.fft_size) || !self.fft_size.is_power_of_two() {
            return Err(DopplerError::Invalid {
                key: format!("{prefix}.fft_size"),
                value: self.fft_size.to_string(),
                reason: "must be a power of two from 16 to 4096",
            });
        }
        r(
            prefix,
            "line_interval",
            self.line_interval,
            1e-3,
            0.1,
            "must be 1 to 100 ms",
        )?;
        if self.hop() == 0 || self.hop() > self.fft_size {
            return Err(DopplerError::Invalid {
                key: format!("{prefix}.line_interval"),
                value: self.line_interval.to_string(),
                reason: "must hold between 1 and fft_size pulses at this prf",
            });
        }
        r(
            prefix,
            "wall_filter",
            self.wall_filter,
            0.0,
            self.prf / 4.0,
            "must be 0 to prf/4 Hz",
        )?;
        if !(16..=4096).contains(&self.scatterers) {
            return Err(DopplerError::Invalid {
                key: format!("{prefix}.scatterers"),
                value: self.scatterers.to_string(),
                reason: "must be 16 to 4096",
            });
        }
        r(
            prefix,
            "clutter_db",
            self.clutter_db,
            -100.0,
            100.0,
            "must be -100 to 100 dB",
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

    /// Pulses between spectral lines: `round(prf · line_interval)`.
    pub fn hop(&self) -> usize {
        (self.prf * self.line_interval).round() as usize
    }

    /// Doppler shift (Hz) of a velocity `v` (m/s) along the flow at this
    /// angle: `f_d = 2 f₀ v cos θ / c`.
    pub fn doppler_shift(&self, v: f64) -> f64 {
        2.0 * self.center_frequency * v * self.angle_deg.to_radians().cos() / self.sound_speed
    }

    /// Angle-corrected velocity (m/s) of a Doppler shift `f` (Hz):
    /// `v = c f / (2 f₀ cos θ)`; `None` beyond 80°, where the correction
    /// is too ill-conditioned to report (1/cos 80° = 5.8).
    pub fn velocity(&self, f: f64) -> Option<f64> {
        let c = self.angle_deg.to_radians().cos();
        (self.angle_deg <= 80.0).then(|| self.sound_speed * f / (2.0 * self.center_frequency * c))
    }

    /// The Nyquist velocity along the flow (m/s): the velocity whose shift
    /// is `prf/2` (`None` beyond 80°).
    pub fn nyquist_velocity(&self) -> Option<f64> {
        self.velocity(0.5 * self.prf)
    }
}
