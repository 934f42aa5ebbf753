//! The running system (paper Fig. 1, `DESIGN.md` §1): the physics side, the
//! link, the haptic side (model manager + haptic loop) and the simulated
//! device, deployed on a deterministic virtual clock, as real-time threads of
//! one process, or as two processes over UDP; the scenario file that
//! configures it and the seam to its front ends (`live`).

#![warn(missing_docs)]

pub mod client;
pub mod coupling;
pub mod deploy;
pub mod exam_probe;
pub mod exam_run;
pub mod exam_script;
pub mod exam_site;
mod exam_walk;
pub mod haptic_side;
pub mod image_depth;
pub mod integrity;
pub mod live;
pub mod live_device;
pub mod live_doppler;
pub mod live_system;
pub mod physics_loop;
pub mod physics_side;
pub mod recorder;
pub mod scenario;
pub mod section;
pub mod section_condition;
pub mod section_follow;
pub mod section_image;
pub mod signals;
pub mod summary;
pub mod tick;
pub mod trace;
pub mod virtual_clock;
