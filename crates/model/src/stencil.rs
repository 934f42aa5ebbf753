//! The grid stencil of the edge-form matrix (issue 18, SIMD kernels): the
//! mesh's springs grouped by the offset `o = j − i` of their endpoints, in
//! structure-of-arrays form indexed by node, so that four consecutive nodes
//! read four consecutive values of every array (one four-lane load).
//!
//! On the `n_θ × n_z` grid (node `k = i_z n_θ + i_θ`) every spring family
//! has one offset over whole runs of nodes: `+1` and `+2` around, `+n_θ`
//! and `+2n_θ` along, `n_θ ± 1` across; the springs across the θ seam fall
//! into other offsets or into those classes at nodes the family leaves
//! empty. [`StencilLayout::from_pattern`] takes as a class every offset
//! held by at least a quarter as many node pairs as there are nodes (at
//! most [`MAX_CLASSES`]); a spring of another offset, or a second spring on
//! an occupied slot, is a *leftover* applied one by one.
//!
//! In class `c` of offset `o`, slot `k` holds the spring between `k` and
//! `k + o` (zero if there is none). The matrix product then *pulls*:
//!
//! `y_k = D_k x_k + Σ_c (E_c[k] x_{k+o_c} + E_c[k−o_c] x_{k−o_c})`,
//!
//! with no scatter and no index: every array is padded by `o_max` zeros on
//! both sides (and the nodes rounded up to a multiple of [`CHUNK`]), so the
//! shifted reads never leave it and every chunk is full.

use crate::block_sparse::BlockSparse;
use crate::edge_matrix::{EdgeMatrix, EdgeTerm};
use crate::node_vectors::{NodeVectors, NodeVectorsMut};
use crate::Vec3;

/// Most offset classes a layout keeps (the grid has six).
pub const MAX_CLASSES: usize = 8;

/// Nodes are processed in chunks of this many (a multiple of every lane count).
pub const CHUNK: usize = 8;

/// Which offsets are classes, and the padded index space (see module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StencilLayout {
    n: usize,
    offsets: Vec<usize>,
    pad: usize,
    rounded: usize,
}

impl StencilLayout {
    /// The classes of `pattern`'s node pairs `(i, j > i)` (see module docs).
    pub fn from_pattern(pattern: &BlockSparse) -> Self {
        let n = pattern.n();
        let mut counts = std::collections::BTreeMap::<usize, usize>::new();
        for i in 0..n {
            for &j in pattern.row(i).0.iter().filter(|&&j| j > i) {
                *counts.entry(j - i).or_default() += 1;
            }
        }
        let mut big: Vec<(usize, usize)> =
            counts.into_iter().filter(|&(_, c)| 4 * c >= n).collect();
        // The most populated classes first, then back in offset order.
        big.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        big.truncate(MAX_CLASSES);
        let mut offsets: Vec<usize> = big.into_iter().map(|(o, _)| o).collect();
        offsets.sort_unstable();
        let pad = offsets.last().copied().unwrap_or(0);
        StencilLayout {
            n,
            offsets,
            pad,
            rounded: n.div_ceil(CHUNK) * CHUNK,
        }
    }

    /// Number of nodes.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The class offsets, ascending.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Zeros before node 0 (the largest offset).
    pub fn pad(&self) -> usize {
        self.pad
    }

    /// Nodes processed: `n` rounded up to a multiple of [`CHUNK`].
    pub fn rounded(&self) -> usize {
        self.rounded
    }

    /// Length of every padded array.
    pub fn len(&self) -> usize {
        2 * self.pad + self.rounded
    }

    /// True if the layout has no nodes.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The class and slot of a spring between `i` and `j`, if its offset is a class.
    #[inline]
    pub fn slot(&self, i: usize, j: usize) -> Option<(usize, usize)> {
        let (lo, hi) = if i < j { (i, j) } else { (j, i) };
        let o = hi - lo;
        self.offsets
            .iter()
            .position(|&c| c == o)
            .map(|c| (c, self.pad + lo))
    }
}

/// Three padded arrays (x, y, z components) of a node vector; the padding
/// stays zero.
#[derive(Debug, Clone)]
pub struct Soa3 {
    /// Components, each of [`StencilLayout::len`] values, node `k` at `pad + k`.
    pub c: [Vec<f64>; 3],
    pad: usize,
}

impl Soa3 {
    /// Zeros in `layout`'s index space (allocates).
    pub fn new(layout: &StencilLayout) -> Self {
        let z = vec![0.0; layout.len()];
        Soa3 {
            c: [z.clone(), z.clone(), z],
            pad: layout.pad(),
        }
    }

    /// Copies `v` in (node `k` to `pad + k`); the padding is untouched.
    pub fn load(&mut self, v: &[Vec3]) {
        let [a, b, c] = &mut self.c;
        let p = self.pad;
        for (k, vk) in v.iter().enumerate() {
            a[p + k] = vk.x;
            b[p + k] = vk.y;
            c[p + k] = vk.z;
        }
    }

    /// Copies the nodes out into `v`.
    pub fn store(&self, v: &mut [Vec3]) {
        for (k, vk) in v.iter_mut().enumerate() {
            *vk = self.at(k);
        }
    }

    /// Sets every value (padding included) to zero.
    pub fn clear(&mut self) {
        for c in &mut self.c {
            c.fill(0.0);
        }
    }
}

impl NodeVectors for Soa3 {
    #[inline(always)]
    fn at(&self, k: usize) -> Vec3 {
        let i = self.pad + k;
        Vec3::new(self.c[0][i], self.c[1][i], self.c[2][i])
    }
}

impl NodeVectorsMut for Soa3 {
    #[inline(always)]
    fn add_at(&mut self, k: usize, v: Vec3) {
        let i = self.pad + k;
        self.c[0][i] += v.x;
        self.c[1][i] += v.y;
        self.c[2][i] += v.z;
    }
}

/// One class's slots: the spring `p d dᵀ + q I` between `k` and `k + offset`.
#[derive(Debug, Clone)]
pub struct StencilClass {
    /// Offset `o` (nodes).
    pub offset: usize,
    /// Direction components `d` per slot.
    pub d: [Vec<f64>; 3],
    /// Coefficient of `d dᵀ` per slot (0: no spring).
    pub p: Vec<f64>,
    /// Coefficient of `I` per slot (0: no spring).
    pub q: Vec<f64>,
}

impl StencilClass {
    /// Zeroed classes of `layout` (allocates).
    pub fn for_layout(layout: &StencilLayout) -> Vec<StencilClass> {
        let z = vec![0.0; layout.len()];
        layout
            .offsets()
            .iter()
            .map(|&offset| StencilClass {
                offset,
                d: [z.clone(), z.clone(), z.clone()],
                p: z.clone(),
                q: z.clone(),
            })
            .collect()
    }

    /// The springs held (slots with `p` or `q` nonzero) as edge terms.
    pub fn terms<'a>(&'a self, layout: &'a StencilLayout) -> impl Iterator<Item = EdgeTerm> + 'a {
        let pad = layout.pad();
        (0..layout.n().saturating_sub(self.offset))
            .filter(move |&k| self.p[pad + k] != 0.0 || self.q[pad + k] != 0.0)
            .map(move |k| EdgeTerm {
                i: k as u32,
                j: (k + self.offset) as u32,
                d: [self.d[0][pad + k], self.d[1][pad + k], self.d[2][pad + k]],
                p: self.p[pad + k],
                q: self.q[pad + k],
            })
    }

    /// `y += (this class's springs) x` one by one (scalar; tests and the
    /// scalar kernels), returning their share of `xᵀ A x`.
    pub fn add_product<X, Y>(&self, layout: &StencilLayout, x: &X, y: &mut Y) -> f64
    where
        X: NodeVectors + ?Sized,
        Y: NodeVectorsMut + ?Sized,
    {
        let mut xax = 0.0;
        for e in self.terms(layout) {
            let (i, j) = (e.i as usize, e.j as usize);
            let (xi, xj) = (x.at(i), x.at(j));
            let ej = e.apply(&xj);
            y.add_at(i, ej);
            y.add_at(j, e.apply(&xi));
            xax += 2.0 * xi.dot(&ej);
        }
        xax
    }
}

/// The edge-form matrix repacked for the SIMD kernels: the diagonal blocks
/// as nine arrays (entry `(r, c)` in `diag[3 r + c]`), the classes, and the
/// springs left over; [`EdgeMatrix`] keeps its rank-one terms and side
/// matrix, applied from there.
#[derive(Debug, Clone)]
pub struct StencilMatrix {
    layout: StencilLayout,
    /// Diagonal blocks, row-major entries, padded.
    pub diag: [Vec<f64>; 9],
    /// The classes, in the layout's order.
    pub classes: Vec<StencilClass>,
    /// Springs in no class slot.
    pub leftover: Vec<EdgeTerm>,
    /// True if the classes to use are the matrix's own ([`EdgeMatrix::stencil`]),
    /// not [`Self::classes`].
    pub external: bool,
}

impl StencilMatrix {
    /// Zeroed arrays for `layout` (allocates once; room for as many
    /// leftovers as `capacity`).
    pub fn new(layout: &StencilLayout, capacity: usize) -> Self {
        let z = vec![0.0; layout.len()];
        StencilMatrix {
            diag: std::array::from_fn(|_| z.clone()),
            classes: StencilClass::for_layout(layout),
            external: false,
            leftover: Vec::with_capacity(capacity),
            layout: layout.clone(),
        }
    }

    /// The layout.
    pub fn layout(&self) -> &StencilLayout {
        &self.layout
    }

    /// Copies `a`'s diagonal and springs in (its rank-one terms and side
    /// matrix stay with `a`). Allocates nothing while the leftovers fit the
    /// capacity given to [`Self::new`].
    ///
    /// # Panics
    /// If `a` has another number of nodes.
    pub fn pack(&mut self, a: &EdgeMatrix) {
        assert_eq!(a.n(), self.layout.n());
        let pad = self.layout.pad();
        for (k, m) in a.diagonal().iter().enumerate() {
            for r in 0..3 {
                for c in 0..3 {
                    self.diag[3 * r + c][pad + k] = m[(r, c)];
                }
            }
        }
        self.leftover.clear();
        self.external = a.stencil().is_some();
        if self.external {
            // The springs are in the matrix's classes already.
            self.leftover.extend_from_slice(a.edges());
            return;
        }
        for class in &mut self.classes {
            class.p.fill(0.0);
            class.q.fill(0.0);
        }
        for e in a.edges() {
            let slot = self.layout.slot(e.i as usize, e.j as usize);
            match slot {
                Some((c, s)) if self.classes[c].p[s] == 0.0 && self.classes[c].q[s] == 0.0 => {
                    let class = &mut self.classes[c];
                    for r in 0..3 {
                        class.d[r][s] = e.d[r];
                    }
                    class.p[s] = e.p;
                    class.q[s] = e.q;
                }
                _ => self.leftover.push(*e),
            }
        }
    }
}
