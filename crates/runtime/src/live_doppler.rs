//! The live Doppler seam (issue 17): what a front end asks of the live
//! system's flow (the imaging mode, the manoeuvres, the PW sample gate) and
//! what it reads back (the settings it shows, the colour overlay with each
//! frame, the spectral lines). Kept apart from [`crate::live`] so that the
//! B-mode seam is unchanged; [`crate::live::LiveControl`] carries it
//! through default methods.
//!
//! Units: SI (m/s, Hz, s) except the gate's angle correction (degrees, as
//! scanners show it) and its place (fractions of the image).

use crate::live::CommandError;
use serde::{Deserialize, Serialize};

/// What the imaging thread adds to the B-mode frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DopplerMode {
    /// B-mode only.
    #[default]
    Bmode,
    /// Colour flow: mean velocity, towards the probe red, away blue.
    Color,
    /// Power Doppler: flow amplitude, no direction.
    Power,
    /// Pulsed-wave spectral Doppler at the sample gate (with its sound).
    Spectral,
}

/// Rows of a streamed spectral line (8-bit magnitudes, top row the highest
/// frequency of the display span).
pub const SPECTRAL_ROWS: usize = 64;

/// Spectral lines the live system keeps for the front ends (1.28 s at 200
/// lines/s): a page behind by more misses the oldest.
pub const SPECTRAL_RING: usize = 256;

/// Largest angle correction accepted (degrees): beyond 80° the correction
/// `1/cos θ` exceeds 5.8 and is not reported (`PwConfig::velocity`).
pub const MAX_ANGLE_CORRECTION: f64 = 80.0;

/// A page's Doppler command (JSON `type`: `doppler_mode`, `squeeze`,
/// `valsalva`, `doppler_gate`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum DopplerCommand {
    /// Switch the imaging mode.
    DopplerMode {
        /// The new mode.
        mode: DopplerMode,
    },
    /// A calf squeeze now (distal augmentation).
    Squeeze,
    /// Begin (`hold: true`) or end (`false`) a Valsalva strain.
    Valsalva {
        /// Whether the strain is held.
        hold: bool,
    },
    /// Place the PW sample gate.
    DopplerGate {
        /// Lateral place: fraction of the image width from its left edge (0 to 1).
        x: f64,
        /// Depth: fraction of the image depth from the skin (0 to 1).
        y: f64,
        /// Angle correction: the flow's angle to the beam that the trainee
        /// sets (degrees, 0 to [`MAX_ANGLE_CORRECTION`]).
        angle_deg: f64,
    },
}

/// The JSON `type`s of [`DopplerCommand`], for a decoder routing page messages.
pub const DOPPLER_COMMAND_TYPES: [&str; 4] =
    ["doppler_mode", "squeeze", "valsalva", "doppler_gate"];

impl DopplerCommand {
    /// The range check of the gate's numbers (the others have none).
    pub fn validate(&self) -> Result<(), CommandError> {
        let check = |field, value: f64, unit, (min, max)| {
            if value.is_finite() && (min..=max).contains(&value) {
                Ok(())
            } else {
                Err(CommandError::OutOfRange {
                    field,
                    value,
                    unit,
                    min,
                    max,
                })
            }
        };
        match *self {
            DopplerCommand::DopplerGate { x, y, angle_deg } => {
                check("doppler_gate.x", x, "of the width", (0.0, 1.0))?;
                check("doppler_gate.y", y, "of the depth", (0.0, 1.0))?;
                check(
                    "doppler_gate.angle_deg",
                    angle_deg,
                    "deg",
                    (0.0, MAX_ANGLE_CORRECTION),
                )
            }
            _ => Ok(()),
        }
    }
}

/// The PW sample gate as placed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Gate {
    /// Fraction of the image width from its left edge.
    pub x: f64,
    /// Fraction of the image depth from the skin.
    pub y: f64,
    /// Angle correction (degrees).
    pub angle_deg: f64,
}

impl Default for Gate {
    /// The image's centre column at 40 % of its depth, 60° (the usual
    /// venous setting, `PwConfig`'s default).
    fn default() -> Self {
        Gate {
            x: 0.5,
            y: 0.4,
            angle_deg: 60.0,
        }
    }
}

/// What the page shows of the Doppler settings, with each state.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DopplerStatus {
    /// The imaging mode.
    pub mode: DopplerMode,
    /// Whether flow is imaged (on a leg; the elliptic cylinder has no flow model).
    pub available: bool,
    /// A Valsalva strain is held.
    pub valsalva: bool,
    /// Colour scale: the Nyquist velocity along the beam (m/s).
    pub color_nyquist: f64,
    /// The colour box (fractions of the image: left, top, right, bottom).
    pub color_box: [f64; 4],
    /// The PW sample gate.
    pub gate: Gate,
    /// Spectral display: the pulse repetition frequency (Hz); the span is
    /// ±PRF/2 about the baseline (0).
    pub prf: f64,
    /// Spectral lines per second.
    pub line_rate: f64,
    /// Angle-corrected velocity per Hz of Doppler shift (m/s per Hz):
    /// `c / (2 f₀ cos θ_corr)`, for the page's velocity scale.
    pub velocity_per_hz: f64,
    /// Whether the gate lies in a lumen carrying flow.
    pub gate_in_flow: bool,
    /// The model's centreline velocity at the gate (m/s, along the flow),
    /// the ground truth the trainee's reading may be compared with.
    pub gate_velocity: f64,
}

/// A run of spectral lines copied for a front end.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SpectralLines {
    /// Number of the first line (lines are numbered from 0 since the
    /// imaging thread started).
    pub first: u64,
    /// Lines copied.
    pub count: usize,
    /// `count · SPECTRAL_ROWS` magnitudes, line after line.
    pub data: Vec<u8>,
    /// Simulated time of the first line (s).
    pub time: f64,
    /// Time between lines (s).
    pub interval: f64,
}
