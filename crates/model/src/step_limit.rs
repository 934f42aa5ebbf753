//! The asymptote limiter's step fraction (issue 18): the largest
//! `α ∈ [0, 1]` such that every normal column stays longer than its limit,
//! `n₀·(x + s Δx) ≥ h_min` for all `s ∈ [0, α]`, over the straight path
//! from the Newton iterate `x` to `x + Δx` (m). The column's height is
//! linear in `s`, so per node (with the rate `r = n₀·Δx` and the room
//! `ρ = n₀·x − h_min`, both m):
//!
//! ```text
//! α_k = 1                 if r ≥ 0   (the column lengthens)
//!     = 0                 if ρ ≤ 0   (at the limit and moving in)
//!     = min(ρ / −r, 1)    otherwise
//! ```
//!
//! and the step's fraction is `min(1, min_k α_k)`.
//!
//! The limits are stored as structure of arrays (`n₀` by component, then
//! `h_min`: the 32 bytes a node needs, read in streams). The SIMD kernel
//! reads four nodes' `x` and `Δx` at a time ([`SimdSqrt::load_xyz`]),
//! computes `r` and `ρ` with the scalar code's operations in its order
//! (`(n_x a_x + n_y a_y) + n_z a_z`, unfused, as nalgebra's 3-vector dot)
//! and chooses between the three cases with lane selects, not branches:
//! the rate's sign is data-dependent and mispredicted half the time in the
//! scalar code. Every case is a value of `{0, 1, ρ/−r}` computed with the
//! same IEEE operations, and the minimum of values without NaN does not
//! depend on the order, so the two paths return the same bits.

use crate::integrator::Kernels;
use crate::simd::{dispatch, SimdSqrt, SqrtKernel};
use crate::Vec3;

/// Largest `α ∈ [0, 1]` with `n·(x + s dx) ≥ h_min` for all `s ∈ [0, α]`
/// for one column of axis `n` (unit) and limit `h_min` (m): the scalar
/// reference, with branches.
#[inline]
pub fn path_fraction(n: &Vec3, h_min: f64, x: &Vec3, dx: &Vec3) -> f64 {
    let rate = n.dot(dx);
    if rate >= 0.0 {
        return 1.0; // moving away from the anchor: the column lengthens
    }
    let room = n.dot(x) - h_min;
    if room <= 0.0 {
        return 0.0; // at the limit and moving inward
    }
    (room / -rate).min(1.0)
}

/// Every node's column limit `(n₀, h_min)` as structure of arrays.
#[derive(Debug, Clone, Default)]
pub struct ColumnLimits {
    /// Components of the unit axis `n₀`, one array per component.
    n: [Vec<f64>; 3],
    /// The lowest allowed height `h_min = n₀·x` (m).
    h_min: Vec<f64>,
}

impl ColumnLimits {
    /// The limits `(n₀, h_min)` of nodes `0, 1, …` (allocates once).
    pub fn new(limits: impl IntoIterator<Item = (Vec3, f64)>) -> Self {
        let mut out = ColumnLimits::default();
        for (n, h) in limits {
            for (c, v) in out.n.iter_mut().zip([n.x, n.y, n.z]) {
                c.push(v);
            }
            out.h_min.push(h);
        }
        out
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.h_min.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.h_min.is_empty()
    }

    /// Node `k`'s limit `(n₀, h_min)`.
    #[inline]
    pub fn get(&self, k: usize) -> (Vec3, f64) {
        let [x, y, z] = &self.n;
        (Vec3::new(x[k], y[k], z[k]), self.h_min[k])
    }

    /// Replaces node `k`'s limit (no allocation).
    pub fn set(&mut self, k: usize, (n, h_min): (Vec3, f64)) {
        for (c, v) in self.n.iter_mut().zip([n.x, n.y, n.z]) {
            c[k] = v;
        }
        self.h_min[k] = h_min;
    }

    /// `min(1, min_k α_k)` over the path from `x` to `x + dx` (both one
    /// entry per node, m): with [`Kernels::Simd`] the branchless lane
    /// kernel, with [`Kernels::Scalar`] the fold of [`path_fraction`]; the
    /// same value to the bit. Allocates nothing.
    ///
    /// # Panics
    /// If `x` or `dx` has fewer entries than there are nodes.
    pub fn max_step_fraction(&self, x: &[Vec3], dx: &[Vec3], kernels: Kernels) -> f64 {
        let (x, dx) = (&x[..self.len()], &dx[..self.len()]);
        match kernels {
            Kernels::Simd => dispatch(StepFraction { l: self, x, dx }),
            Kernels::Scalar => (0..self.len())
                .map(|k| {
                    let (n, h) = self.get(k);
                    path_fraction(&n, h, &x[k], &dx[k])
                })
                .fold(1.0, f64::min),
        }
    }
}

/// `(n_x a_x + n_y a_y) + n_z a_z` per lane, unfused (nalgebra's order).
/// A function, not a closure, so that it inlines into the kernel's
/// AVX2 context (a closure is compiled without the target features).
#[inline(always)]
fn dot<S: SimdSqrt>(
    s: S,
    n: (S::f64s, S::f64s, S::f64s),
    a: (S::f64s, S::f64s, S::f64s),
) -> S::f64s {
    let xy = s.add_f64s(s.mul_f64s(n.0, a.0), s.mul_f64s(n.1, a.1));
    s.add_f64s(xy, s.mul_f64s(n.2, a.2))
}

/// The lane kernel of [`ColumnLimits::max_step_fraction`].
struct StepFraction<'a> {
    l: &'a ColumnLimits,
    x: &'a [Vec3],
    dx: &'a [Vec3],
}

impl SqrtKernel for StepFraction<'_> {
    type Output = f64;

    #[inline(always)]
    fn run<S: SimdSqrt>(self, s: S) -> f64 {
        let lanes = S::F64_LANES;
        let full = self.x.len() / lanes * lanes;
        let [nx, ny, nz] = &self.l.n;
        let (nx, _) = S::as_simd_f64s(&nx[..full]);
        let (ny, _) = S::as_simd_f64s(&ny[..full]);
        let (nz, _) = S::as_simd_f64s(&nz[..full]);
        let (hm, _) = S::as_simd_f64s(&self.l.h_min[..full]);
        let (zero, one) = (s.splat_f64s(0.0), s.splat_f64s(1.0));
        let mut acc = one;
        let nodes = self.x.chunks_exact(lanes).zip(self.dx.chunks_exact(lanes));
        for (k, (x, dx)) in nodes.enumerate() {
            let (x0, x1, x2) = s.load_xyz(x);
            let (d0, d1, d2) = s.load_xyz(dx);
            let n = (nx[k], ny[k], nz[k]);
            let rate = dot(s, n, (d0, d1, d2));
            let room = s.sub_f64s(dot(s, n, (x0, x1, x2)), hm[k]);
            // min(ρ/−r, 1): `minpd` returns its second operand if the first
            // is NaN, as f64::min does.
            let ratio = s.min_f64s(s.div_f64s(room, s.neg_f64s(rate)), one);
            let inward = s.select_f64s_m64s(s.less_than_or_equal_f64s(room, zero), zero, ratio);
            let alpha = s.select_f64s_m64s(s.greater_than_or_equal_f64s(rate, zero), one, inward);
            acc = s.min_f64s(acc, alpha);
        }
        let mut out = s.reduce_min_f64s(acc);
        for k in full..self.x.len() {
            let (n, h) = self.l.get(k);
            out = out.min(path_fraction(&n, h, &self.x[k], &self.dx[k]));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::{path_fraction, ColumnLimits, StepFraction};
    use crate::integrator::Kernels;
    use crate::simd::SqrtKernel;
    use crate::Vec3;
    use proptest::prelude::*;

    /// A component: exactly 0 one time in four (so that `r = 0` and
    /// `Δx = 0` occur), else uniform in ±1 m.
    fn component() -> impl Strategy<Value = f64> {
        prop_oneof![1 => Just(0.0), 3 => -1.0..1.0f64]
    }

    fn vector() -> impl Strategy<Value = Vec3> {
        (component(), component(), component()).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// A node: `(n₀, h_min, x, Δx)` with `h_min = n₀·x − ρ`, the room `ρ`
    /// exactly 0 one time in five, negative (past the limit) or positive,
    /// and up to 2 m: with `|Δx| ≤ √3 m` both sides of the 1.0 cap occur.
    fn node() -> impl Strategy<Value = (Vec3, f64, Vec3, Vec3)> {
        let room = prop_oneof![1 => Just(0.0), 4 => -0.5..2.0f64];
        (vector(), vector(), vector(), room).prop_map(|(n, x, dx, room)| {
            let n = n.try_normalize(0.0).unwrap_or(Vec3::new(0.0, 1.0, 0.0));
            (n, n.dot(&x) - room, x, dx)
        })
    }

    proptest! {
        /// The lane kernel, on AVX2 lanes and on pulp's one-lane scalar
        /// type, returns the scalar fold's bits: every lane computes the
        /// scalar code's IEEE operations in its order (see the module
        /// docs), so no tolerance. 0–41 nodes: empty, tails of 1–3 nodes
        /// after the four-lane chunks, several chunks.
        #[test]
        fn lane_kernel_is_bit_equal_to_the_scalar_fold(
            nodes in proptest::collection::vec(node(), 0..42),
        ) {
            let limits = ColumnLimits::new(nodes.iter().map(|&(n, h, _, _)| (n, h)));
            let x: Vec<Vec3> = nodes.iter().map(|t| t.2).collect();
            let dx: Vec<Vec3> = nodes.iter().map(|t| t.3).collect();
            let scalar = limits.max_step_fraction(&x, &dx, Kernels::Scalar);
            let simd = limits.max_step_fraction(&x, &dx, Kernels::Simd);
            prop_assert_eq!(scalar.to_bits(), simd.to_bits());
            let one_lane = StepFraction { l: &limits, x: &x, dx: &dx }.run(pulp::Scalar::new());
            prop_assert_eq!(scalar.to_bits(), one_lane.to_bits());
            #[cfg(target_arch = "x86_64")]
            if let Some(v3) = pulp::x86::V3::try_new() {
                let four = v3.vectorize(|| StepFraction { l: &limits, x: &x, dx: &dx }.run(v3));
                prop_assert_eq!(scalar.to_bits(), four.to_bits());
            }
        }
    }

    /// Each case of the law in one four-node chunk, against hand values:
    /// the node that binds decides, and the lanes do not mix up nodes
    /// (the AoS → SoA load).
    #[test]
    fn lane_kernel_takes_each_nodes_own_case() {
        let up = Vec3::new(0.0, 1.0, 0.0);
        // Heights 0.04 m, limits 0.01 m (room 0.03 m) except where noted.
        let x = vec![Vec3::new(0.1, 0.04, 0.2); 5];
        let mut dx = vec![Vec3::new(0.0, 0.01, 0.0); 5]; // all lengthen: α = 1
        let limits = ColumnLimits::new([(up, 0.01); 5]);
        assert_eq!(limits.max_step_fraction(&x, &dx, Kernels::Simd), 1.0);
        // Node 2 moves down 0.12 m: room 0.03 m, α = 0.25.
        dx[2] = Vec3::new(0.3, -0.12, -0.3);
        assert_eq!(limits.max_step_fraction(&x, &dx, Kernels::Simd), 0.25);
        // Node 3 moves down 0.01 m only: capped at 1, node 2 still binds.
        dx[3] = Vec3::new(0.0, -0.01, 0.0);
        assert_eq!(limits.max_step_fraction(&x, &dx, Kernels::Simd), 0.25);
        // Node 4 (the tail) is at its limit and moves in: α = 0.
        let mut limits = limits;
        limits.set(4, (up, 0.04));
        dx[4] = Vec3::new(0.0, -1e-9, 0.0);
        assert_eq!(limits.max_step_fraction(&x, &dx, Kernels::Simd), 0.0);
        // Node 1 at its limit but not moving (r = 0): α = 1, node 2 binds.
        limits.set(4, (up, 0.01));
        limits.set(1, (up, 0.04));
        dx[1] = Vec3::zeros();
        assert_eq!(limits.max_step_fraction(&x, &dx, Kernels::Simd), 0.25);
    }

    #[test]
    fn path_fraction_stops_on_the_limit_plane() {
        // Column axis +y, limit at height 0.01 m, from 0.04 m straight down
        // by 0.04 m: the limit is reached at s = 0.75.
        let n = Vec3::new(0.0, 1.0, 0.0);
        let x = Vec3::new(0.3, 0.04, 0.0);
        let d = Vec3::new(0.0, -0.04, 0.0);
        assert!((path_fraction(&n, 0.01, &x, &d) - 0.75).abs() < 1e-12);
        assert_eq!(path_fraction(&n, 0.01, &x, &(d * 0.5)), 1.0);
        assert_eq!(path_fraction(&n, 0.01, &x, &(-d)), 1.0);
        // A sideways move does not shorten the column, however long.
        let side = Vec3::new(1.0, 0.0, 0.0);
        assert_eq!(path_fraction(&n, 0.01, &x, &side), 1.0);
        // Oblique: only the axial part counts (0.03 m of room, 0.06 m down).
        let oblique = Vec3::new(5.0, -0.06, 0.0);
        assert!((path_fraction(&n, 0.01, &x, &oblique) - 0.5).abs() < 1e-12);
        // At the limit, moving in: no step at all.
        assert_eq!(path_fraction(&n, 0.04, &x, &d), 0.0);
    }
}
