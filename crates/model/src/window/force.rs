//! An extra force model of the whole mesh (the probe contact), seen from
//! the window's patch: the patch's iterate is written into the mesh's
//! state, the model evaluated there, and its terms brought back to the
//! patch's nodes (issue 18).
//!
//! Forces: the model adds into a mesh-sized buffer; the patch's entries are
//! taken and zeroed after each call. A model writing to a node outside the
//! patch (a held node: its force would be a reaction, not a load) leaves a
//! value there that no patch node reads; the window clears the whole buffer
//! when it moves, before any such node can join. Jacobians: the model
//! writes into the patch's edge matrix through its index translation
//! ([`EdgeMatrix::enable_translation`]), which drops the rows and columns
//! of held nodes outside the patch, as the Dirichlet filter would.

use crate::block_sparse::BlockSparse;
use crate::edge_matrix::EdgeMatrix;
use crate::force_model::{ForceModel, JacobianScratch};
use crate::Vec3;
use std::cell::RefCell;

/// The mesh-sized arrays the adapter writes through.
pub struct Outer<'a> {
    /// The mesh's positions (m): the patch's nodes get the iterate's.
    pub x: &'a mut [Vec3],
    /// The mesh's velocities (m/s), as `x`.
    pub v: &'a mut [Vec3],
    /// Force buffer (N), zero on the patch's nodes between calls.
    pub f: &'a mut [Vec3],
    /// Path buffer (m) of the step limiter, zero off the patch's nodes.
    pub dx: &'a mut [Vec3],
}

/// `extra` (numbered on the whole mesh) as a force model of the patch
/// whose node `l` is mesh node `map[l]`.
pub struct WindowForce<'a> {
    /// The model on the whole mesh.
    pub extra: &'a mut dyn ForceModel,
    /// Patch node → mesh node.
    pub map: &'a [usize],
    /// The mesh-sized arrays (a cell: the step limiter takes `&self`).
    pub outer: RefCell<Outer<'a>>,
}

impl WindowForce<'_> {
    /// Writes the patch's `x` and `v` into the mesh's state.
    fn scatter(&mut self, x: &[Vec3], v: &[Vec3]) {
        let o = self.outer.get_mut();
        for ((&g, xl), vl) in self.map.iter().zip(x).zip(v) {
            o.x[g] = *xl;
            o.v[g] = *vl;
        }
    }
}

impl ForceModel for WindowForce<'_> {
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        self.scatter(x, v);
        let o = self.outer.get_mut();
        self.extra.add_forces(o.x, o.v, o.f);
        for (&g, fl) in self.map.iter().zip(f.iter_mut()) {
            *fl += o.f[g];
            o.f[g] = Vec3::zeros();
        }
    }

    /// The window assembles in edge form only
    /// ([`Self::add_scaled_jacobians_edge`]).
    ///
    /// # Panics
    /// Always: a block-sparse matrix of the patch cannot take a mesh
    /// model's blocks.
    fn add_jacobians(&mut self, _: &[Vec3], _: &[Vec3], _: &mut BlockSparse, _: &mut BlockSparse) {
        panic!("the active window assembles its system in edge form only");
    }

    /// See [`Self::add_jacobians`].
    ///
    /// # Panics
    /// Always.
    fn add_scaled_jacobians(
        &mut self,
        _: &[Vec3],
        _: &[Vec3],
        _: f64,
        _: f64,
        _: &mut BlockSparse,
        _: &mut JacobianScratch,
    ) {
        panic!("the active window assembles its system in edge form only");
    }

    /// The model's terms, translated to the patch (see the module docs).
    /// The model must write edge terms (a model that only knows the
    /// block-sparse side matrix panics there).
    fn add_scaled_jacobians_edge(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut EdgeMatrix,
        scratch: &mut JacobianScratch,
    ) {
        self.scatter(x, v);
        let o = self.outer.get_mut();
        a.set_translating(true);
        self.extra
            .add_scaled_jacobians_edge(o.x, o.v, alpha, beta, a, scratch);
        a.set_translating(false);
    }

    fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3]) -> f64 {
        let mut o = self.outer.borrow_mut();
        let o = &mut *o;
        for ((&g, xl), dl) in self.map.iter().zip(x).zip(dx) {
            o.x[g] = *xl;
            o.dx[g] = *dl;
        }
        let alpha = self.extra.max_step_fraction(o.x, o.dx);
        for &g in self.map {
            o.dx[g] = Vec3::zeros();
        }
        alpha
    }
}
