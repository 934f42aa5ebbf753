//! The physical model of the thigh (d'Aulignac, Balaniuk & Laugier, §3):
//! a two-layer spring–damper mesh — a surface of lumped masses joined by
//! linear springs `f = a x` with dampers, and nonlinear normal springs
//! `f(x) = x/(a x + b)` to an inner layer of fixed anchors — integrated with
//! implicit Euler (Eq. 1), Newton iterations and a preconditioned conjugate
//! gradient on an edge-form matrix (one `p d dᵀ + q I` block per spring and a
//! dense block diagonal; the 3×3 block-sparse form is kept as the reference).
//!
//! ```
//! use echothigh_model::{ModelConfig, NoExtraForce, ThighModel, Vec3};
//! let mut model = ThighModel::new(&ModelConfig::default()).unwrap();
//! let top = model.mesh().node_at(std::f64::consts::FRAC_PI_2, 0.0);
//! model.external_forces_mut()[top] = Vec3::new(0.0, -1.0, 0.0); // 1 N inward
//! let stats = model.step(0.01, &mut NoExtraForce);
//! assert!(stats.converged && model.positions()[top].y < model.rest_positions()[top].y);
//! ```
//!
//! Units are SI (m, N, s, kg). Frame: z along the thigh, x lateral, y anterior.
#![warn(missing_docs)]

pub mod block_sparse;
pub mod checkpoint;
pub mod config;
pub mod edge_matrix;
pub mod edge_pcg;
pub mod force_model;
pub mod integrator;
pub mod leg;
pub mod mesh;
pub mod node_vectors;
pub mod pcg;
pub mod simd;
pub mod simd_pcg;
pub mod springs;
pub mod stencil;
pub mod stencil_kernels;
pub mod stencil_setup;
pub mod step_limit;
pub mod thigh;
pub mod timings;
pub mod tissue;
pub mod tissue_simd;
pub mod window;

/// A 3-vector of `f64` (m, m/s or N by context).
pub type Vec3 = nalgebra::Vector3<f64>;

pub use block_sparse::{BlockSparse, PatternError};
pub use checkpoint::{DivergedError, MAX_POSITION, MAX_SPEED};
pub use config::{
    ConfigError, IntegratorParams, ModelConfig, ThighGeometry, TissueParams, WindowParams,
};
pub use edge_matrix::{EdgeMatrix, EdgeTerm, RankOneTerm};
pub use edge_pcg::EdgePcg;
pub use force_model::{ForceModel, JacobianScratch, NoExtraForce, SumForce};
pub use integrator::{Dynamics, ImplicitEuler, Kernels, StepStats, SystemForm};
pub use leg::{HandTarget, LegNode, LegSurface};
pub use mesh::{Edge, EdgeKind, SurfaceMesh};
pub use node_vectors::{NodeVectors, NodeVectorsMut};
pub use pcg::{Pcg, PcgParams, Preconditioner, SolveStats};
pub use simd_pcg::SimdPcg;
pub use stencil::{Soa3, StencilLayout, StencilMatrix};
pub use step_limit::ColumnLimits;
pub use thigh::{Energy, ThighModel};
pub use timings::StepTimings;
pub use tissue::TissueForces;
pub use window::ActiveWindow;
