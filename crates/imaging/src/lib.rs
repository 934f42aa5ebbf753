//! The echographic image of echothigh (issue 7, DESIGN.md §5; beyond the
//! paper, whose image generator was "being implemented"): a B-mode
//! transverse section of the mid-thigh under the probe, coupled to the
//! physical model's deformation, in which a healthy femoral vein collapses
//! under the probe's pressure and a thrombosed one does not.
//!
//! - [`ImagingConfig`] / [`AnatomyConfig`]: the `[imaging]` section, with
//!   published sources for the defaults.
//! - [`Anatomy`]: tissue classes in tissue coordinates, lumen laws per
//!   [`VeinState`], the arterial pulse.
//! - [`SectionDeformation`]: the skin displacement along the section from
//!   the physics, carried into depth towards the femur (normal springs).
//! - [`Renderer`]: scatterers fixed in tissue, complex-baseband PSF of a
//!   focused linear array ([`BeamConfig`]: transmit focus, dynamic receive,
//!   elevation slice, spectral down-shift; tabulated per depth once),
//!   envelope, near-field and lumen reverberation ([`ReverbConfig`]),
//!   attenuation, clutter and electronic noise, TGC, log compression;
//!   allocation-free [`Renderer::render_into`].
//! - [`TextureConfig`]: muscle's transverse "starry sky", the fat's
//!   coherent septa, the veins' slow-flow smoke (an option).
//! - Specular interfaces (fascia, vessel walls, the artery's intima–media
//!   double line) as coherent lines with an angle-dependent echo, and
//!   refraction edge shadows below the vessels' lateral margins.
//! - [`measure_psf`]: the standard point phantom's FWHM, focal gain and
//!   side lobes; [`Phantom`]: points, speckle, cyst.
//! - PNG output of a frame: [`write_gray_png`].
//!
//! ```
//! use echothigh_imaging::*;
//! let cfg = ImagingConfig { columns: 64, rows: 160, ..Default::default() };
//! let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
//! let bone = r.anatomy().unwrap().femur_top();
//! let press = SectionDeformation::flat_press(0.005, 0.04, 1.5e-3, bone).unwrap();
//! let input = FrameInput { deformation: &press, probe_pressure: 5.0 / 4e-4, time: 0.0, lateral_offset: 0.0 };
//! let mut frame = vec![0u8; 64 * 160];
//! r.render_into(&input, &mut frame).unwrap();
//! ```

#![warn(missing_docs)]

mod anatomy;
mod anatomy_config;
mod beam;
mod beam_config;
mod carry;
#[cfg(target_arch = "x86_64")]
mod compress_avx2;
mod config;
mod deformation;
mod edge_shadow;
mod enhancement;
mod error;
mod lateral_map;
mod material;
mod measure;
mod output;
mod post_thrombotic;
pub mod pressure;
mod psf;
#[cfg(test)]
mod published_acoustics;
mod pulse;
mod render;
mod reverberation;
mod scatterers;
mod smoke;
mod specular;
mod stage_times;
mod stages;
mod structure_config;
mod target_band;
mod texture;
mod tissue;
mod vein_condition;
mod warp;
mod widen;

pub use anatomy::{Anatomy, LumenLaw, SectionVessel, Vessel, MAX_BREAKPOINTS};
pub use anatomy_config::{AnatomyConfig, VeinState, VeinStateParams, MMHG};
pub use beam_config::BeamConfig;
pub use config::{ImagingConfig, FWHM_PER_SIGMA};
pub use deformation::{column_depth, SectionDeformation};
pub use edge_shadow::{SHADOW_DB, SHADOW_FADE, SHADOW_LENGTH, SHADOW_ONSET, SHADOW_WIDTH};
pub use error::ImagingError;
pub use material::{MaterialWindow, SLAB_SIGMAS, SLICE};
pub use measure::{axis_column, fwhm_samples, measure_psf, PsfAtDepth, PsfReport, POINT_DEPTHS};
pub use output::write_gray_png;
pub use post_thrombotic::{PostThrombotic, IRREGULAR_THICKENING, WEB_THICKNESS};
pub use render::{FrameInput, Lumen, LumenReport, Phantom, Renderer};
pub use reverberation::ReverbConfig;
pub use specular::INTIMA_MEDIA;
pub use stage_times::{wall_seconds, StageTimes};
pub use structure_config::{StructureConfig, StructureKind, MAX_STRUCTURES};
pub use target_band::{TargetBand, ARTERY_CLEARLY_OVAL};
pub use texture::TextureConfig;
pub use tissue::{Acoustics, Tissue};
pub use vein_condition::{CollapseLaw, ContentLayout, VeinCondition, BREATHING_RATE, TAIL_SWING};
pub use warp::VesselWarp;
pub use widen::{ellipse_perimeter, wall_length_half_width};
