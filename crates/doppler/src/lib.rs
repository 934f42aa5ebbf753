//! Doppler of echothigh (issue 17): the flow in each vessel segment of a
//! case, pulsed-wave spectral Doppler with its sound, and colour flow over
//! the B-mode frame.
//!
//! - Flow: [`FlowConfig`] (sources in [`physiology`]), [`SegmentFlow`]
//!   (a case's vessel at `s`: phasic, continuous, augmentable, occluded,
//!   jet by continuity), [`Maneuvers`] (calf squeeze, Valsalva, release of
//!   a compression), [`arterial::triphasic`], [`Profile`].
//! - Spectral: [`PwConfig`], [`PwDoppler`] (scatterers through a gate,
//!   clutter, noise, wall filter, FFT lines: [`Spectrum`]),
//!   [`SpectralDisplay`] (baseline and scale), [`AudioSynth`] (the lines
//!   as sound, forward left and reverse right).
//! - Colour: [`ColorConfig`], [`ColorFlow`] (ensembles, regression wall
//!   filter, Kasai velocity and power, gain, priority, flash) over a
//!   [`FlowScene`] (the lumens of a frame and their velocities).
//!
//! Convention: a positive Doppler shift is flow towards the probe, drawn
//! red, away blue (BART).

#![warn(missing_docs)]

pub mod arterial;
mod audio;
mod color;
mod color_config;
mod display;
mod error;
mod flow;
mod maneuver;
pub mod physiology;
mod profile;
mod pw;
mod pw_config;
mod sample_volume;
mod scene;
mod spectrum;
mod wall_filter;

pub use audio::AudioSynth;
pub use color::{code_of, code_rgb, ColorFlow, ColorMode, Colour};
pub use color_config::ColorConfig;
pub use display::SpectralDisplay;
pub use error::DopplerError;
pub use flow::{FlowKind, SegmentFlow};
pub use maneuver::{Maneuver, Maneuvers, MAX_EVENTS};
pub use physiology::FlowConfig;
pub use profile::Profile;
pub use pw::PwDoppler;
pub use pw_config::PwConfig;
pub use sample_volume::SampleVolume;
pub use scene::{FlowScene, FlowVessel, SectionFlows, MAX_FLOW_VESSELS};
pub use spectrum::Spectrum;
pub use wall_filter::{regression_filter, HighPass};
