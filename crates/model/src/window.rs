//! The active window (issue 18): only the nodes near the probe are
//! integrated implicitly; the others are held where they are.
//!
//! **The physics.** The step is the model's own (implicit Euler, Eq. 1,
//! Newton and PCG on the edge-form matrix, [`crate::integrator`]) on a
//! rectangular patch of the grid around the probe: its unknowns are the
//! *core* nodes, and the patch's outer band of two nodes
//! ([`shape::BAND`], the bending springs' reach) and every node outside the
//! patch are held at their current positions with zero velocity (Dirichlet,
//! as Baraff–Witkin's filter holds the mesh's ends). Every spring of a core
//! node lies in the patch with the constants of the whole mesh's spring, so
//! the core's equations are exactly the full model's with the far field's
//! positions frozen. The full model moves the far field too, and that
//! motion is the window's error: its size is the skin's displacement where
//! the window ends, which decays fast away from the probe (issue 18: at
//! the press peak on 10 112 nodes, everything above 1e-4 of the peak
//! displacement lies within ~100 mm of the probe). The validation against
//! the full model is `crates/contact/tests/suite/window.rs`.
//!
//! **Following the probe** ([`ActiveWindow::follow`], see [`shape`] for
//! the membership rules): the window re-centres when the probe's nearest
//! node is more than the margin from its centre. A node that enters the
//! core starts from its held state (its position, zero velocity); a node
//! that leaves keeps its position and stops (its velocity is set to zero:
//! held nodes have none; at the first placement, so does every node
//! outside the core). Nothing jumps: positions are continuous, and near
//! the probe the equations do not change. Re-centring costs one pass over
//! the patch (its springs' constants are reloaded from the mesh's rest
//! data into the same arrays) and one over the mesh's force buffer; it
//! allocates nothing, so the step never pauses.
//!
//! **The far field** is held, not relaxed: after the probe slides away, a
//! node left beyond `r + m` keeps the small displacement it had there
//! until the window comes back. Gravity acts on the core only (the model's
//! default has none).

mod force;
pub mod shape;

pub use force::{Outer, WindowForce};
pub use shape::{mean_spacing, nearest_node, WindowShape, BAND};

use crate::block_sparse::BlockSparse;
use crate::config::{ConfigError, IntegratorParams, ModelConfig, TissueParams};
use crate::edge_matrix::OUTSIDE;
use crate::force_model::{ForceModel, SumForce};
use crate::integrator::{Dynamics, ImplicitEuler, Kernels, StepStats};
use crate::mesh::SurfaceMesh;
use crate::timings::seconds_since;
use crate::tissue::TissueForces;
use crate::Vec3;
use std::cell::RefCell;
use std::time::Instant;

/// The mesh's state and data that a windowed step reads and updates.
pub struct MeshState<'a> {
    /// The whole mesh.
    pub mesh: &'a SurfaceMesh,
    /// Its positions (m): the core's are updated.
    pub x: &'a mut [Vec3],
    /// Its velocities (m/s): the core's are updated, the band's zeroed.
    pub v: &'a mut [Vec3],
    /// Its lumped masses (kg).
    pub mass: &'a [f64],
    /// Its external forces (N).
    pub external: &'a [Vec3],
    /// Gravity (m/s²).
    pub gravity: Vec3,
}

/// The active window: the patch's system, its data and where it lies.
/// Allocates only in [`Self::new`].
#[derive(Debug, Clone)]
pub struct ActiveWindow {
    shape: WindowShape,
    tissue_params: TissueParams,
    asymptote_margin: f64,
    patch: SurfaceMesh,
    tissue: TissueForces,
    integrator: ImplicitEuler,
    /// Patch node → mesh node.
    map: Vec<usize>,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    external: Vec<Vec3>,
    mass: Vec<f64>,
    /// Held patch nodes: the band and the mesh's fixed nodes.
    held: Vec<bool>,
    f_outer: Vec<Vec3>,
    dx_outer: Vec<Vec3>,
    centre: Option<(usize, usize)>,
    origin: (usize, usize),
    moves: u64,
    /// Time of [`Self::follow`] since the last step (s), reported by it.
    follow_time: f64,
}

impl ActiveWindow {
    /// The window of `config.integrator.window` on `mesh` (not yet placed:
    /// [`Self::follow`] places it). Errors name
    /// `integrator.window.radius` if the patch would wrap the mesh.
    pub fn new(mesh: &SurfaceMesh, config: &ModelConfig) -> Result<Self, ConfigError> {
        let shape = WindowShape::new(mesh, &config.integrator.window, "integrator.window")?;
        let patch = SurfaceMesh::patch(mesh, shape.l_theta, shape.l_z);
        let n = patch.node_count();
        let pattern = BlockSparse::from_pairs(n, patch.coupled_pairs());
        let ip = &config.integrator;
        let tissue = TissueForces::new(
            &patch,
            &config.tissue,
            &pattern,
            ip.asymptote_margin,
            ip.geometric_stiffness_in_compression,
        );
        let mut integrator = ImplicitEuler::new(&pattern);
        integrator
            .edge_matrix_mut()
            .enable_translation(mesh.node_count());
        let outer = vec![Vec3::zeros(); mesh.node_count()];
        Ok(ActiveWindow {
            shape,
            tissue_params: config.tissue.clone(),
            asymptote_margin: ip.asymptote_margin,
            patch,
            tissue,
            integrator,
            map: vec![0; n],
            x: vec![Vec3::zeros(); n],
            v: vec![Vec3::zeros(); n],
            external: vec![Vec3::zeros(); n],
            mass: vec![0.0; n],
            held: vec![true; n],
            f_outer: outer.clone(),
            dx_outer: outer,
            centre: None,
            origin: (0, 0),
            moves: 0,
            follow_time: 0.0,
        })
    }

    /// Follows the probe at `p` (m): re-centres the window on `p`'s
    /// nearest node if it is more than the margin away (or places it the
    /// first time). `v` and `mass` are the mesh's velocities (a node
    /// leaving the core stops) and masses. Returns true if the window
    /// moved. Allocates nothing.
    pub fn follow(&mut self, mesh: &SurfaceMesh, p: &Vec3, v: &mut [Vec3], mass: &[f64]) -> bool {
        let clock = Instant::now();
        let focus = match self.centre {
            Some((ct, cz)) => nearest_node(mesh, p, mesh.node_index(ct, cz)),
            None => nearest_by_scan(mesh, p),
        };
        let focus = mesh.grid_index(focus);
        let moved = match self.centre {
            Some(c) => self.shape.must_move(c, focus, mesh.n_theta()),
            None => true,
        };
        if moved {
            self.place(mesh, focus, v, mass);
        }
        self.follow_time += seconds_since(clock);
        moved
    }

    /// Centres the window on grid node `centre`.
    fn place(&mut self, mesh: &SurfaceMesh, centre: (usize, usize), v: &mut [Vec3], mass: &[f64]) {
        let (nt, nz) = (mesh.n_theta(), mesh.n_z());
        let origin = self.shape.origin(centre, (nt, nz));
        let new_core = |g: usize| core_at(&self.shape, mesh, origin, g);
        match self.centre {
            // Nodes leaving the core stop (held nodes have no velocity).
            Some(_) => {
                for (&g, &held) in self.map.iter().zip(&self.held) {
                    if !held && !new_core(g) {
                        v[g] = Vec3::zeros();
                    }
                }
            }
            // First placement: everything outside the core is held from now.
            None => {
                for (g, vg) in v.iter_mut().enumerate() {
                    if !new_core(g) {
                        *vg = Vec3::zeros();
                    }
                }
            }
        }
        let translation = self.integrator.edge_matrix_mut().translation_mut();
        for &g in &self.map {
            translation[g] = OUTSIDE;
        }
        self.origin = origin;
        self.centre = Some(centre);
        self.patch.load_patch(mesh, origin.0, origin.1);
        self.tissue
            .reload(&self.patch, &self.tissue_params, self.asymptote_margin);
        let lt = self.shape.l_theta;
        for (l, g) in self.map.iter_mut().enumerate() {
            let (jt, jz) = (l % lt, l / lt);
            *g = mesh.node_index(origin.0 + jt, origin.1 + jz);
            translation[*g] = l as u32;
            self.held[l] = self.shape.in_band((jt, jz), origin.1, nz) || mesh.fixed()[*g];
            self.mass[l] = mass[*g];
        }
        // Values a model left on nodes outside the old patch (see `force`).
        self.f_outer.fill(Vec3::zeros());
        // The warm start is in the old patch's numbering.
        self.integrator.reset();
        self.moves += 1;
    }

    /// One implicit step of `h` (s) of the core under the tissue, `extra`
    /// (numbered on the whole mesh) and the external forces; the rest of
    /// the mesh held. The window must have been placed ([`Self::follow`]).
    /// Allocates nothing.
    ///
    /// # Panics
    /// If the window was never placed.
    pub fn step(
        &mut self,
        state: MeshState<'_>,
        h: f64,
        params: &IntegratorParams,
        extra: &mut dyn ForceModel,
    ) -> StepStats {
        assert!(self.centre.is_some(), "the window must be placed first");
        let clock = Instant::now();
        for (l, &g) in self.map.iter().enumerate() {
            self.x[l] = state.x[g];
            self.v[l] = state.v[g];
            self.external[l] = state.external[g];
        }
        let mut window_time = seconds_since(clock) + std::mem::take(&mut self.follow_time);
        let mut outer_model = WindowForce {
            extra,
            map: &self.map,
            outer: RefCell::new(Outer {
                x: state.x,
                v: state.v,
                f: &mut self.f_outer,
                dx: &mut self.dx_outer,
            }),
        };
        let mut forces = SumForce::new(&mut self.tissue, &mut outer_model);
        let sys = Dynamics {
            x: &mut self.x,
            v: &mut self.v,
            mass: &self.mass,
            fixed: &self.held,
            external: &self.external,
            gravity: state.gravity,
        };
        let mut stats = self.integrator.step(sys, h, params, &mut forces);
        stats.timings.move_to_contact(&forces.second_timings);
        let Outer { x, v, .. } = outer_model.outer.into_inner();
        let clock = Instant::now();
        // Held nodes come back as they were (position x₀, velocity 0).
        for (l, &g) in self.map.iter().enumerate() {
            x[g] = self.x[l];
            v[g] = self.v[l];
        }
        window_time += seconds_since(clock);
        stats.timings.window += window_time;
        stats
    }

    /// True once [`Self::follow`] has placed the window.
    pub fn is_placed(&self) -> bool {
        self.centre.is_some()
    }

    /// Grid indices `(i_θ, i_z)` of the window's centre node.
    pub fn centre(&self) -> Option<(usize, usize)> {
        self.centre
    }

    /// How many times the window was placed or re-centred.
    pub fn moves(&self) -> u64 {
        self.moves
    }

    /// True if mesh node `g` of `mesh` is integrated (in the core, not fixed).
    pub fn is_core(&self, mesh: &SurfaceMesh, g: usize) -> bool {
        self.centre.is_some() && core_at(&self.shape, mesh, self.origin, g) && !mesh.fixed()[g]
    }

    /// Number of core nodes (unknowns of the window's solve).
    pub fn core_count(&self) -> usize {
        self.held.iter().filter(|&&h| !h).count()
    }

    /// The patch's nodes (mesh indices), core and band.
    pub fn patch_nodes(&self) -> &[usize] {
        &self.map
    }

    /// The window's shape in cells.
    pub fn shape(&self) -> &WindowShape {
        &self.shape
    }

    /// Chooses the kernels of the window's system (no allocation).
    pub fn set_kernels(&mut self, kernels: Kernels) {
        self.integrator.set_kernels(kernels);
        self.tissue.set_kernels(kernels);
    }

    /// Forgets the warm start (after a reset of the state); the window stays.
    pub fn reset(&mut self) {
        self.integrator.reset();
    }
}

/// True if mesh node `g` is in the core of the patch at `origin`.
fn core_at(shape: &WindowShape, mesh: &SurfaceMesh, origin: (usize, usize), g: usize) -> bool {
    let (nt, nz) = (mesh.n_theta(), mesh.n_z());
    let (it, iz) = mesh.grid_index(g);
    let jt = (it + nt - origin.0) % nt;
    if jt >= shape.l_theta || iz < origin.1 || iz - origin.1 >= shape.l_z {
        return false;
    }
    !shape.in_band((jt, iz - origin.1), origin.1, nz)
}

/// The node nearest (at rest) to `p`, by a scan of the whole mesh (the
/// window's first placement). Node 0 if `p` is not finite.
fn nearest_by_scan(mesh: &SurfaceMesh, p: &Vec3) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (k, x) in mesh.rest_positions().iter().enumerate() {
        let d = (x - p).norm_squared();
        if d < best.0 {
            best = (d, k);
        }
    }
    best.1
}
