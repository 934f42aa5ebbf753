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
//!
//! **Kept up to date** (issue 18). The contact rebins the surface two or
//! three times per physics step, and between two calls the nodes move by
//! micrometres to millimetres: most stay in their cell. By default
//! ([`SurfaceGrid::set_incremental`]) a full rebuild pads the bounding box by
//! half a target cell on every side, and the next [`SurfaceGrid::rebuild`]
//! first recomputes each point's cell in the same grid: if every point is
//! still strictly inside the grid's box, the cells that changed are re-sorted
//! in place (or nothing is done if none changed); only a point leaving the
//! box (or a non-finite one) forces a full rebuild. Queries stay exact
//! either way: they only need every point in the cell its coordinates give.

use crate::probe::OrientedBox;
use nalgebra::Vector3;

/// What the last [`SurfaceGrid::rebuild`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum GridUpdate {
    /// Bounding box, cell size and counting sort from scratch.
    #[default]
    Rebuilt,
    /// Same grid; some points changed cell and were re-sorted.
    Rebinned,
    /// Same grid; no point changed cell, nothing was re-sorted.
    Unchanged,
}

/// Uniform grid over a point set, rebuilt each step without allocation.
#[derive(Debug, Clone)]
pub struct SurfaceGrid {
    target_cell: f64,
    cell: f64,
    /// `1 / cell`, 1/m.
    inv_cell: f64,
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
    /// Points given to the last binning (`x.len()` clipped to capacity).
    n_given: usize,
    /// Keep the grid between calls when the points stay inside it.
    incremental: bool,
    /// True once a full rebuild has binned every point it was given.
    reusable: bool,
    last: GridUpdate,
}

/// Cell marker of a point left out of the grid (non-finite or too far).
const SKIPPED: u32 = u32::MAX;

impl SurfaceGrid {
    /// A grid for `n_points` points with cells of edge `cell_size` (m) when
    /// they fit in the capacity (`8 n_points` cells, at least 4096).
    pub fn new(n_points: usize, cell_size: f64) -> Self {
        let max_cells = (8 * n_points).max(4096);
        let cell = cell_size.max(f64::MIN_POSITIVE);
        Self {
            target_cell: cell,
            cell,
            inv_cell: 1.0 / cell,
            origin: Vector3::zeros(),
            dims: [1, 1, 1],
            max_cells,
            cell_start: vec![0; max_cells + 1],
            entries: vec![0; n_points],
            point_cell: vec![0; n_points],
            n_points: 0,
            n_given: 0,
            incremental: true,
            reusable: false,
            last: GridUpdate::Rebuilt,
        }
    }

    /// Keeps the grid between calls of [`Self::rebuild`] while the points
    /// stay inside it (`true`, the default), or rebuilds it from scratch
    /// every time (`false`: the implementation before issue 18, kept for
    /// same-run comparisons and tests). Queries return the same either way.
    pub fn set_incremental(&mut self, on: bool) {
        self.incremental = on;
        self.reusable = false;
    }

    /// What the last [`Self::rebuild`] did.
    pub fn last_update(&self) -> GridUpdate {
        self.last
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
    ///
    /// With [`Self::set_incremental`] on (the default), the grid of the
    /// previous call is kept if every point is still strictly inside its box
    /// (see the module docs; [`Self::last_update`] tells which path ran).
    pub fn rebuild(&mut self, x: &[Vector3<f64>]) -> usize {
        let n = x.len().min(self.entries.len());
        if self.incremental && self.reusable && n == self.n_given {
            match self.rebin(&x[..n]) {
                Some(false) => {
                    self.last = GridUpdate::Unchanged;
                    return 0;
                }
                Some(true) => {
                    self.sort_by_cell();
                    self.last = GridUpdate::Rebinned;
                    return 0;
                }
                None => {}
            }
        }
        self.last = GridUpdate::Rebuilt;
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
        if self.incremental {
            // Room for the points to move before the box must be rebuilt.
            let pad = Vector3::repeat(0.5 * self.target_cell);
            lo -= pad;
            hi += pad;
        }
        // span ≤ 2 km (plus the pad) and cell ≥ target > 0: the counts below
        // are finite and computed in f64, so they cannot wrap.
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
        self.inv_cell = 1.0 / cell;
        self.origin = lo;
        self.n_given = n;
        let mut binned = 0;
        for (i, p) in x[..n].iter().enumerate() {
            self.point_cell[i] = if usable(p) {
                binned += 1;
                self.cell_of(p) as u32
            } else {
                SKIPPED
            };
        }
        self.sort_by_cell();
        self.reusable = binned == n;
        n - binned
    }

    /// Recomputes every point's cell in the current grid into `point_cell`:
    /// whether some point changed cell, or `None` if a point is not strictly
    /// inside the grid's box (or not finite), after which `point_cell` is
    /// partly overwritten and the caller must rebuild from scratch.
    fn rebin(&mut self, x: &[Vector3<f64>]) -> Option<bool> {
        let dims = self.dims.map(|d| d as f64);
        let (o, inv) = (self.origin, self.inv_cell);
        let mut changed = false;
        for (p, cell) in x.iter().zip(&mut self.point_cell) {
            let t = (p - o) * inv;
            // One negated test: NaN fails every comparison and is outside.
            let inside = t.x >= 0.0
                && t.y >= 0.0
                && t.z >= 0.0
                && t.x < dims[0]
                && t.y < dims[1]
                && t.z < dims[2];
            if !inside {
                return None;
            }
            // t ≥ 0 and below dims: the truncation is the floor and in range
            // (the same cell as `cell_of`, which clamps what is already in).
            let (i, j, k) = (t.x as usize, t.y as usize, t.z as usize);
            let c = ((k * self.dims[1] + j) * self.dims[0] + i) as u32;
            changed |= c != *cell;
            *cell = c;
        }
        Some(changed)
    }

    /// Counting sort of the points `0..n_given` by `point_cell` (skipping
    /// [`SKIPPED`] ones) into `cell_start` and `entries`.
    fn sort_by_cell(&mut self) {
        let n = self.n_given;
        let n_cells = self.dims[0] * self.dims[1] * self.dims[2];
        self.cell_start[..=n_cells].fill(0);
        let mut binned = 0;
        for &c in &self.point_cell[..n] {
            if c != SKIPPED {
                self.cell_start[c as usize + 1] += 1;
                binned += 1;
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
    }

    /// Cell coordinate of `v` (m) along `axis`: `⌊(v − origin)/cell⌋`
    /// clamped to the grid (NaN and below the origin give 0). The saturating
    /// `as` conversion truncates, which is the floor for `t ≥ 0`, and is
    /// monotonic in `v` as the product is: a point between two query bounds
    /// has its cell between theirs, which is all the queries need.
    fn coord(&self, v: f64, axis: usize) -> usize {
        let t = (v - self.origin[axis]) * self.inv_cell;
        (t as usize).min(self.dims[axis] - 1)
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

    /// A grid kept up to date while the points move (small steps that
    /// rebin, a jump out of the box that rebuilds, a rest that changes
    /// nothing, a non-finite point) answers every query as brute force does,
    /// and as a grid rebuilt from scratch does.
    #[test]
    fn kept_grid_answers_as_brute_force_while_points_move() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(18);
        let mut x: Vec<Vector3<f64>> = (0..300)
            .map(|_| {
                Vector3::new(
                    rng.gen_range(-0.08..0.08),
                    rng.gen_range(-0.07..0.07),
                    rng.gen_range(-0.15..0.15),
                )
            })
            .collect();
        let mut kept = SurfaceGrid::new(x.len(), 0.012);
        let mut fresh = SurfaceGrid::new(x.len(), 0.012);
        fresh.set_incremental(false);
        let mut seen = [0usize; 3];
        let (mut got, mut want) = (Vec::new(), Vec::new());
        for round in 0..60 {
            let step = match round % 10 {
                0 | 1 => 0.0, // at rest: unchanged
                9 => 0.05,    // a jump: some point leaves the box
                _ => 0.002,   // small motion: some points change cell
            };
            for p in &mut x {
                *p += Vector3::new(
                    rng.gen_range(-step..=step),
                    rng.gen_range(-step..=step),
                    rng.gen_range(-step..=step),
                );
            }
            if round == 45 {
                x[7] = Vector3::new(f64::NAN, 0.0, 0.0);
            }
            assert_eq!(kept.rebuild(&x), fresh.rebuild(&x), "round {round}");
            seen[kept.last_update() as usize] += 1;
            assert_eq!(fresh.last_update(), GridUpdate::Rebuilt);
            for _ in 0..5 {
                let c = Vector3::new(
                    rng.gen_range(-0.1..0.1),
                    rng.gen_range(-0.1..0.1),
                    rng.gen_range(-0.2..0.2),
                );
                let r = rng.gen_range(0.0..0.05);
                kept.query_sphere(&x, &c, r, &mut got);
                fresh.query_sphere(&x, &c, r, &mut want);
                let brute: Vec<usize> = (0..x.len())
                    .filter(|&i| (x[i] - c).norm_squared() <= r * r)
                    .collect();
                assert_eq!(got, brute, "round {round}");
                assert_eq!(want, brute, "round {round}");
                let pose = Isometry3::from_parts(
                    Translation3::from(c),
                    UnitQuaternion::from_euler_angles(r, -r, 2.0 * r),
                );
                let obb = Probe::default().body_box(&pose, 0.004);
                kept.query_box(&x, &obb, &mut got);
                let brute: Vec<usize> = (0..x.len()).filter(|&i| obb.contains(&x[i])).collect();
                assert_eq!(got, brute, "round {round}");
                assert_eq!(kept.nearest(&x, &c), fresh.nearest(&x, &c), "round {round}");
            }
        }
        assert!(
            seen.iter().all(|&c| c > 0),
            "rebuilt, rebinned, unchanged: {seen:?}"
        );
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
