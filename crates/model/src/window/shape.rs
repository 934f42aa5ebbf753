//! Where the active window lies on the grid, and who is in it: the
//! membership rules with their hysteresis (issue 18).
//!
//! Distances are counted in grid cells around (`θ`, periodic) and along
//! (`z`), converted from metres with the mesh's mean rest spacings. With
//! `r` cells of radius and `m` cells of margin, the window's *core* (the
//! nodes integrated implicitly) is the rectangle of half-widths `r + m`
//! around the window's centre node, and the centre moves to the probe's
//! nearest node only when that node is more than `m` cells from it (along
//! either axis). Hence, at every step:
//!
//! - a node within `r` cells of the probe's node is in the core
//!   (`|node − centre| ≤ |node − probe| + |probe − centre| ≤ r + m`);
//! - a node leaves the core only beyond `r + m` cells of the probe's node
//!   (it leaves when the centre moves onto the probe's node).
//!
//! The *patch* adds a band of two held nodes around the core (the bending
//! springs reach two nodes): every spring of a core node lies in the patch.
//! Near an end of the mesh the patch is shifted to stay on it; the core
//! then reaches the end (more nodes than the radius asks, none fewer).

use crate::config::{ConfigError, WindowParams};
use crate::mesh::SurfaceMesh;
use crate::Vec3;

/// Width of the held band around the core (nodes): the bending springs' reach.
pub const BAND: usize = 2;

/// The window's size in grid cells and its patch's size in nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WindowShape {
    /// Radius `r` in cells around and along.
    pub radius: (usize, usize),
    /// Margin `m` in cells around and along.
    pub margin: (usize, usize),
    /// Patch nodes around (`2 (r + m) + 1 + 2·BAND`).
    pub l_theta: usize,
    /// Patch rings along (as `l_theta`, at most `n_z`).
    pub l_z: usize,
}

impl WindowShape {
    /// The shape of `params` on `mesh`: `r` and `r + m` rounded up to whole
    /// cells of the mean rest spacing. An error names
    /// `{prefix}.radius` if the patch would wrap the circumference
    /// (`l_θ > n_θ`): the window would then be the whole mesh.
    pub fn new(
        mesh: &SurfaceMesh,
        params: &WindowParams,
        prefix: &str,
    ) -> Result<Self, ConfigError> {
        let (d_theta, d_z) = mean_spacing(mesh);
        let cells = |len: f64, d: f64| (len / d).ceil() as usize;
        let radius = (cells(params.radius, d_theta), cells(params.radius, d_z));
        let reach = (
            cells(params.radius + params.margin, d_theta),
            cells(params.radius + params.margin, d_z),
        );
        let margin = (reach.0 - radius.0, reach.1 - radius.1);
        let l_theta = 2 * reach.0 + 1 + 2 * BAND;
        let l_z = (2 * reach.1 + 1 + 2 * BAND).min(mesh.n_z());
        if l_theta > mesh.n_theta() {
            return Err(ConfigError::invalid(
                format!("{prefix}.radius"),
                format!(
                    "= {} m (+ margin {} m) needs {l_theta} nodes around at {:.2} mm spacing, \
                     more than the mesh's n_theta = {}: the window would wrap the whole \
                     circumference; use a smaller radius or the full model (enabled = false)",
                    params.radius,
                    params.margin,
                    d_theta * 1e3,
                    mesh.n_theta()
                ),
            ));
        }
        Ok(WindowShape {
            radius,
            margin,
            l_theta,
            l_z,
        })
    }

    /// Half-widths of the core in cells, `r + m`.
    pub fn reach(&self) -> (usize, usize) {
        (self.radius.0 + self.margin.0, self.radius.1 + self.margin.1)
    }

    /// Grid offset `(θ₀, z₀)` of the patch centred on node `(c_θ, c_z)` of
    /// an `n_θ × n_z` grid (shifted along z to stay on the mesh).
    pub fn origin(&self, (ct, cz): (usize, usize), (nt, nz): (usize, usize)) -> (usize, usize) {
        let (ht, hz) = self.reach();
        let theta0 = (ct + nt * (ht + BAND).div_ceil(nt) - ht - BAND) % nt;
        let z0 = cz.saturating_sub(hz + BAND).min(nz - self.l_z);
        (theta0, z0)
    }

    /// True if patch node `(j_θ, j_z)` at origin row `z₀` is in the held
    /// band (not a mesh end: the patch shifted there has no band).
    pub fn in_band(&self, (jt, jz): (usize, usize), z0: usize, nz: usize) -> bool {
        jt < BAND
            || jt >= self.l_theta - BAND
            || (jz < BAND && z0 > 0)
            || (jz >= self.l_z - BAND && z0 + self.l_z < nz)
    }

    /// True if the window centred on `centre` must move to `focus`: more
    /// than `m` cells apart along either axis (θ periodic over `nt`).
    pub fn must_move(&self, centre: (usize, usize), focus: (usize, usize), nt: usize) -> bool {
        let dt = centre.0.abs_diff(focus.0);
        let dt = dt.min(nt - dt);
        dt > self.margin.0 || centre.1.abs_diff(focus.1) > self.margin.1
    }
}

/// Mean rest spacing (m) of neighbours around and along the grid.
pub fn mean_spacing(mesh: &SurfaceMesh) -> (f64, f64) {
    let (nt, nz) = (mesh.n_theta(), mesh.n_z());
    let x = mesh.rest_positions();
    let (mut around, mut along) = (0.0, 0.0);
    for iz in 0..nz {
        for it in 0..nt {
            let k = mesh.node_index(it, iz);
            around += (x[mesh.node_index(it + 1, iz)] - x[k]).norm();
            if iz + 1 < nz {
                along += (x[mesh.node_index(it, iz + 1)] - x[k]).norm();
            }
        }
    }
    (
        around / (nt * nz) as f64,
        along / (nt * (nz - 1)).max(1) as f64,
    )
}

/// The node of `mesh` nearest (at rest) to `p` (m), by descent on the grid
/// from node `start` (each move to the nearest of the 8 neighbours, at most
/// `n_θ + n_z` moves). For a probe near the skin, whose cross-sections are
/// convex, the distance has a single minimum over the grid near the probe
/// and the descent from the previous centre reaches it; the window's first
/// placement scans the whole mesh instead. Allocates nothing.
pub fn nearest_node(mesh: &SurfaceMesh, p: &Vec3, start: usize) -> usize {
    let x = mesh.rest_positions();
    let (nt, nz) = (mesh.n_theta(), mesh.n_z());
    let mut k = start;
    let mut best = (x[k] - p).norm_squared();
    // At most a walk across the grid; NaN never improves.
    for _ in 0..nt + nz {
        let (it, iz) = mesh.grid_index(k);
        let mut next = k;
        for dz in [-1isize, 0, 1] {
            let jz = iz as isize + dz;
            if jz < 0 || jz >= nz as isize {
                continue;
            }
            for dt in [nt - 1, 0, 1] {
                let j = mesh.node_index(it + dt, jz as usize);
                let d = (x[j] - p).norm_squared();
                if d < best {
                    (best, next) = (d, j);
                }
            }
        }
        if next == k {
            break;
        }
        k = next;
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Radius 3 cells, margin 1: core half-width 4, patch 4·2 + 1 + 4 = 13.
    fn shape(l_z: usize) -> WindowShape {
        WindowShape {
            radius: (3, 3),
            margin: (1, 1),
            l_theta: 13,
            l_z,
        }
    }

    #[test]
    fn the_patch_wraps_around_and_stays_on_the_mesh_along() {
        let s = shape(13);
        // Centre at θ = 2 on a 40 × 30 grid: the patch starts 6 nodes
        // before it, across the seam.
        assert_eq!(s.origin((2, 15), (40, 30)), (36, 9));
        // Near the ends along z it is shifted onto the mesh.
        assert_eq!(s.origin((0, 1), (40, 30)).1, 0);
        assert_eq!(s.origin((0, 28), (40, 30)).1, 17);
    }

    #[test]
    fn the_band_is_held_except_at_the_mesh_ends() {
        let s = shape(13);
        assert!(s.in_band((1, 6), 9, 30) && s.in_band((11, 6), 9, 30));
        assert!(s.in_band((6, 1), 9, 30) && s.in_band((6, 11), 9, 30));
        assert!(!s.in_band((2, 2), 9, 30) && !s.in_band((10, 10), 9, 30));
        // Shifted onto the first ring: its rows are the mesh's own.
        assert!(!s.in_band((6, 0), 0, 30) && s.in_band((6, 12), 0, 30));
        assert!(!s.in_band((6, 12), 17, 30) && s.in_band((6, 0), 17, 30));
    }

    #[test]
    fn the_window_moves_only_beyond_the_margin() {
        let s = shape(13);
        assert!(!s.must_move((0, 10), (39, 11), 40)); // one cell, across the seam
        assert!(s.must_move((0, 10), (38, 10), 40));
        assert!(s.must_move((0, 10), (0, 12), 40));
    }
}
