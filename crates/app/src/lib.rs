//! The `echothigh` application: the scenario file, the running system
//! (physics, link, haptic side, simulated device) in its deployments, the
//! experiments, the benchmarks and the web viewer. The binary (`main.rs`)
//! only parses the command line and calls into this library.

pub mod bench;
pub mod cmd;
pub mod experiment;
pub mod live;
pub mod plot;
pub mod runtime;
pub mod scenario;
pub mod view;
