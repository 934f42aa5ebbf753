//! # echothigh-haptics: the buffer model and the 1 kHz haptic loop
//!
//! The haptic side of d'Aulignac, Balaniuk & Laugier's thigh simulator
//! (paper §4, `DESIGN.md` §3). It sees only the samples `(p, D, ∇D, k)` the
//! ~100 Hz physics reports ([`Sample`]), never the physical model:
//!
//! - [`local_model`]: the local model trait `φ(u, x)` with `∇ₓφ`, `∂φ/∂u`,
//!   `∂(∇ₓφ)/∂u`, and the paper's [`Sphere`] plus a [`Plane`].
//! - [`ModelManager`]: Gauss–Newton fitting `du = J⁺[D − φ; D' − φ']`
//!   (SVD pseudo-inverse, windowed with forgetting), publishing a Copy
//!   [`BufferModel`] through a lock-free single-slot [`handoff`].
//! - [`HapticRenderer`]: the god-object proxy with friction cones, force
//!   shading, texture and safety (clamp, rate limit, stale fade, no NaN);
//!   `tick(p, now) -> f` with `f = k (x − p)`.
//! - [`LoopRunner`]: a fixed-rate loop with precise sleeping, best-effort
//!   real-time priority and a timing ring.
//!
//! Units: SI (m, N, s, N/m); thigh frame (`z` along the thigh, `y` anterior).
#![warn(missing_docs)]

pub mod buffer;
pub mod config;
pub mod local_model;
pub mod lsq;
pub mod manager;
pub mod proxy;
pub mod ramp;
pub mod renderer;
pub mod runner;
pub mod safety;
pub mod shading;

/// A 3-vector in the thigh frame (m, N, ...).
pub type Vec3 = nalgebra::Vector3<f64>;

pub use buffer::{handoff, BufferModel, ModelPublisher, ModelReceiver};
pub use config::{ConfigError, FitConfig, HapticsConfig, LoopConfig, ModelKind, RenderConfig};
pub use local_model::{LocalModel, ModelParams, Params, Plane, Sphere};
pub use manager::{FitReport, ModelManager, Sample, SampleError};
pub use proxy::{Friction, Proxy, Surface};
pub use ramp::{ForceRamp, RampPhase};
pub use renderer::{flags, HapticRenderer, RenderState, TickOutput};
pub use runner::{LoopRunner, Percentiles, TickTiming, TimingRing, TimingSummary};
