//! A 3×3 block-sparse matrix in compressed sparse row form (BSR), with a
//! pattern fixed at construction (the mesh topology never changes): the
//! values are refilled every step without allocating.

use crate::Vec3;
use nalgebra::Matrix3;

/// Returned when a block outside the fixed pattern is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("block ({row}, {col}) is not in the fixed sparsity pattern")]
pub struct PatternError {
    /// Block row (node index).
    pub row: usize,
    /// Block column (node index).
    pub col: usize,
}

/// Square matrix of `n × n` blocks of 3×3 (`3n × 3n` scalars), block CSR.
///
/// Row `i` holds blocks `(i, cols[k])` for `k in row_ptr[i]..row_ptr[i+1]`,
/// columns sorted, the diagonal always present. Units are those of whatever
/// is stored (N/m for a stiffness, N·s/m for a damping, kg for a mass matrix).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockSparse {
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    diag: Vec<usize>,
    values: Vec<Matrix3<f64>>,
}

impl BlockSparse {
    /// Builds the pattern of an `n × n` block matrix holding the diagonal and
    /// the blocks `(i, j)` and `(j, i)` for every pair given (duplicates and
    /// pairs `(i, i)` are fine). Values start at zero.
    ///
    /// # Panics
    /// If a pair has an index `>= n` (a programming error, not user input).
    pub fn from_pairs(n: usize, pairs: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut adjacency: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
        for (i, j) in pairs {
            assert!(i < n && j < n, "pair ({i}, {j}) out of range for n = {n}");
            if i != j {
                adjacency[i].push(j);
                adjacency[j].push(i);
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut diag = Vec::with_capacity(n);
        row_ptr.push(0);
        for (i, row) in adjacency.iter_mut().enumerate() {
            row.sort_unstable();
            row.dedup();
            let start = cols.len();
            let d = row.binary_search(&i).expect("diagonal inserted above");
            diag.push(start + d);
            cols.extend_from_slice(row);
            row_ptr.push(cols.len());
        }
        let values = vec![Matrix3::zeros(); cols.len()];
        BlockSparse {
            row_ptr,
            cols,
            diag,
            values,
        }
    }

    /// Number of block rows (nodes).
    pub fn n(&self) -> usize {
        self.diag.len()
    }

    /// Number of stored blocks.
    pub fn nnz_blocks(&self) -> usize {
        self.values.len()
    }

    /// Sets every stored value to zero (pattern unchanged).
    pub fn clear(&mut self) {
        self.values.fill(Matrix3::zeros());
    }

    /// Storage index of block `(row, col)`, if it is in the pattern
    /// (binary search in the row, no allocation).
    pub fn block_index(&self, row: usize, col: usize) -> Option<usize> {
        if row >= self.n() {
            return None;
        }
        let (start, end) = (self.row_ptr[row], self.row_ptr[row + 1]);
        self.cols[start..end]
            .binary_search(&col)
            .ok()
            .map(|k| start + k)
    }

    /// Storage index of the diagonal block `(row, row)`.
    pub fn diagonal_index(&self, row: usize) -> usize {
        self.diag[row]
    }

    /// Adds `block` to block `(row, col)`; fails if it is not in the pattern.
    pub fn add_block(
        &mut self,
        row: usize,
        col: usize,
        block: &Matrix3<f64>,
    ) -> Result<(), PatternError> {
        let k = self
            .block_index(row, col)
            .ok_or(PatternError { row, col })?;
        self.values[k] += block;
        Ok(())
    }

    /// Adds `block` to the diagonal block of `row`.
    pub fn add_diagonal(&mut self, row: usize, block: &Matrix3<f64>) {
        let k = self.diag[row];
        self.values[k] += block;
    }

    /// Adds `block` at storage index `index` (from [`Self::block_index`]).
    #[inline]
    pub fn add_at(&mut self, index: usize, block: &Matrix3<f64>) {
        self.values[index] += block;
    }

    /// Block `(row, col)`, if in the pattern.
    pub fn block(&self, row: usize, col: usize) -> Option<&Matrix3<f64>> {
        self.block_index(row, col).map(|k| &self.values[k])
    }

    /// Column indices and blocks of row `row`.
    pub fn row(&self, row: usize) -> (&[usize], &[Matrix3<f64>]) {
        let (s, e) = (self.row_ptr[row], self.row_ptr[row + 1]);
        (&self.cols[s..e], &self.values[s..e])
    }

    /// All stored blocks, in storage order.
    pub fn values(&self) -> &[Matrix3<f64>] {
        &self.values
    }

    /// All stored blocks, mutable (pattern fixed).
    pub fn values_mut(&mut self) -> &mut [Matrix3<f64>] {
        &mut self.values
    }

    /// True if `other` has exactly the same pattern.
    pub fn same_pattern(&self, other: &BlockSparse) -> bool {
        self.row_ptr == other.row_ptr && self.cols == other.cols
    }

    /// `y = A x`.
    ///
    /// # Panics
    /// If `x` or `y` is not of length [`Self::n`].
    pub fn mul_vec(&self, x: &[Vec3], y: &mut [Vec3]) {
        assert_eq!(x.len(), self.n());
        assert_eq!(y.len(), self.n());
        for (i, yi) in y.iter_mut().enumerate() {
            let (s, e) = (self.row_ptr[i], self.row_ptr[i + 1]);
            let mut acc = Vec3::zeros();
            for (m, &j) in self.values[s..e].iter().zip(&self.cols[s..e]) {
                acc += m * x[j];
            }
            *yi = acc;
        }
    }

    /// Sets `self = α·a + β·b + diag(d_i I)`, all three of the same pattern
    /// as `self` (used to form `M − λ h B − λ² h² K`).
    ///
    /// # Panics
    /// If a pattern or `diag`'s length differs.
    pub fn set_combination(
        &mut self,
        alpha: f64,
        a: &BlockSparse,
        beta: f64,
        b: &BlockSparse,
        diag: &[f64],
    ) {
        assert!(self.values.len() == a.values.len() && self.values.len() == b.values.len());
        debug_assert!(self.same_pattern(a) && self.same_pattern(b));
        assert_eq!(diag.len(), self.n());
        for ((out, ka), kb) in self.values.iter_mut().zip(&a.values).zip(&b.values) {
            *out = ka * alpha + kb * beta;
        }
        for (i, &d) in diag.iter().enumerate() {
            let k = self.diag[i];
            self.values[k][(0, 0)] += d;
            self.values[k][(1, 1)] += d;
            self.values[k][(2, 2)] += d;
        }
    }

    /// `self += α·a + β·b` (same pattern).
    ///
    /// # Panics
    /// If a pattern differs.
    pub fn add_scaled(&mut self, alpha: f64, a: &BlockSparse, beta: f64, b: &BlockSparse) {
        assert!(self.values.len() == a.values.len() && self.values.len() == b.values.len());
        debug_assert!(self.same_pattern(a) && self.same_pattern(b));
        for ((out, ka), kb) in self.values.iter_mut().zip(&a.values).zip(&b.values) {
            *out += ka * alpha + kb * beta;
        }
    }

    /// Adds `d_i · I` to each diagonal block (e.g. the lumped masses, kg).
    ///
    /// # Panics
    /// If `d.len() != self.n()`.
    pub fn add_to_diagonal(&mut self, d: &[f64]) {
        assert_eq!(d.len(), self.n());
        for (&k, &di) in self.diag.iter().zip(d) {
            let m = &mut self.values[k];
            m[(0, 0)] += di;
            m[(1, 1)] += di;
            m[(2, 2)] += di;
        }
    }

    /// The dense `3n × 3n` matrix (tests and small problems only; allocates).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let n = self.n();
        let mut d = nalgebra::DMatrix::zeros(3 * n, 3 * n);
        for i in 0..n {
            let (cols, vals) = self.row(i);
            for (&j, m) in cols.iter().zip(vals) {
                d.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(m);
            }
        }
        d
    }
}
