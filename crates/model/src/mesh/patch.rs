//! A rectangle of the grid as a mesh of its own: the active window's
//! topology (issue 18, [`crate::window`]).
//!
//! The patch of `l_θ × l_z` nodes has the grid's edges (structural, shear,
//! bending) between its own nodes, not periodic in θ, and its nodes carry
//! the data of the mesh nodes they stand for (rest position, anchor,
//! normal, lumped area, layer scale and stiffness factor): a spring of the
//! patch gets the constants of the mesh's spring between the same nodes.
//! The patch's edges are the mesh's edges between its nodes (a subset:
//! those crossing the patch's border are missing, and so are those closing
//! the circumference if `l_θ ≥ n_θ − 1`; every edge of a node two or more
//! nodes inside the border is present). Moving the patch changes its data,
//! not its topology ([`SurfaceMesh::load_patch`]), so the matrices of a
//! system built on it are allocated once.

use super::{Edge, EdgeKind, SurfaceMesh};
use crate::Vec3;

impl SurfaceMesh {
    /// The `l_θ × l_z` patch of `mesh` at grid offset `(0, 0)` (allocates).
    /// No node of a patch is fixed (the window holds its own).
    ///
    /// # Panics
    /// If `l_θ > n_θ`, `l_z > n_z` or either is below 3.
    pub fn patch(mesh: &SurfaceMesh, l_theta: usize, l_z: usize) -> SurfaceMesh {
        assert!((3..=mesh.n_theta()).contains(&l_theta) && (3..=mesh.n_z()).contains(&l_z));
        let n = l_theta * l_z;
        let idx = |it: usize, iz: usize| iz * l_theta + it;
        let mut triangles = Vec::with_capacity(2 * (l_theta - 1) * (l_z - 1));
        for iz in 0..l_z - 1 {
            for it in 0..l_theta - 1 {
                let (a, b) = (idx(it, iz), idx(it + 1, iz));
                let (c, d) = (idx(it + 1, iz + 1), idx(it, iz + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        let mut edges = Vec::with_capacity(6 * n);
        for iz in 0..l_z {
            for it in 0..l_theta {
                let k = idx(it, iz);
                let mut push = |j: usize, kind| edges.push(Edge { i: k, j, kind });
                if it + 1 < l_theta {
                    push(idx(it + 1, iz), EdgeKind::Structural);
                }
                if it + 2 < l_theta {
                    push(idx(it + 2, iz), EdgeKind::Bending);
                }
                if iz + 1 < l_z {
                    push(idx(it, iz + 1), EdgeKind::Structural);
                    if it + 1 < l_theta {
                        push(idx(it + 1, iz + 1), EdgeKind::Shear);
                    }
                    if it >= 1 {
                        push(idx(it - 1, iz + 1), EdgeKind::Shear);
                    }
                }
                if iz + 2 < l_z {
                    push(idx(it, iz + 2), EdgeKind::Bending);
                }
            }
        }
        let mut geometry = mesh.geometry.clone();
        (geometry.n_theta, geometry.n_z) = (l_theta, l_z);
        let mut patch = SurfaceMesh {
            geometry,
            rest_positions: vec![Vec3::zeros(); n],
            anchors: vec![Vec3::zeros(); n],
            rest_normals: vec![Vec3::zeros(); n],
            areas: vec![0.0; n],
            triangles,
            edges,
            fixed: vec![false; n],
            layer_scale: vec![0.0; n],
            stiffness: vec![0.0; n],
            leg: None,
        };
        patch.load_patch(mesh, 0, 0);
        patch
    }

    /// Loads into this patch the data of `mesh`'s nodes `(θ₀ + j_θ mod
    /// n_θ, z₀ + j_z)`. Allocates nothing.
    ///
    /// # Panics
    /// If the patch does not fit: `z₀ + l_z > n_z` or `l_θ > n_θ`.
    pub fn load_patch(&mut self, mesh: &SurfaceMesh, theta0: usize, z0: usize) {
        let (lt, lz) = (self.n_theta(), self.n_z());
        assert!(z0 + lz <= mesh.n_z() && lt <= mesh.n_theta());
        for jz in 0..lz {
            for jt in 0..lt {
                let (k, g) = (jz * lt + jt, mesh.node_index(theta0 + jt, z0 + jz));
                self.rest_positions[k] = mesh.rest_positions[g];
                self.anchors[k] = mesh.anchors[g];
                self.rest_normals[k] = mesh.rest_normals[g];
                self.areas[k] = mesh.areas[g];
                self.layer_scale[k] = mesh.layer_scale[g];
                self.stiffness[k] = mesh.stiffness[g];
            }
        }
    }
}
