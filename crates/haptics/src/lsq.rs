//! Small fixed-size least squares for the model manager: an incremental QR
//! (Givens rotations) that reduces any number of weighted rows to a 4×4
//! triangle without allocating, and an SVD pseudo-inverse (minimum-norm,
//! truncated) solve. Never forms or inverts `JᵀJ`.

use nalgebra::{Matrix4, Vector4};

/// A 4×4 SVD `M = U diag(σ) Vᵀ` with its numerical rank.
#[derive(Debug, Clone, Copy)]
pub struct Svd4 {
    /// Left singular vectors (columns).
    pub u: Matrix4<f64>,
    /// Singular values (unordered).
    pub sigma: Vector4<f64>,
    /// Right singular vectors, transposed (rows).
    pub v_t: Matrix4<f64>,
    /// Threshold below which a singular value counts as zero.
    pub cutoff: f64,
}

impl Svd4 {
    /// Decomposes `m`, singular values below `rcond · σ_max` counting as
    /// zero; `None` if `m` is not finite or the SVD did not converge.
    pub fn new(m: &Matrix4<f64>, rcond: f64) -> Option<Svd4> {
        Self::with_floor(m, rcond, 0.0)
    }

    /// As `new`, with singular values below `floor` also counting as zero
    /// (a scale taken from a larger problem this one was reduced from).
    pub fn with_floor(m: &Matrix4<f64>, rcond: f64, floor: f64) -> Option<Svd4> {
        if !m.iter().all(|v| v.is_finite()) {
            return None;
        }
        let svd = m.try_svd(true, true, f64::EPSILON * 5.0, 500)?;
        let (u, v_t) = (svd.u?, svd.v_t?);
        let smax = svd.singular_values.max();
        Some(Svd4 {
            u,
            sigma: svd.singular_values,
            v_t,
            cutoff: (rcond * smax).max(floor).max(f64::MIN_POSITIVE),
        })
    }

    /// True when singular value `i` is above the cutoff.
    pub fn in_range(&self, i: usize) -> bool {
        self.sigma[i] > self.cutoff
    }

    /// Numerical rank.
    pub fn rank(&self) -> usize {
        (0..4).filter(|&i| self.in_range(i)).count()
    }

    /// Coordinates `y = Σ⁺ Uᵀ b` in the basis of the right singular vectors;
    /// `x = V y` is the minimum-norm least-squares solution of `M x = b`.
    pub fn solve_coords(&self, b: &Vector4<f64>) -> Vector4<f64> {
        let ub = self.u.tr_mul(b);
        Vector4::from_fn(|i, _| {
            if self.in_range(i) {
                ub[i] / self.sigma[i]
            } else {
                0.0
            }
        })
    }
}

/// Incremental QR: accumulates rows `a·x ≈ b` into `R x ≈ q` (R upper
/// triangular 4×4) plus the residual sum of squares that no `x` can remove.
#[derive(Debug, Clone, Copy, Default)]
pub struct QrAccumulator {
    r: Matrix4<f64>,
    q: Vector4<f64>,
    rss: f64,
}

impl QrAccumulator {
    /// Empties the accumulator.
    pub fn clear(&mut self) {
        *self = QrAccumulator::default();
    }

    /// Adds the row `a·x ≈ b` (Givens rotations into R).
    pub fn add_row(&mut self, a: &Vector4<f64>, b: f64) {
        let (mut a, mut b) = (*a, b);
        for k in 0..4 {
            if a[k] == 0.0 {
                continue;
            }
            let rkk = self.r[(k, k)];
            let h = rkk.hypot(a[k]);
            let (c, s) = (rkk / h, a[k] / h);
            for j in k..4 {
                let (rkj, aj) = (self.r[(k, j)], a[j]);
                self.r[(k, j)] = c * rkj + s * aj;
                a[j] = -s * rkj + c * aj;
            }
            let qk = self.q[k];
            self.q[k] = c * qk + s * b;
            b = -s * qk + c * b;
        }
        self.rss += b * b;
    }

    /// Minimum-norm least-squares solution and its rank, singular values of
    /// R below `rcond · σ_max` or below `floor` counting as zero; `None` if
    /// not finite.
    pub fn solve(&self, rcond: f64, floor: f64) -> Option<(Vector4<f64>, usize)> {
        let svd = Svd4::with_floor(&self.r, rcond, floor)?;
        let y = svd.solve_coords(&self.q);
        Some((svd.v_t.tr_mul(&y), svd.rank()))
    }

    /// Residual sum of squares left after the best fit of the rows added.
    pub fn residual_sum_of_squares(&self) -> f64 {
        self.rss
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn qr_matches_overdetermined_least_squares() {
        // Fit y = x0 + x1 t + x2 t² + x3 t³ to exact data: recovers x.
        let truth = Vector4::new(0.5, -1.0, 2.0, 0.25);
        let mut acc = QrAccumulator::default();
        for i in 0..12 {
            let t = i as f64 * 0.3 - 1.0;
            let a = Vector4::new(1.0, t, t * t, t * t * t);
            acc.add_row(&a, a.dot(&truth));
        }
        let (x, rank) = acc.solve(1e-12, 0.0).unwrap();
        assert_eq!(rank, 4);
        assert!((x - truth).norm() < 1e-12);
        assert!(acc.residual_sum_of_squares() < 1e-24);
    }

    #[test]
    fn rank_deficient_gives_minimum_norm() {
        // Only x0 + x1 is observed: the minimum-norm solution splits it.
        let mut acc = QrAccumulator::default();
        acc.add_row(&Vector4::new(1.0, 1.0, 0.0, 0.0), 2.0);
        acc.add_row(&Vector4::new(2.0, 2.0, 0.0, 0.0), 4.0);
        let (x, rank) = acc.solve(1e-9, 0.0).unwrap();
        assert_eq!(rank, 1);
        assert!((x - Vector4::new(1.0, 1.0, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn non_finite_is_rejected() {
        let mut acc = QrAccumulator::default();
        acc.add_row(&Vector4::new(f64::NAN, 1.0, 0.0, 0.0), 1.0);
        assert!(acc.solve(1e-9, 0.0).is_none());
    }
}
