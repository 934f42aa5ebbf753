//! The edge-form system matrix (issue 18): the Newton matrix
//! `M − λhB − λ²h²K` stored as the mesh's springs, not as blocks.
//!
//! Every spring between nodes `i` and `j` contributes one block
//! `E = p d dᵀ + q I` (unit direction `d`, `p` and `q` in the units of the
//! matrix) at `(i, j)` and `(j, i)`, and `−E` to the diagonal blocks of both
//! nodes (a spring's Jacobian, see [`crate::springs`]). The matrix keeps
//!
//! - a dense block diagonal `D_i` (3×3 per node, everything on the diagonal
//!   summed: masses, normal springs, `−E` of every edge, contact);
//! - the edge terms `(i, j, d, p, q)` with `u32` endpoints, 48 bytes each
//!   (against four 72-byte blocks and their 8-byte column indices in
//!   [`BlockSparse`]), written in one streaming pass with no clear;
//! - rank-one terms `c (w ⊗ k)(w ⊗ k)ᵀ` over up to three nodes (a contact
//!   face sample on its triangle: weights `w`, direction `k`); their
//!   diagonal part goes into `D`, the products below apply the rest;
//! - a block-sparse side matrix of the model's pattern for any force model
//!   that only knows [`BlockSparse`] assembly (the [`crate::ForceModel`]
//!   default), used only when such a model wrote into it.
//!
//! **Index translation** (the active window, [`crate::window`]): a
//! matrix can take the terms of a force model that numbers nodes in a
//! larger index space (the whole mesh) while the matrix holds a part of it
//! ([`Self::enable_translation`]). While translating, [`Self::add_diagonal`],
//! [`Self::add_spring`] and [`Self::add_rank_one`] map each node through
//! the translation and drop every block row and column of a node outside
//! the part: those nodes are held (Dirichlet), so their rows and columns
//! are filtered out of the solve anyway (Baraff–Witkin's `S A S`).
//!
//! `y = A x` is then `y_i = D_i x_i + Σ_{e ∋ i} E_e x_{other}` plus the
//! rank-one and side terms: the product reads 48 bytes per edge.

use crate::block_sparse::{BlockSparse, PatternError};
use crate::node_vectors::{add_edge_product, NodeVectors, NodeVectorsMut};
use crate::stencil::{StencilClass, StencilLayout};
use crate::Vec3;
use nalgebra::Matrix3;

/// One spring's off-diagonal block `p d dᵀ + q I` between nodes `i`, `j`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeTerm {
    /// First node.
    pub i: u32,
    /// Second node.
    pub j: u32,
    /// Unit direction `d` (from `i` to `j`; the sign does not matter).
    pub d: [f64; 3],
    /// Coefficient of `d dᵀ`.
    pub p: f64,
    /// Coefficient of `I`.
    pub q: f64,
}

impl EdgeTerm {
    /// `E u = p (d·u) d + q u`.
    #[inline(always)]
    pub fn apply(&self, u: &Vec3) -> Vec3 {
        let [dx, dy, dz] = self.d;
        let s = self.p * (dx * u.x + dy * u.y + dz * u.z);
        Vec3::new(
            s * dx + self.q * u.x,
            s * dy + self.q * u.y,
            s * dz + self.q * u.z,
        )
    }

    /// The block `p d dᵀ + q I`.
    pub fn block(&self) -> Matrix3<f64> {
        let d = Vec3::from(self.d);
        d * d.transpose() * self.p + Matrix3::from_diagonal_element(self.q)
    }
}

/// A rank-one term `c (w ⊗ k)(w ⊗ k)ᵀ` over three nodes: the block
/// `(m, n)` is `c w_m w_n k kᵀ` (a contact face sample on its triangle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RankOneTerm {
    /// Nodes.
    pub nodes: [u32; 3],
    /// Weights on the nodes.
    pub w: [f64; 3],
    /// Direction `k`.
    pub k: [f64; 3],
    /// Coefficient `c`.
    pub c: f64,
}

/// The edge-form matrix of `n` nodes (see the module docs).
#[derive(Debug, Clone)]
pub struct EdgeMatrix {
    diag: Vec<Matrix3<f64>>,
    edges: Vec<EdgeTerm>,
    layout: StencilLayout,
    stencil: Vec<StencilClass>,
    stencil_active: bool,
    rank_one: Vec<RankOneTerm>,
    side: BlockSparse,
    side_active: bool,
    side_dirty: bool,
    /// Outer node index → own index (`u32::MAX`: not in this matrix).
    translation: Vec<u32>,
    translating: bool,
}

/// [`EdgeMatrix`]'s translation of a node outside the matrix.
pub const OUTSIDE: u32 = u32::MAX;

impl EdgeMatrix {
    /// A matrix for the nodes of `pattern` (whose pattern the side matrix
    /// takes), with room for one edge per coupled pair of the pattern and
    /// `rank_one_capacity` rank-one terms; more of either go into the side
    /// matrix. Allocates once.
    pub fn new(pattern: &BlockSparse, rank_one_capacity: usize) -> Self {
        let n = pattern.n();
        let mut side = pattern.clone();
        side.clear();
        let layout = StencilLayout::from_pattern(pattern);
        EdgeMatrix {
            diag: vec![Matrix3::zeros(); n],
            edges: Vec::with_capacity((pattern.nnz_blocks() - n) / 2),
            stencil: StencilClass::for_layout(&layout),
            layout,
            stencil_active: false,
            rank_one: Vec::with_capacity(rank_one_capacity),
            side,
            side_active: false,
            side_dirty: false,
            translation: Vec::new(),
            translating: false,
        }
    }

    /// Prepares the translation from an outer index space of `outer_n`
    /// nodes (every node [`OUTSIDE`] until set through
    /// [`Self::translation_mut`]). Allocates (once, at set-up).
    pub fn enable_translation(&mut self, outer_n: usize) {
        self.translation = vec![OUTSIDE; outer_n];
    }

    /// The translation, outer index → own index or [`OUTSIDE`].
    pub fn translation_mut(&mut self) -> &mut [u32] {
        &mut self.translation
    }

    /// Turns the translation on or off for the terms added next (see the
    /// module docs).
    ///
    /// # Panics
    /// If turned on before [`Self::enable_translation`].
    pub fn set_translating(&mut self, on: bool) {
        assert!(
            !on || !self.translation.is_empty(),
            "no translation enabled"
        );
        self.translating = on;
    }

    /// Own index of node `i` (`None` if outside), translated if translating.
    #[inline(always)]
    fn own(&self, i: usize) -> Option<usize> {
        if !self.translating {
            return Some(i);
        }
        let t = self.translation[i];
        (t != OUTSIDE).then_some(t as usize)
    }

    /// Number of nodes.
    pub fn n(&self) -> usize {
        self.diag.len()
    }

    /// Starts an assembly: `D_i = d_i I` (e.g. the masses, kg), no edges,
    /// no rank-one terms, the side matrix unused. Allocates nothing.
    ///
    /// # Panics
    /// If `d.len() != self.n()`.
    pub fn begin(&mut self, d: &[f64]) {
        assert_eq!(d.len(), self.n());
        for (m, &di) in self.diag.iter_mut().zip(d) {
            *m = Matrix3::from_diagonal_element(di);
        }
        self.edges.clear();
        self.rank_one.clear();
        self.side_active = false;
        self.stencil_active = false;
    }

    /// The grid stencil's layout (the classes of [`Self::stencil_mut`]).
    pub fn stencil_layout(&self) -> &StencilLayout {
        &self.layout
    }

    /// The stencil classes and the diagonal blocks, for a force model that
    /// writes its springs by class (the SIMD tissue): from this call to the
    /// next [`Self::begin`] the classes are part of the matrix, and the
    /// caller must write every slot (zero where it has no spring).
    pub fn stencil_mut(&mut self) -> (&mut [StencilClass], &mut [Matrix3<f64>]) {
        self.stencil_active = true;
        (&mut self.stencil, &mut self.diag)
    }

    /// The stencil classes, if a model wrote them during this assembly.
    pub fn stencil(&self) -> Option<&[StencilClass]> {
        self.stencil_active.then_some(&self.stencil[..])
    }

    /// Adds `block` to the diagonal block of node `i`.
    #[inline]
    pub fn add_diagonal(&mut self, i: usize, block: &Matrix3<f64>) {
        if let Some(i) = self.own(i) {
            self.diag[i] += block;
        }
    }

    /// Adds a spring's term: `E = p d dᵀ + q I` at `(i, j)` and `(j, i)`,
    /// `−E` on both diagonal blocks. Past the edge capacity the blocks go
    /// into the side matrix (an error if `(i, j)` is not in its pattern).
    #[inline]
    pub fn add_spring(
        &mut self,
        i: usize,
        j: usize,
        d: &Vec3,
        p: f64,
        q: f64,
    ) -> Result<(), PatternError> {
        let (i, j) = match (self.own(i), self.own(j)) {
            (Some(i), Some(j)) => (i, j),
            (one, other) => {
                // A held endpoint: only the other node's diagonal block.
                if let Some(k) = one.or(other) {
                    self.diag[k] -= EdgeTerm {
                        i: 0,
                        j: 0,
                        d: [d.x, d.y, d.z],
                        p,
                        q,
                    }
                    .block();
                }
                return Ok(());
            }
        };
        let e = EdgeTerm {
            i: i as u32,
            j: j as u32,
            d: [d.x, d.y, d.z],
            p,
            q,
        };
        let [dx, dy, dz] = e.d;
        let di = &mut self.diag[i];
        let (a, b, c) = (p * dx, p * dy, p * dz);
        let m = Matrix3::new(
            a * dx + q,
            a * dy,
            a * dz,
            b * dx,
            b * dy + q,
            b * dz,
            c * dx,
            c * dy,
            c * dz + q,
        );
        *di -= m;
        self.diag[j] -= m;
        if self.edges.len() < self.edges.capacity() {
            self.edges.push(e);
            Ok(())
        } else {
            let side = self.side_mut();
            side.add_block(i, j, &m)?;
            side.add_block(j, i, &m)
        }
    }

    /// Adds `c (w ⊗ k)(w ⊗ k)ᵀ` over `nodes` (blocks `c w_m w_n k kᵀ`).
    /// Past the rank-one capacity the off-diagonal blocks go into the side
    /// matrix (an error if a pair is not in its pattern).
    pub fn add_rank_one(
        &mut self,
        nodes: [usize; 3],
        w: [f64; 3],
        k: &Vec3,
        c: f64,
    ) -> Result<(), PatternError> {
        // Held nodes drop out: weight 0 on some node of the term.
        let own = nodes.map(|m| self.own(m));
        let Some(any) = own.iter().flatten().next().copied() else {
            return Ok(());
        };
        let nodes = own.map(|m| m.unwrap_or(any));
        let w = [0, 1, 2].map(|r| if own[r].is_some() { w[r] } else { 0.0 });
        let kk = k * k.transpose();
        for (&m, &wm) in nodes.iter().zip(&w) {
            self.diag[m] += kk * (c * wm * wm);
        }
        if self.rank_one.len() < self.rank_one.capacity() {
            self.rank_one.push(RankOneTerm {
                nodes: nodes.map(|m| m as u32),
                w,
                k: [k.x, k.y, k.z],
                c,
            });
            return Ok(());
        }
        // `nodes` are this matrix's own indices (translated above), so the
        // side matrix takes them while translating too.
        let side = self.side_in_own_indices();
        for r in 0..3 {
            for s in 0..3 {
                if r != s {
                    side.add_block(nodes[r], nodes[s], &(kk * (c * w[r] * w[s])))?;
                }
            }
        }
        Ok(())
    }

    /// The side matrix (the model's block pattern), zeroed on the first
    /// call of an assembly; whatever is added to it joins the matrix.
    ///
    /// # Panics
    /// While translating (the side matrix is in this matrix's indices).
    pub fn side_mut(&mut self) -> &mut BlockSparse {
        assert!(
            !self.translating,
            "a translated force model must assemble edge terms, not the side matrix"
        );
        self.side_in_own_indices()
    }

    /// [`Self::side_mut`] for terms already in this matrix's own indices.
    fn side_in_own_indices(&mut self) -> &mut BlockSparse {
        if !self.side_active {
            if self.side_dirty {
                self.side.clear();
            }
            self.side_active = true;
            self.side_dirty = true;
        }
        &mut self.side
    }

    /// Ends an assembly: moves the side matrix's diagonal blocks into `D`.
    pub fn finish(&mut self) {
        if self.side_active {
            for i in 0..self.diag.len() {
                let k = self.side.diagonal_index(i);
                let block = self.side.values()[k];
                self.diag[i] += block;
                self.side.values_mut()[k] = Matrix3::zeros();
            }
        }
    }

    /// Adds `s` to every diagonal block's `d_i I` part: `D_i += s_i I`.
    ///
    /// # Panics
    /// If `s.len() != self.n()`.
    pub fn add_to_diagonal(&mut self, s: &[f64]) {
        assert_eq!(s.len(), self.n());
        for (m, &si) in self.diag.iter_mut().zip(s) {
            m[(0, 0)] += si;
            m[(1, 1)] += si;
            m[(2, 2)] += si;
        }
    }

    /// The dense block diagonal `D`.
    pub fn diagonal(&self) -> &[Matrix3<f64>] {
        &self.diag
    }

    /// The edge terms.
    pub fn edges(&self) -> &[EdgeTerm] {
        &self.edges
    }

    /// The rank-one terms.
    pub fn rank_one_terms(&self) -> &[RankOneTerm] {
        &self.rank_one
    }

    /// The side matrix, if a model wrote into it during this assembly.
    pub fn side(&self) -> Option<&BlockSparse> {
        self.side_active.then_some(&self.side)
    }

    /// `y += (A − D) x` and returns `xᵀ (A − D) x`: the edge, rank-one and
    /// side terms (the off-diagonal part; `D` is applied by the caller, in
    /// its node pass). Allocates nothing.
    pub fn add_off_diagonal_product(&self, x: &[Vec3], y: &mut [Vec3]) -> f64 {
        let mut xax = add_edge_product(&self.edges, x, y) + self.add_coupling_product(x, y);
        if let Some(classes) = self.stencil() {
            for c in classes {
                xax += c.add_product(&self.layout, x, y);
            }
        }
        xax
    }

    /// `y += C x` and returns `xᵀ C x` for `C` the rank-one and side terms
    /// alone (off-diagonal blocks; the SIMD kernels apply the springs
    /// themselves). Allocates nothing.
    pub fn add_coupling_product<X, Y>(&self, x: &X, y: &mut Y) -> f64
    where
        X: NodeVectors + ?Sized,
        Y: NodeVectorsMut + ?Sized,
    {
        let mut xax = 0.0;
        for t in &self.rank_one {
            let k = Vec3::from(t.k);
            let kx = t.nodes.map(|m| k.dot(&x.at(m as usize)));
            let s = t.w[0] * kx[0] + t.w[1] * kx[1] + t.w[2] * kx[2];
            for (r, &kxr) in kx.iter().enumerate() {
                // Row r, off-diagonal: c w_r k Σ_{n≠r} w_n k·x_n.
                let off = s - t.w[r] * kxr;
                y.add_at(t.nodes[r] as usize, k * (t.c * t.w[r] * off));
                xax += t.c * t.w[r] * kxr * off;
            }
        }
        if self.side_active {
            // Off-diagonal blocks only (`finish` moved the diagonal into D).
            for i in 0..self.n() {
                let (cols, blocks) = self.side.row(i);
                let mut acc = Vec3::zeros();
                for (&j, m) in cols.iter().zip(blocks) {
                    acc += m * x.at(j);
                }
                y.add_at(i, acc);
                xax += x.at(i).dot(&acc);
            }
        }
        xax
    }

    /// `y = A x` (a plain product, for tests and single products).
    ///
    /// # Panics
    /// If `x` or `y` is not of length [`Self::n`].
    pub fn mul_vec(&self, x: &[Vec3], y: &mut [Vec3]) {
        assert!(x.len() == self.n() && y.len() == self.n());
        for ((yi, d), xi) in y.iter_mut().zip(&self.diag).zip(x) {
            *yi = d * xi;
        }
        self.add_off_diagonal_product(x, y);
    }

    /// The same matrix in block-sparse form on `pattern` (tests; every edge
    /// must be a pair of the pattern).
    pub fn to_block_sparse(&self, pattern: &BlockSparse) -> Result<BlockSparse, PatternError> {
        let mut a = pattern.clone();
        a.clear();
        for (i, d) in self.diag.iter().enumerate() {
            a.add_diagonal(i, d);
        }
        let stencil_edges = self
            .stencil()
            .into_iter()
            .flatten()
            .flat_map(|c| c.terms(&self.layout));
        for e in self.edges.iter().copied().chain(stencil_edges) {
            let b = e.block();
            a.add_block(e.i as usize, e.j as usize, &b)?;
            a.add_block(e.j as usize, e.i as usize, &b)?;
        }
        for t in &self.rank_one {
            let k = Vec3::from(t.k);
            let kk = k * k.transpose();
            for r in 0..3 {
                for s in 0..3 {
                    if r != s {
                        let (m, n) = (t.nodes[r] as usize, t.nodes[s] as usize);
                        a.add_block(m, n, &(kk * (t.c * t.w[r] * t.w[s])))?;
                    }
                }
            }
        }
        if self.side_active {
            for i in 0..self.n() {
                let (cols, blocks) = self.side.row(i);
                for (&j, m) in cols.iter().zip(blocks) {
                    if j != i {
                        a.add_block(i, j, m)?;
                    }
                }
            }
        }
        Ok(a)
    }
}
