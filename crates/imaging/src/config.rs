//! Configuration of the image formation (`[imaging]`).
//!
//! Defaults and their sources:
//! - **Probe and frequency**: a linear vascular probe of ~40 mm aperture at
//!   5–10 MHz, the usual choice for compression ultrasound of the femoral vein
//!   (e.g. Needleman et al. 2018, "Ultrasound for lower extremity deep venous
//!   thrombosis: multidisciplinary recommendations from the Society of
//!   Radiologists in Ultrasound consensus conference", Circulation 137). Centre
//!   frequency 7.5 MHz, speed of sound 1540 m/s (the scanners' convention).
//! - **Beam**: the array, its pulse and focusing are `[imaging.beam]`
//!   ([`BeamConfig`], with its sources); the resolution follows from them
//!   (axial FWHM 0.21 mm, lateral 0.44 mm at the 20 mm focus). The
//!   default grid, 512 × 864 over 40 × 60 mm (69 µm rows), carries
//!   ≥ 2.5 pixels per axial FWHM (3.05 measured by `echothigh psf`; the
//!   measure on a sampled envelope moves by ~5 % with the grid, and 768
//!   or 800 rows gave 2.4–2.6).
//! - **Attenuation compensated by the TGC**: soft tissue 0.5–0.7 dB/(cm·MHz)
//!   (Duck 1990, "Physical Properties of Tissue", ch. 4; Goss, Johnston &
//!   Dunn 1978, JASA 64). Default 0.65 dB/(cm·MHz).
//! - **Dynamic range** 72 dB with white 25 dB above muscle: black at −47 dB,
//!   so that the −25 to −40 dB fill of anechoic targets on scanners stays
//!   visible (B-mode displays use 50–80 dB).
//! - **Scatterer density**: fully developed speckle needs ≳ 10 scatterers per
//!   resolution cell (Wagner et al. 1983, "Statistics of speckle in ultrasound
//!   B-scans", IEEE Trans. Sonics Ultrason. 30(3)); the default 100 per mm²
//!   puts ≈ 9 in the 2-D cell `2π σx σz` of the focal PSF (0.4 × 0.2 mm),
//!   more elsewhere (the amplitudes are circular Gaussian, so the sum is
//!   Gaussian whatever the count once it varies little between cells).

use crate::anatomy_config::AnatomyConfig;
use crate::beam_config::BeamConfig;
use crate::error::ImagingError;
use crate::reverberation::ReverbConfig;
use crate::texture::TextureConfig;
use serde::{Deserialize, Serialize};

/// Full width at half maximum of a Gaussian divided by its σ: `2 √(2 ln 2)`.
pub const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949;

/// Parameters of the B-mode image formation (`[imaging]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImagingConfig {
    /// Image columns (lateral pixels, along the probe's width). Default 512.
    pub columns: usize,
    /// Image rows (axial pixels, depth). Default 864.
    pub rows: usize,
    /// Columns of the live viewer's image ([`ImagingConfig::live`]): the
    /// live path renders on one core and streams every frame to the browser
    /// as a PNG, so it uses a coarser grid than `echothigh image`. Default 256
    /// (156 µm pixels over 40 mm: the lateral FWHM, ≥ 0.4 mm, still spans
    /// ≥ 2.5 pixels).
    pub live_columns: usize,
    /// Rows of the live viewer's image. Default 384 (156 µm over 60 mm: the
    /// axial FWHM, 0.21 mm, spans 1.35 pixels; the envelope is still sampled
    /// above its Nyquist rate, bandwidth ~1/FWHM).
    pub live_rows: usize,
    /// Lateral field of view, centred on the probe (m). Default 0.040.
    /// Accepted: in 0.01 to 0.1 m (linear probe apertures).
    pub width: f64,
    /// Imaged depth below the probe face (m). Default 0.060.
    /// Accepted: in 0.01 to 0.2 m (a thigh is imaged to 4-10 cm).
    pub depth: f64,
    /// On a patient's leg, the live image's depth follows the level as a
    /// sonographer sets it: each section's studied vein's far wall at ¾ of
    /// the image, in whole centimetres (`echothigh_runtime::image_depth`).
    /// `false` keeps `depth` everywhere. Default true.
    pub auto_depth: bool,
    /// Centre frequency of the pulse (Hz). Default 7.5e6.
    /// Accepted: in 1e6 to 2e7 Hz (clinical B-mode probes).
    pub center_frequency: f64,
    /// Speed of sound assumed by the scanner (m/s). Default 1540.
    /// Accepted: in 1400 to 1700 m/s (soft tissue 1450-1640, Duck 1990).
    pub sound_speed: f64,
    /// Attenuation slope compensated by the time-gain compensation
    /// (dB/(cm·MHz), one way; the TGC applies twice this, round trip), also
    /// the tissue slope of the beam's spectral down-shift. Default 0.65.
    /// Accepted: in 0 to 2 dB/(cm MHz) (soft tissue 0.3-1.5, Duck 1990).
    pub tgc_attenuation: f64,
    /// Displayed dynamic range of the log compression (dB). Default 72.
    /// Accepted: in 10 to 120 dB.
    pub dynamic_range: f64,
    /// Level of white above the mean echo of muscle at the transmit focus (dB). Default 25.
    /// Accepted: in 0 to 80 dB.
    pub headroom: f64,
    /// Scatterers per unit area of the section (1/m²). Default 1.0e8 (100 per mm²).
    /// Accepted: in 1e5 to 1e9 1/m^2 (0.1 to 1000 per mm^2).
    pub scatterer_density: f64,
    /// Seed of the scatterer generator (same seed, same image). Default 7.
    pub seed: u64,
    /// Deepest indentation the scatterer field is prepared for (m): tissue
    /// down to `depth + max_indentation` below the skin is populated. Default 0.030.
    /// Accepted: in 0 to 0.1 m (the soft tissue thickness).
    pub max_indentation: f64,
    /// Width of the probe face along the image plane (m), for the pressure
    /// under the face (must match `[probe]`). Default 0.040.
    /// Accepted: in 0.01 to 0.1 m (linear probe apertures).
    pub probe_width: f64,
    /// Elevation (thickness) of the probe face across the image plane (m),
    /// for the pressure under the face (must match `[probe]`). Default 0.010.
    /// Accepted: in 0.002 to 0.04 m (probe footprints).
    pub probe_elevation: f64,
    /// How far the image can pan laterally, each way (m): the anatomy is
    /// fixed in the thigh, the image centred on the probe, so sliding the
    /// probe across the thigh by `s` (arc length along the skin) moves the
    /// anatomy by `−s` in the image (see [`crate::FrameInput::lateral_offset`]).
    /// The scatterer field is prepared over `width + 2 · pan_range`; a probe
    /// farther than this from the vessels sees the field's edge (fat, muscle,
    /// no vessel). Default 0.050.
    /// Accepted: in 0 to 0.2 m (around the thigh: its half-circumference is ~0.25 m).
    pub pan_range: f64,
    /// The probe's array, pulse and focusing (`[imaging.beam]`).
    pub beam: BeamConfig,
    /// The anatomy of the section (`[imaging.anatomy]`).
    pub anatomy: AnatomyConfig,
    /// Tissue textures and the smoke option (`[imaging.texture]`).
    pub texture: TextureConfig,
    /// Near-field and lumen reverberation (`[imaging.reverberation]`).
    pub reverberation: ReverbConfig,
}

impl Default for ImagingConfig {
    fn default() -> Self {
        ImagingConfig {
            columns: 512,
            rows: 864,
            live_columns: 256,
            live_rows: 384,
            width: 0.040,
            depth: 0.060,
            auto_depth: true,
            center_frequency: 7.5e6,
            sound_speed: 1540.0,
            tgc_attenuation: 0.65,
            dynamic_range: 72.0,
            headroom: 25.0,
            scatterer_density: 1.0e8,
            seed: 7,
            max_indentation: 0.030,
            probe_width: 0.040,
            probe_elevation: 0.010,
            pan_range: 0.050,
            beam: BeamConfig::default(),
            anatomy: AnatomyConfig::default(),
            texture: TextureConfig::default(),
            reverberation: ReverbConfig::default(),
        }
    }
}

impl ImagingConfig {
    /// Largest accepted frame side (pixels).
    pub const MAX_PIXELS_PER_SIDE: usize = 4096;
    /// Largest accepted number of scatterers in the populated field.
    pub const MAX_SCATTERERS: f64 = 2.0e7;

    /// Checks every field, naming the offending key as `"{prefix}.{field}"`.
    pub fn validate(&self, prefix: &str) -> Result<(), ImagingError> {
        for (field, n) in [
            ("columns", self.columns),
            ("rows", self.rows),
            ("live_columns", self.live_columns),
            ("live_rows", self.live_rows),
        ] {
            if !(8..=Self::MAX_PIXELS_PER_SIDE).contains(&n) {
                return Err(ImagingError::invalid(
                    prefix,
                    field,
                    n,
                    "must be between 8 and 4096",
                ));
            }
        }
        ImagingError::in_range(
            prefix,
            "width",
            self.width,
            0.01,
            0.1,
            "must be between 0.01 and 0.1 m (linear probe apertures)",
        )?;
        ImagingError::in_range(
            prefix,
            "depth",
            self.depth,
            0.01,
            0.2,
            "must be between 0.01 and 0.2 m (a thigh is imaged to 4-10 cm)",
        )?;
        ImagingError::in_range(
            prefix,
            "center_frequency",
            self.center_frequency,
            1000000.0,
            20000000.0,
            "must be between 1e6 and 2e7 Hz (clinical B-mode probes)",
        )?;
        ImagingError::in_range(
            prefix,
            "sound_speed",
            self.sound_speed,
            1400.0,
            1700.0,
            "must be between 1400 and 1700 m/s (soft tissue 1450-1640, Duck 1990)",
        )?;
        for (field, n, live) in [
            ("columns", self.columns, false),
            ("live_columns", self.live_columns, true),
        ] {
            let c = if live { self.live() } else { self.clone() };
            if c.pixel_width() > 1e-3 || c.pixel_depth() > 1e-3 {
                return Err(ImagingError::invalid(
                    prefix,
                    field,
                    n,
                    "pixels must be at most 1 mm (width / columns, depth / rows) to carry the beam",
                ));
            }
        }
        ImagingError::in_range(
            prefix,
            "tgc_attenuation",
            self.tgc_attenuation,
            0.0,
            2.0,
            "must be between 0 and 2 dB/(cm MHz) (soft tissue 0.3-1.5, Duck 1990)",
        )?;
        ImagingError::in_range(
            prefix,
            "dynamic_range",
            self.dynamic_range,
            10.0,
            120.0,
            "must be between 10 and 120 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "headroom",
            self.headroom,
            0.0,
            80.0,
            "must be between 0 and 80 dB",
        )?;
        ImagingError::in_range(
            prefix,
            "scatterer_density",
            self.scatterer_density,
            100000.0,
            1000000000.0,
            "must be between 1e5 and 1e9 1/m^2 (0.1 to 1000 per mm^2)",
        )?;
        ImagingError::in_range(
            prefix,
            "max_indentation",
            self.max_indentation,
            0.0,
            0.1,
            "must be between 0 and 0.1 m (the soft tissue thickness)",
        )?;
        ImagingError::in_range(
            prefix,
            "probe_width",
            self.probe_width,
            0.01,
            0.1,
            "must be between 0.01 and 0.1 m (linear probe apertures)",
        )?;
        ImagingError::in_range(
            prefix,
            "probe_elevation",
            self.probe_elevation,
            0.002,
            0.04,
            "must be between 0.002 and 0.04 m (probe footprints)",
        )?;
        ImagingError::in_range(
            prefix,
            "pan_range",
            self.pan_range,
            0.0,
            0.2,
            "must be between 0 and 0.2 m (around the thigh: its half-circumference is ~0.25 m)",
        )?;
        let area =
            (self.width + 2.0 * self.pan_range + 0.01) * (self.depth + self.max_indentation + 0.01);
        if self.scatterer_density * area > Self::MAX_SCATTERERS {
            return Err(ImagingError::invalid(
                prefix,
                "scatterer_density",
                self.scatterer_density,
                "too many scatterers for the field (limit 2e7)",
            ));
        }
        self.beam.validate(&format!("{prefix}.beam"))?;
        self.texture.validate(&format!("{prefix}.texture"))?;
        self.reverberation
            .validate(&format!("{prefix}.reverberation"))?;
        self.anatomy.validate(&format!("{prefix}.anatomy"))
    }

    /// The configuration of the live viewer's image: this one at
    /// `live_columns × live_rows` (same field of view, beam and anatomy).
    pub fn live(&self) -> ImagingConfig {
        ImagingConfig {
            columns: self.live_columns,
            rows: self.live_rows,
            ..self.clone()
        }
    }

    /// Lateral pixel pitch (m).
    pub fn pixel_width(&self) -> f64 {
        self.width / self.columns as f64
    }

    /// Axial pixel pitch (m).
    pub fn pixel_depth(&self) -> f64 {
        self.depth / self.rows as f64
    }

    /// The largest pan, in whole columns (the pan is quantized to the
    /// lateral pixel pitch, so that scatterers stay on their columns).
    pub fn pan_columns(&self) -> usize {
        (self.pan_range / self.pixel_width()).floor() as usize
    }

    /// Area of the probe face (m²): `probe_width · probe_elevation`.
    pub fn probe_area(&self) -> f64 {
        self.probe_width * self.probe_elevation
    }
}
