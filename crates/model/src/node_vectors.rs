//! Vectors of 3-vectors by node in either layout — an array of
//! structures (`[Vec3]`) or a structure of arrays
//! ([`crate::stencil::Soa3`]) — for the scalar kernels that both the
//! scalar and the SIMD paths run (issue 18).

use crate::edge_matrix::EdgeTerm;
use crate::Vec3;

/// Read access to a vector of 3-vectors by node (array of structures or
/// structure of arrays), for the kernels shared by both layouts.
pub trait NodeVectors {
    /// The value at node `k`.
    fn at(&self, k: usize) -> Vec3;
}

/// Accumulating access to a vector of 3-vectors by node.
pub trait NodeVectorsMut: NodeVectors {
    /// `self[k] += v`.
    fn add_at(&mut self, k: usize, v: Vec3);
}

impl NodeVectors for [Vec3] {
    #[inline(always)]
    fn at(&self, k: usize) -> Vec3 {
        self[k]
    }
}

impl NodeVectorsMut for [Vec3] {
    #[inline(always)]
    fn add_at(&mut self, k: usize, v: Vec3) {
        self[k] += v;
    }
}

/// `y += Σ_e (E_e x_j at i, E_e x_i at j)` over `edges` and returns their
/// share of `xᵀ A x`, `Σ 2 x_iᵀ E_e x_j`. Allocates nothing.
pub fn add_edge_product<X, Y>(edges: &[EdgeTerm], x: &X, y: &mut Y) -> f64
where
    X: NodeVectors + ?Sized,
    Y: NodeVectorsMut + ?Sized,
{
    let mut xax = 0.0;
    // Edges come grouped by their first node (the mesh lists a node's
    // springs together): row i's sum stays in a register while its
    // group lasts, so consecutive edges do not wait on each other's
    // store to y[i], and the group's share of xᵀAx is 2 x_iᵀ Σ E x_j.
    let mut row = usize::MAX;
    let (mut xi, mut acc) = (Vec3::zeros(), Vec3::zeros());
    for e in edges {
        let (i, j) = (e.i as usize, e.j as usize);
        if i != row {
            if row != usize::MAX {
                y.add_at(row, acc);
                xax += 2.0 * xi.dot(&acc);
            }
            row = i;
            xi = x.at(i);
            acc = Vec3::zeros();
        }
        acc += e.apply(&x.at(j));
        y.add_at(j, e.apply(&xi));
    }
    if row != usize::MAX {
        y.add_at(row, acc);
        xax += 2.0 * xi.dot(&acc);
    }
    xax
}
