//! The two-level preconditioner trial (issue 18): block-Jacobi plus an
//! additive coarse correction on the mesh's θ × z grid,
//!
//! ```text
//! z = D⁻¹ r + P A_c⁻¹ Pᵀ r,    A_c = Pᵀ S A S P
//! ```
//!
//! (Toselli & Widlund, *Domain Decomposition Methods*, §2.2 and §3.10: the
//! additive two-level Schwarz method with a Galerkin coarse space; `S`
//! zeroes the Dirichlet nodes as the conjugate gradient does). `P` is the
//! piecewise-constant prolongation of aggregates: patches of about
//! `s × s` grid nodes (θ periodic, z open), each coarse node carrying a
//! rigid translation of its patch (3 unknowns). Both terms are symmetric
//! positive (semi-)definite, so `z` is a symmetric positive definite
//! preconditioner for CG.
//!
//! `A_c` is assembled per Newton matrix from the edge form (a pass over the
//! diagonal blocks and the springs: `D_i` into `(I, I)`, a spring's `E`
//! into `(I, J)` and `(J, I)`, or `2E` into `(I, I)` inside a patch) and
//! factored by a banded Cholesky. The coarse nodes are ordered so the band
//! is narrow on a cylinder: z outer and θ folded (`0, 1, n−1, 2, n−2, …`,
//! so θ-neighbours, the periodic pair included, are at most two apart), or
//! θ outer when that band is narrower. Factor `n_c b²/2` flops, solve
//! `2 n_c b` (`n_c` coarse unknowns, `b` their half-bandwidth).

use crate::block_sparse::BlockSparse;
use crate::edge_matrix::EdgeMatrix;
use crate::stencil::Soa3;
use crate::Vec3;
use nalgebra::Matrix3;

/// Why a coarse matrix could not be factored.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("coarse matrix not positive definite at unknown {index} (pivot {pivot})")]
pub struct NotPositiveDefinite {
    /// Scalar unknown of the failing pivot.
    pub index: usize,
    /// Its value before the square root.
    pub pivot: f64,
}

/// The aggregates of an `n_θ × n_z` grid and the coarse band storage.
#[derive(Debug, Clone)]
pub struct TwoLevel {
    /// Coarse node (band order) of each fine node.
    coarse_of: Vec<u32>,
    /// Coarse nodes.
    nc: usize,
    /// Scalar half-bandwidth `b`.
    bw: usize,
    /// Lower band, row `i` holding columns `i − b ..= i` at
    /// `i (b + 1) + (j − i + b)`: `A_c`, then its Cholesky factor `L`.
    band: Vec<f64>,
    /// Free fine nodes per coarse node (an empty aggregate gets `I`).
    free_count: Vec<u32>,
    /// The coarse right-hand side, then the coarse solution.
    rc: Vec<f64>,
}

/// Patch index of grid line `i` of `n` lines in `m` patches of ≥ 2 lines
/// (sizes differ by at most one).
fn patch_of(i: usize, n: usize, m: usize) -> usize {
    i * m / n
}

/// Position of θ-patch `t` of `m` in the folded order `0, 1, m−1, 2, m−2, …`.
fn folded(t: usize, m: usize) -> usize {
    if t == 0 {
        0
    } else if 2 * t <= m {
        2 * t - 1
    } else {
        2 * (m - t)
    }
}

impl TwoLevel {
    /// Aggregates of about `patch × patch` nodes on an `n_theta × n_z` grid
    /// (node `k` at `θ = k mod n_θ`, `z = k div n_θ`), at least `patch`
    /// lines per patch in each direction; the band is as wide as the
    /// couplings of `pattern` (the matrices' block pattern) require.
    /// Allocates once.
    ///
    /// # Panics
    /// If `patch < 2`, or `pattern` has not `n_theta · n_z` nodes.
    pub fn new(n_theta: usize, n_z: usize, patch: usize, pattern: &BlockSparse) -> Self {
        assert!(patch >= 2 && pattern.n() == n_theta * n_z);
        let mt = (n_theta / patch).max(1);
        let mz = (n_z / patch).max(1);
        // z outer, θ folded inner: neighbours within 2 θ-positions and one
        // z-row (m_θ positions); or θ outer (folded), z inner.
        let z_outer = mt + 2 <= 2 * mz + 1;
        let coarse = |it: usize, iz: usize| {
            let (t, z) = (patch_of(it, n_theta, mt), patch_of(iz, n_z, mz));
            if z_outer {
                z * mt + folded(t, mt)
            } else {
                folded(t, mt) * mz + z
            }
        };
        let coarse_of: Vec<u32> = (0..n_theta * n_z)
            .map(|k| coarse(k % n_theta, k / n_theta) as u32)
            .collect();
        let nc = mt * mz;
        let nodes_bw = (0..pattern.n())
            .flat_map(|i| pattern.row(i).0.iter().map(move |&j| (i, j)))
            .map(|(i, j)| coarse_of[i].abs_diff(coarse_of[j]) as usize)
            .max()
            .unwrap_or(0);
        let bw = 3 * nodes_bw + 2;
        TwoLevel {
            coarse_of,
            nc,
            bw,
            band: vec![0.0; 3 * nc * (bw + 1)],
            free_count: vec![0; nc],
            rc: vec![0.0; 3 * nc],
        }
    }

    /// Fine nodes.
    pub fn fine_nodes(&self) -> usize {
        self.coarse_of.len()
    }

    /// Coarse nodes.
    pub fn coarse_nodes(&self) -> usize {
        self.nc
    }

    /// Scalar half-bandwidth of the coarse matrix.
    pub fn bandwidth(&self) -> usize {
        self.bw
    }

    /// Coarse node of fine node `k` (in the band's order).
    pub fn coarse_of(&self, k: usize) -> usize {
        self.coarse_of[k] as usize
    }

    #[inline(always)]
    fn at(&mut self, i: usize, j: usize) -> &mut f64 {
        debug_assert!(j <= i && i - j <= self.bw);
        &mut self.band[i * (self.bw + 1) + j + self.bw - i]
    }

    /// Adds the 3×3 block `m` at coarse block `(ci, cj)` (and, implicitly,
    /// its transpose at `(cj, ci)`): only the lower band is stored.
    #[inline(always)]
    fn add_block(&mut self, ci: usize, cj: usize, m: &Matrix3<f64>) {
        let (ci, cj, m) = if ci >= cj {
            (ci, cj, *m)
        } else {
            (cj, ci, m.transpose())
        };
        assert!(ci - cj <= self.bw / 3, "a coupling outside the pattern");
        for r in 0..3 {
            for c in 0..3 {
                let (i, j) = (3 * ci + r, 3 * cj + c);
                if j <= i {
                    *self.at(i, j) += m[(r, c)];
                }
            }
        }
    }

    /// Assembles `A_c = Pᵀ S A S P` of `a` (the free nodes' rows and
    /// columns only) and factors it. Allocates nothing.
    ///
    /// # Errors
    /// If `A_c` is not positive definite (then `a` is not SPD on the free
    /// nodes, or an aggregate's nodes are all fixed but coupled: not met).
    pub fn factor(&mut self, a: &EdgeMatrix, fixed: &[bool]) -> Result<(), NotPositiveDefinite> {
        self.band.fill(0.0);
        self.free_count.fill(0);
        for (k, d) in a.diagonal().iter().enumerate() {
            if !fixed[k] {
                let c = self.coarse_of(k);
                self.free_count[c] += 1;
                self.add_block(c, c, d);
            }
        }
        let free = |k: u32| !fixed[k as usize];
        for e in a.edges() {
            if free(e.i) && free(e.j) {
                self.add_edge(e.i as usize, e.j as usize, &e.block());
            }
        }
        if let Some(classes) = a.stencil() {
            let layout = a.stencil_layout();
            for class in classes {
                for e in class.terms(layout) {
                    if free(e.i) && free(e.j) {
                        self.add_edge(e.i as usize, e.j as usize, &e.block());
                    }
                }
            }
        }
        for t in a.rank_one_terms() {
            let k = Vec3::from(t.k);
            let kkt = k * k.transpose() * t.c;
            for (m, &i) in t.nodes.iter().enumerate() {
                for (n, &j) in t.nodes.iter().enumerate().skip(m + 1) {
                    if free(i) && free(j) {
                        self.add_edge(i as usize, j as usize, &(kkt * (t.w[m] * t.w[n])));
                    }
                }
            }
        }
        if let Some(side) = a.side() {
            for i in (0..a.n()).filter(|&i| !fixed[i]) {
                let (cols, blocks) = side.row(i);
                for (&j, m) in cols.iter().zip(blocks) {
                    // Each off-diagonal block once per row: (i, j) here,
                    // (j, i) from row j; keep the lower coarse triangle.
                    let (ci, cj) = (self.coarse_of(i), self.coarse_of(j));
                    if j != i && !fixed[j] && ci >= cj {
                        self.add_block_one_sided(ci, cj, m);
                    }
                }
            }
        }
        for c in 0..self.nc {
            if self.free_count[c] == 0 {
                for r in 0..3 {
                    *self.at(3 * c + r, 3 * c + r) = 1.0;
                }
            }
        }
        self.cholesky()
    }

    /// A block `m` at `(ci, cj)`, `ci ≥ cj`, its transpose not implied
    /// (the side matrix lists both off-diagonal blocks of a pair).
    fn add_block_one_sided(&mut self, ci: usize, cj: usize, m: &Matrix3<f64>) {
        assert!(ci - cj <= self.bw / 3, "a coupling outside the pattern");
        for r in 0..3 {
            for c in 0..3 {
                let (i, j) = (3 * ci + r, 3 * cj + c);
                if j <= i {
                    *self.at(i, j) += m[(r, c)];
                }
            }
        }
    }

    /// A symmetric off-diagonal pair `E` at fine `(i, j)` and `(j, i)`.
    #[inline(always)]
    fn add_edge(&mut self, i: usize, j: usize, e: &Matrix3<f64>) {
        let (ci, cj) = (self.coarse_of(i), self.coarse_of(j));
        if ci == cj {
            self.add_block(ci, ci, &(e * 2.0));
        } else {
            self.add_block(ci, cj, e);
        }
    }

    /// In-place banded Cholesky `A_c = L Lᵀ` (row-oriented: each entry is
    /// a contiguous dot product of two band rows).
    fn cholesky(&mut self) -> Result<(), NotPositiveDefinite> {
        let (n, bw, w) = (3 * self.nc, self.bw, self.bw + 1);
        for i in 0..n {
            let lo = i.saturating_sub(bw);
            for j in lo..=i {
                let k0 = lo.max(j.saturating_sub(bw));
                let ri = &self.band[i * w + k0 + bw - i..i * w + j + bw - i];
                let rj = &self.band[j * w + k0 + bw - j..j * w + j + bw - j];
                let dot: f64 = ri.iter().zip(rj).map(|(a, b)| a * b).sum();
                let s = self.band[i * w + j + bw - i] - dot;
                self.band[i * w + j + bw - i] = if i == j {
                    // Not `s <= 0.0`: a NaN pivot fails too.
                    if s.is_nan() || s <= 0.0 {
                        return Err(NotPositiveDefinite { index: i, pivot: s });
                    }
                    s.sqrt()
                } else {
                    s / self.band[j * w + bw]
                };
            }
        }
        Ok(())
    }

    /// `z += P A_c⁻¹ Pᵀ r` on the free nodes (`free` 1 or 0 per node, at
    /// the vectors' padded positions; `r` is zero on fixed nodes), and
    /// returns `rᵀ P A_c⁻¹ Pᵀ r`, the correction's share of `rᵀ z`.
    /// Allocates nothing.
    pub fn apply(&mut self, r: &Soa3, z: &mut Soa3, free: &[f64], pad: usize) -> f64 {
        self.rc.fill(0.0);
        let n = self.coarse_of.len();
        for c in 0..3 {
            let rc = &r.c[c][pad..pad + n];
            for (&k, &v) in self.coarse_of.iter().zip(rc) {
                self.rc[3 * k as usize + c] += v;
            }
        }
        let rtr = self.solve_in_place();
        for c in 0..3 {
            let zc = &mut z.c[c][pad..pad + n];
            for ((zk, &k), &f) in zc.iter_mut().zip(&self.coarse_of).zip(&free[pad..pad + n]) {
                *zk += f * self.rc[3 * k as usize + c];
            }
        }
        rtr
    }

    /// `rc ← A_c⁻¹ rc` by the factor, returning `rcᵀ A_c⁻¹ rc = |L⁻¹ rc|²`.
    fn solve_in_place(&mut self) -> f64 {
        let (n, bw, w) = (3 * self.nc, self.bw, self.bw + 1);
        let mut yy = 0.0;
        for i in 0..n {
            let lo = i.saturating_sub(bw);
            let row = &self.band[i * w + lo + bw - i..i * w + bw];
            let dot: f64 = row.iter().zip(&self.rc[lo..i]).map(|(a, b)| a * b).sum();
            self.rc[i] = (self.rc[i] - dot) / self.band[i * w + bw];
            yy += self.rc[i] * self.rc[i];
        }
        for i in (0..n).rev() {
            let xi = self.rc[i] / self.band[i * w + bw];
            self.rc[i] = xi;
            let lo = i.saturating_sub(bw);
            let row = &self.band[i * w + lo + bw - i..i * w + bw];
            for (y, l) in self.rc[lo..i].iter_mut().zip(row) {
                *y -= l * xi;
            }
        }
        yy
    }
}
