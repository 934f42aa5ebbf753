//! Broad phase: a uniform grid over the surface nodes (paper §3, "Collision
//! Detection": find the surface elements inside the probe's bounding box
//! without scanning every node).
//!
//! Why a hand-written grid and not parry3d: parry's BVH would do, but it is
//! heavy to compile on the project's 2-core machines, and the problem here is
//! simple: a few thousand points, one box query per step, points that move a
//! little every step. A grid rebuilt by counting sort costs `O(n)` per step,
//! needs no refit heuristics, and its memory is sized once at construction so
//! the rebuild allocates nothing.
//!
//! The rebuild takes the points' bounding box and a target cell size; if the
//! box would need more cells than the preallocated capacity (the surface
//! swelled, or a node flew away), the cell size grows until it fits. Queries
//! are exact: candidates from the overlapped cells are tested against the
//! query shape, so the result is exactly what a brute-force scan returns.

use crate::probe::OrientedBox;
use nalgebra::Vector3;

/// Uniform grid over a point set, rebuilt each step without allocation.
#[derive(Debug, Clone)]
pub struct SurfaceGrid {
    target_cell: f64,
    cell: f64,
    origin: Vector3<f64>,
    dims: [usize; 3],
    max_cells: usize,
    /// `cell_start[c]..cell_start[c+1]` indexes `entries` for cell `c`.
    cell_start: Vec<u32>,
    /// Point indices sorted by cell.
    entries: Vec<u32>,
    /// Cell of each point (scratch of the counting sort).
    point_cell: Vec<u32>,
    n_points: usize,
}

impl SurfaceGrid {
    /// A grid for `n_points` points with cells of edge `cell_size` (m) when
    /// they fit in the capacity (`8 n_points` cells, at least 4096).
    pub fn new(n_points: usize, cell_size: f64) -> Self {
        let max_cells = (8 * n_points).max(4096);
        Self {
            target_cell: cell_size.max(f64::MIN_POSITIVE),
            cell: cell_size.max(f64::MIN_POSITIVE),
            origin: Vector3::zeros(),
            dims: [1, 1, 1],
            max_cells,
            cell_start: vec![0; max_cells + 1],
            entries: vec![0; n_points],
            point_cell: vec![0; n_points],
            n_points: 0,
        }
    }

    /// Current cell edge, m (the target size, or larger if the points'
    /// bounding box needed it).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Largest coordinate magnitude (m) of a point the grid bins: 1 km. The
    /// thigh frame spans less than a metre, so a point beyond this (or with
    /// a non-finite coordinate) belongs to a diverged model, which its owner
    /// detects at its own checkpoint (`ThighModel::check_state`) and reports.
    pub const MAX_COORDINATE: f64 = 1.0e3;

    /// Re-bins the points `x` (positions in m). `x.len()` must not exceed the
    /// size given to [`SurfaceGrid::new`]; extra points are ignored.
    ///
    /// Points with a non-finite coordinate, or one beyond
    /// ±[`SurfaceGrid::MAX_COORDINATE`], are skipped: they are in no cell,
    /// so no query returns them. Returns how many were skipped (0 for a
    /// healthy model). Skipping keeps the cell count bounded: a point at
    /// 1e308 m made the bounding box's span overflow to infinity and the
    /// cell counts to wrap (an index out of bounds, issue 20).
    pub fn rebuild(&mut self, x: &[Vector3<f64>]) -> usize {
        let n = x.len().min(self.entries.len());
        let usable = |p: &Vector3<f64>| p.iter().all(|c| c.abs() <= Self::MAX_COORDINATE);
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in x[..n].iter().filter(|p| usable(p)) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo.x > hi.x {
            lo = Vector3::zeros();
            hi = Vector3::zeros();
        }
        // span ≤ 2 km and cell ≥ target > 0: the counts below are finite
        // and computed in f64, so they cannot wrap.
        let span = hi - lo;
        let mut cell = self.target_cell;
        loop {
            let d = span.map(|s| (s / cell).floor() + 1.0);
            if d.x * d.y * d.z <= self.max_cells as f64 {
                self.dims = [d.x as usize, d.y as usize, d.z as usize];
                break;
            }
            cell *= 1.5;
        }
        self.cell = cell;
        self.origin = lo;
        let n_cells = self.dims[0] * self.dims[1] * self.dims[2];
        let counts = &mut self.cell_start[..=n_cells];
        counts.fill(0);
        const SKIPPED: u32 = u32::MAX;
        let mut binned = 0;
        for (i, p) in x[..n].iter().enumerate() {
            if usable(p) {
                let c = self.cell_of(p);
                self.point_cell[i] = c as u32;
                self.cell_start[c + 1] += 1;
                binned += 1;
            } else {
                self.point_cell[i] = SKIPPED;
            }
        }
        self.n_points = binned;
        for c in 0..n_cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        // Place entries; `cell_start[c]` is used as a cursor and restored below.
        for i in 0..n {
            let c = self.point_cell[i];
            if c == SKIPPED {
                continue;
            }
            let slot = self.cell_start[c as usize] as usize;
            self.entries[slot] = i as u32;
            self.cell_start[c as usize] += 1;
        }
        for c in (1..=n_cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
        n - binned
    }

    fn coord(&self, v: f64, axis: usize) -> usize {
        let t = ((v - self.origin[axis]) / self.cell).floor();
        if t.is_nan() || t < 0.0 {
            0
        } else {
            (t as usize).min(self.dims[axis] - 1)
        }
    }

    fn cell_of(&self, p: &Vector3<f64>) -> usize {
        let (i, j, k) = (self.coord(p.x, 0), self.coord(p.y, 1), self.coord(p.z, 2));
        (k * self.dims[1] + j) * self.dims[0] + i
    }

    /// Calls `visit(i)` for every point in the cells overlapping the
    /// axis-aligned box `[lo, hi]` (m): a superset of the points inside it.
    pub fn for_each_candidate(
        &self,
        lo: &Vector3<f64>,
        hi: &Vector3<f64>,
        mut visit: impl FnMut(usize),
    ) {
        if self.n_points == 0 {
            return;
        }
        let end = self.origin + Vector3::from(self.dims.map(|d| d as f64)) * self.cell;
        if (0..3).any(|a| hi[a] < self.origin[a] || lo[a] > end[a] || lo[a] > hi[a]) {
            return;
        }
        let (i0, i1) = (self.coord(lo.x, 0), self.coord(hi.x, 0));
        let (j0, j1) = (self.coord(lo.y, 1), self.coord(hi.y, 1));
        let (k0, k1) = (self.coord(lo.z, 2), self.coord(hi.z, 2));
        for k in k0..=k1 {
            for j in j0..=j1 {
                let row = (k * self.dims[1] + j) * self.dims[0];
                let s = self.cell_start[row + i0] as usize;
                let e = self.cell_start[row + i1 + 1] as usize;
                for &idx in &self.entries[s..e] {
                    visit(idx as usize);
                }
            }
        }
    }

    /// Writes into `out` (cleared first) the indices of the points of `x`
    /// inside the oriented box, in increasing order. `x` must be the slice
    /// given to the last [`SurfaceGrid::rebuild`]. Allocates only if `out`
    /// has less capacity than the number of hits.
    pub fn query_box(&self, x: &[Vector3<f64>], obb: &OrientedBox, out: &mut Vec<usize>) {
        out.clear();
        let (lo, hi) = obb.aabb();
        self.for_each_candidate(&lo, &hi, |i| {
            if obb.contains(&x[i]) {
                out.push(i);
            }
        });
        out.sort_unstable();
    }

    /// Writes into `out` (cleared first) the indices of the points within
    /// distance `r` (m) of `c`, in increasing order.
    pub fn query_sphere(&self, x: &[Vector3<f64>], c: &Vector3<f64>, r: f64, out: &mut Vec<usize>) {
        out.clear();
        let e = Vector3::repeat(r);
        self.for_each_candidate(&(c - e), &(c + e), |i| {
            if (x[i] - c).norm_squared() <= r * r {
                out.push(i);
            }
        });
        out.sort_unstable();
    }

    /// The point of `x` nearest to `c` and its distance (m), found by
    /// searching growing cubes of cells; `None` if the grid is empty.
    pub fn nearest(&self, x: &[Vector3<f64>], c: &Vector3<f64>) -> Option<(usize, f64)> {
        if self.n_points == 0 || !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        // Distance from c to the grid's box: the search starts there.
        let end = self.origin + Vector3::from(self.dims.map(|d| d as f64)) * self.cell;
        let outside = (self.origin - c)
            .sup(&(c - end))
            .sup(&Vector3::zeros())
            .norm();
        let diag = (end - self.origin).norm();
        let mut r = outside + self.cell;
        loop {
            let mut best: Option<(usize, f64)> = None;
            let e = Vector3::repeat(r);
            self.for_each_candidate(&(c - e), &(c + e), |i| {
                let d2 = (x[i] - c).norm_squared();
                if best.map(|(_, b)| d2 < b).unwrap_or(true) {
                    best = Some((i, d2));
                }
            });
            // A hit within r is the nearest: every point within r lies in the
            // searched cube. Past the grid's diagonal, everything was searched.
            if let Some((i, d2)) = best {
                if d2 <= r * r || r > outside + diag {
                    return Some((i, d2.sqrt()));
                }
            }
            r *= 2.0;
            if !r.is_finite() {
                return best.map(|(i, d2)| (i, d2.sqrt()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::Probe;
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use proptest::prelude::*;

    fn cloud(seed: &[(f64, f64, f64)]) -> Vec<Vector3<f64>> {
        seed.iter()
            .map(|&(a, b, c)| Vector3::new(a, b, c))
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn box_query_equals_brute_force(
            pts in prop::collection::vec((-0.1f64..0.1, -0.1f64..0.1, -0.15f64..0.15), 1..400),
            cell in 0.002f64..0.05,
            t in (-0.1f64..0.1, -0.1f64..0.1, -0.1f64..0.1),
            r in (-3.2f64..3.2, -1.6f64..1.6, -3.2f64..3.2),
        ) {
            let x = cloud(&pts);
            let mut grid = SurfaceGrid::new(x.len(), cell);
            grid.rebuild(&x);
            let pose = Isometry3::from_parts(
                Translation3::new(t.0, t.1, t.2),
                UnitQuaternion::from_euler_angles(r.0, r.1, r.2),
            );
            let obb = Probe::default().body_box(&pose, 0.004);
            let mut got = Vec::new();
            grid.query_box(&x, &obb, &mut got);
            let want: Vec<usize> = (0..x.len()).filter(|&i| obb.contains(&x[i])).collect();
            prop_assert_eq!(got, want);
        }

        #[test]
        fn sphere_and_nearest_equal_brute_force(
            pts in prop::collection::vec((-0.1f64..0.1, -0.1f64..0.1, -0.15f64..0.15), 1..300),
            c in (-0.3f64..0.3, -0.3f64..0.3, -0.3f64..0.3),
            r in 0.0f64..0.08,
        ) {
            let x = cloud(&pts);
            let mut grid = SurfaceGrid::new(x.len(), 0.01);
            grid.rebuild(&x);
            let c = Vector3::new(c.0, c.1, c.2);
            let mut got = Vec::new();
            grid.query_sphere(&x, &c, r, &mut got);
            let want: Vec<usize> =
                (0..x.len()).filter(|&i| (x[i] - c).norm_squared() <= r * r).collect();
            prop_assert_eq!(got, want);
            let (i, d) = grid.nearest(&x, &c).unwrap();
            let dmin = x.iter().map(|p| (p - c).norm()).fold(f64::INFINITY, f64::min);
            prop_assert!((d - dmin).abs() < 1e-15 && ((x[i] - c).norm() - dmin).abs() < 1e-15);
        }
    }

    /// Regression (issue 20): a diverged model's far-away or non-finite
    /// nodes made the span overflow and `rebuild` index out of bounds. They
    /// are now skipped (counted) and the healthy points are still found
    /// exactly as by brute force.
    #[test]
    fn far_away_and_non_finite_points_are_skipped_not_binned() {
        let x = vec![
            Vector3::new(0.01, 0.0, 0.0),
            Vector3::new(1e308, -1e308, 0.0),
            Vector3::new(f64::NAN, 0.0, 0.0),
            Vector3::new(0.0, f64::INFINITY, 0.0),
            Vector3::new(2e3, 0.0, 0.0),
            Vector3::new(-0.02, 0.01, 0.0),
        ];
        let mut grid = SurfaceGrid::new(x.len(), 1e-3);
        assert_eq!(grid.rebuild(&x), 4);
        let mut out = Vec::new();
        grid.query_sphere(&x, &Vector3::zeros(), 0.1, &mut out);
        assert_eq!(out, vec![0, 5]);
        let (i, d) = grid.nearest(&x, &Vector3::new(0.011, 0.0, 0.0)).unwrap();
        assert_eq!(i, 0);
        assert!((d - 0.001).abs() < 1e-15);
        assert_eq!(grid.nearest(&x, &Vector3::new(f64::NAN, 0.0, 0.0)), None);
        // All points unusable: the grid is empty and queries end.
        let bad = vec![Vector3::repeat(f64::NAN); 3];
        assert_eq!(grid.rebuild(&bad), 3);
        assert_eq!(grid.nearest(&bad, &Vector3::zeros()), None);
    }

    #[test]
    fn spread_out_points_grow_the_cell_to_fit_capacity() {
        let x = vec![Vector3::zeros(), Vector3::new(100.0, 100.0, 100.0)];
        let mut grid = SurfaceGrid::new(2, 0.001);
        grid.rebuild(&x);
        assert!(grid.cell_size() > 1.0);
        let mut out = Vec::new();
        grid.query_sphere(&x, &Vector3::new(99.0, 99.0, 99.0), 2.0, &mut out);
        assert_eq!(out, vec![1]);
    }
}
