//! The linear array, its pulse and its focusing (`[imaging.beam]`).
//!
//! Defaults: a 7.5 MHz vascular linear array shaped on the Verasonics
//! L11-5v as the MUST toolbox describes it (`getparam('L11-5v')`, Garcia
//! 2021, "SIMUS: an open-source simulator for medical ultrasound imaging",
//! Comput. Methods Programs Biomed. 218): 128 elements at 0.30 mm pitch,
//! 0.27 mm wide, 77 % fractional bandwidth at −6 dB, 5 mm elevation height
//! with an 18 mm elevation lens. A 2.5-cycle transmit at the centre
//! frequency under a Hann envelope (axial FWHM 0.21 mm from 10 to 40 mm,
//! `echothigh psf`; PyMUST with this preset: 0.19–0.24 mm with
//! attenuation), a 32-element transmit aperture focused at 20 mm, dynamic
//! receive focusing at F# 1.7 with a 50 % Tukey apodization (Szabo 2014,
//! "Diagnostic Ultrasound Imaging: Inside Out", 2nd ed., ch. 7: the receive
//! aperture of scanners grows with depth at a fixed F# of 1–3, apodized;
//! Tukey 0.5 is the default receive window of MUST's `dasmtx`).
//!
//! Noise and clutter levels are relative to the mean echo of muscle at the
//! transmit focus before attenuation:
//! - electronic noise −80 dB: with the round trip attenuation of
//!   0.65–0.7 dB/(cm·MHz) at 7.5 MHz (≈ 10 dB/cm) and the beam's loss past
//!   the focus it meets the tissue echo near 65–70 mm, the penetration of a
//!   7.5 MHz linear array in muscle (Szabo 2014, ch. 4: penetration
//!   ≈ 60–70 dB / (2 α f)); it rises through the bottom of a 60 mm image and
//!   greys the bone's shadow with depth;
//! - body-wall reverberation and aberration clutter −35 dB, a diffuse haze
//!   independent of the local echo: the level at which it fills anechoic
//!   targets on scanners (−25 to −40 dB: Lediju et al. 2011, "Short-lag
//!   spatial coherence of backscattered echoes", IEEE TUFFC 58(7); Pinton
//!   et al. 2011, "Sources of image degradation in fundamental and harmonic
//!   ultrasound imaging", IEEE TUFFC 58(6)).

use crate::error::ImagingError;
use serde::{Deserialize, Serialize};

/// The array, pulse and focusing of the probe (`[imaging.beam]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BeamConfig {
    /// One-way fractional bandwidth of the elements at −6 dB. Default 0.77.
    ///
    /// MUST documents its `param.bandwidth` (77 % for the L11-5v) as the
    /// probe's *pulse-echo* −6 dB fractional bandwidth (`getpulse`,
    /// `pfield`: the one-way response is its square root). Taken one way
    /// here, the element response squared spans 0.77/√2 = 54 % at −6 dB, and
    /// with the 2.5-cycle Hann burst the pulse-echo spectrum `S₀` spans
    /// 45 % (computed from `crate::pulse`'s formulas). Matching MUST (one-way
    /// 1.09) would give `S₀` 56 % and shorten the axial FWHM from ≈ 0.20 to
    /// ≈ 0.165 mm (same computation, no attenuation), under the default
    /// grid's 2.5 rows per FWHM; left for a change with the grid.
    pub bandwidth: f64,
    /// Cycles of the transmitted burst at the centre frequency, under a
    /// Hann envelope (`crate::pulse`). Default 2.5.
    pub pulse_cycles: f64,
    /// Element pitch (m). Default 0.30e-3.
    pub pitch: f64,
    /// Element width along the array (m), for the element directivity. Default 0.27e-3.
    pub element_width: f64,
    /// Elements of the array. Default 128.
    pub elements: usize,
    /// Elements of the transmit aperture (centred on the line). Default 32.
    pub transmit_elements: usize,
    /// Transmit focal depth (m). Default 0.020.
    pub transmit_focus: f64,
    /// Receive F-number of the dynamic receive aperture (depth / aperture). Default 1.7.
    pub receive_f_number: f64,
    /// Elevation height of the elements (m). Default 5e-3.
    pub elevation_height: f64,
    /// Focal depth of the elevation lens (m). Default 0.018.
    pub elevation_focus: f64,
    /// Electronic noise power relative to muscle at the focus (dB). Default −80.
    pub noise_db: f64,
    /// Diffuse clutter (reverberation, aberration) relative to the mean echo
    /// of muscle at the same depth (dB). Default −35.
    pub clutter_db: f64,
}

impl Default for BeamConfig {
    fn default() -> Self {
        BeamConfig {
            bandwidth: 0.77,
            pulse_cycles: 2.5,
            pitch: 0.30e-3,
            element_width: 0.27e-3,
            elements: 128,
            transmit_elements: 32,
            transmit_focus: 0.020,
            receive_f_number: 1.7,
            elevation_height: 5e-3,
            elevation_focus: 0.018,
            noise_db: -80.0,
            clutter_db: -35.0,
        }
    }
}

impl BeamConfig {
    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        ImagingError::in_range(
            prefix,
            "bandwidth",
            self.bandwidth,
            0.1,
            1.5,
            "must be between 0.1 and 1.5",
        )?;
        ImagingError::in_range(
            prefix,
            "pulse_cycles",
            self.pulse_cycles,
            0.5,
            10.0,
            "must be between 0.5 and 10",
        )?;
        ImagingError::in_range(
            prefix,
            "pitch",
            self.pitch,
            20e-6,
            2e-3,
            "must be between 20 µm and 2 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "element_width",
            self.element_width,
            1e-6,
            self.pitch,
            "must be positive and at most the pitch",
        )?;
        if !(8..=512).contains(&self.elements) {
            return Err(ImagingError::invalid(
                prefix,
                "elements",
                self.elements,
                "must be between 8 and 512",
            ));
        }
        if !(1..=self.elements).contains(&self.transmit_elements) {
            return Err(ImagingError::invalid(
                prefix,
                "transmit_elements",
                self.transmit_elements,
                "must be between 1 and elements",
            ));
        }
        ImagingError::in_range(
            prefix,
            "transmit_focus",
            self.transmit_focus,
            2e-3,
            0.2,
            "must be between 2 and 200 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "receive_f_number",
            self.receive_f_number,
            0.5,
            10.0,
            "must be between 0.5 and 10",
        )?;
        ImagingError::in_range(
            prefix,
            "elevation_height",
            self.elevation_height,
            0.5e-3,
            20e-3,
            "must be between 0.5 and 20 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "elevation_focus",
            self.elevation_focus,
            2e-3,
            0.2,
            "must be between 2 and 200 mm",
        )?;
        ImagingError::in_range(
            prefix,
            "noise_db",
            self.noise_db,
            -200.0,
            0.0,
            "must be between -200 and 0 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "clutter_db",
            self.clutter_db,
            -200.0,
            0.0,
            "must be between -200 and 0 dB",
        )
    }
}
