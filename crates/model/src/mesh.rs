//! The surface mesh of the thigh: an `n_θ × n_z` grid on the elliptic
//! cylinder or on a patient's tapered leg (periodic in θ; see
//! [`crate::leg`]), its triangles, its spring edges by kind, and the inner
//! layer of anchors (paper §3, Fig. 2).

mod patch;

use crate::config::{ConfigError, ThighGeometry};
use crate::leg::LegSurface;
use crate::Vec3;

/// Kind of a mesh edge carrying a linear spring.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EdgeKind {
    /// Nearest neighbours in θ or in z.
    Structural,
    /// Diagonals of each grid quad.
    Shear,
    /// Second neighbours in θ or in z.
    Bending,
}

/// A mesh edge (linear spring) between nodes `i` and `j`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// First node.
    pub i: usize,
    /// Second node.
    pub j: usize,
    /// Kind.
    pub kind: EdgeKind,
}

/// The surface mesh: plain data, built once from a [`ThighGeometry`].
///
/// Node `k` sits at grid indices `(i_θ, i_z)` with `k = i_z · n_θ + i_θ`,
/// at angle `θ = 2π i_θ / n_θ` and height `z = −L/2 + L i_z / (n_z − 1)`
/// (on the cylinder θ is the ellipse's parameter; on a leg, the polar angle
/// around the leg's axis).
#[derive(Debug, Clone)]
pub struct SurfaceMesh {
    geometry: ThighGeometry,
    rest_positions: Vec<Vec3>,
    anchors: Vec<Vec3>,
    rest_normals: Vec<Vec3>,
    areas: Vec<f64>,
    triangles: Vec<[usize; 3]>,
    edges: Vec<Edge>,
    fixed: Vec<bool>,
    layer_scale: Vec<f64>,
    stiffness: Vec<f64>,
    leg: Option<LegSurface>,
}

impl SurfaceMesh {
    /// Generates the mesh; validates the geometry first (errors name `thigh.*`).
    pub fn new(geometry: &ThighGeometry) -> Result<Self, ConfigError> {
        geometry.validate("thigh")?;
        let leg = LegSurface::new(geometry, "thigh")?;
        let (nt, nz) = (geometry.n_theta, geometry.n_z);
        let n = nt * nz;
        let idx = |it: usize, iz: usize| iz * nt + (it % nt);
        let mut rest_positions = Vec::with_capacity(n);
        let mut anchors = Vec::with_capacity(n);
        let mut rest_normals = Vec::with_capacity(n);
        let mut layer_scale = Vec::with_capacity(n);
        let mut stiffness = Vec::with_capacity(n);
        for iz in 0..nz {
            let z = geometry.z(iz);
            for it in 0..nt {
                let theta = geometry.theta(it);
                if let Some(leg) = &leg {
                    let node = leg.node(theta, z);
                    rest_positions.push(node.position);
                    rest_normals.push(node.normal);
                    anchors.push(node.anchor);
                    let rest = (node.position - node.anchor).norm();
                    layer_scale.push(rest / geometry.tissue_thickness);
                    stiffness.push(node.stiffness);
                } else {
                    let p = geometry.surface_point(theta, z);
                    let nrm = geometry.surface_normal(theta);
                    let a = geometry.anchor_xy(theta);
                    rest_positions.push(Vec3::new(p[0], p[1], p[2]));
                    rest_normals.push(Vec3::new(nrm[0], nrm[1], nrm[2]));
                    anchors.push(Vec3::new(a[0], a[1], z));
                    layer_scale.push(1.0);
                    stiffness.push(1.0);
                }
            }
        }
        let mut triangles = Vec::with_capacity(2 * nt * (nz - 1));
        for iz in 0..nz - 1 {
            for it in 0..nt {
                let (a, b) = (idx(it, iz), idx(it + 1, iz));
                let (c, d) = (idx(it + 1, iz + 1), idx(it, iz + 1));
                // (b − a) ~ ∂p/∂θ, (d − a) ~ ẑ: counter-clockwise seen from outside.
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        let mut areas = vec![0.0; n];
        for t in &triangles {
            let [a, b, c] = t.map(|k| rest_positions[k]);
            let third = (b - a).cross(&(c - a)).norm() / 6.0;
            for &k in t {
                areas[k] += third;
            }
        }
        let mut edges = Vec::with_capacity(6 * n);
        for iz in 0..nz {
            for it in 0..nt {
                let k = idx(it, iz);
                let mut push = |j: usize, kind| edges.push(Edge { i: k, j, kind });
                push(idx(it + 1, iz), EdgeKind::Structural);
                push(idx(it + 2, iz), EdgeKind::Bending);
                if iz + 1 < nz {
                    push(idx(it, iz + 1), EdgeKind::Structural);
                    push(idx(it + 1, iz + 1), EdgeKind::Shear);
                    push(idx(it + nt - 1, iz + 1), EdgeKind::Shear);
                }
                if iz + 2 < nz {
                    push(idx(it, iz + 2), EdgeKind::Bending);
                }
            }
        }
        let fixed = (0..n)
            .map(|k| geometry.hold_ends && (k / nt == 0 || k / nt == nz - 1))
            .collect();
        Ok(SurfaceMesh {
            geometry: geometry.clone(),
            rest_positions,
            anchors,
            rest_normals,
            areas,
            triangles,
            edges,
            fixed,
            layer_scale,
            stiffness,
            leg,
        })
    }

    /// The patient's leg the mesh follows (`None` on the elliptic cylinder).
    pub fn leg(&self) -> Option<&LegSurface> {
        self.leg.as_ref()
    }

    /// Each node's normal-spring rest length over the reference layer
    /// `thigh.tissue_thickness` (1 on the cylinder): the factor on the
    /// normal law's `b` and asymptote (see `TissueParams`).
    pub fn layer_scales(&self) -> &[f64] {
        &self.layer_scale
    }

    /// Each node's factor on its normal spring's stiffness (1 on the
    /// cylinder; patient and adductor canal on a leg, see [`crate::leg`]).
    pub fn stiffness_factors(&self) -> &[f64] {
        &self.stiffness
    }

    /// The geometry the mesh was built from.
    pub fn geometry(&self) -> &ThighGeometry {
        &self.geometry
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.rest_positions.len()
    }

    /// Nodes around the circumference.
    pub fn n_theta(&self) -> usize {
        self.geometry.n_theta
    }

    /// Node rings along z.
    pub fn n_z(&self) -> usize {
        self.geometry.n_z
    }

    /// Rest positions of the surface nodes (m).
    pub fn rest_positions(&self) -> &[Vec3] {
        &self.rest_positions
    }

    /// Anchors of the normal springs on the inner layer (m), fixed.
    pub fn anchors(&self) -> &[Vec3] {
        &self.anchors
    }

    /// Outward unit normals of the skin at rest.
    pub fn rest_normals(&self) -> &[Vec3] {
        &self.rest_normals
    }

    /// Lumped area of each node (m²): a third of each adjacent triangle.
    pub fn areas(&self) -> &[f64] {
        &self.areas
    }

    /// Triangles (node indices, counter-clockwise seen from outside).
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Spring edges of every kind.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Dirichlet flags: true for nodes held fixed (the end rings if `hold_ends`).
    pub fn fixed(&self) -> &[bool] {
        &self.fixed
    }

    /// Node index of grid indices `(i_θ, i_z)` (`i_θ` taken modulo `n_θ`).
    ///
    /// # Panics
    /// If `i_z >= n_z`.
    pub fn node_index(&self, i_theta: usize, i_z: usize) -> usize {
        assert!(i_z < self.n_z(), "i_z = {i_z} >= n_z = {}", self.n_z());
        i_z * self.n_theta() + i_theta % self.n_theta()
    }

    /// Grid indices `(i_θ, i_z)` of node `k`.
    pub fn grid_index(&self, k: usize) -> (usize, usize) {
        (k % self.n_theta(), k / self.n_theta())
    }

    /// Angle θ (rad) and height z (m) of node `k` at rest.
    pub fn theta_z(&self, k: usize) -> (f64, f64) {
        let (it, iz) = self.grid_index(k);
        (self.geometry.theta(it), self.geometry.z(iz))
    }

    /// The node nearest to the rest surface point `(θ, z)`: θ (rad) is taken
    /// modulo 2π, z (m) is clamped to the segment. Non-finite input gives node 0's column/ring.
    pub fn node_at(&self, theta: f64, z: f64) -> usize {
        let nt = self.n_theta() as f64;
        let t = (theta / std::f64::consts::TAU * nt).round();
        let it = if t.is_finite() {
            t.rem_euclid(nt) as usize % self.n_theta()
        } else {
            0
        };
        let l = self.geometry.length;
        let s = ((z + 0.5 * l) / l * (self.n_z() - 1) as f64).round();
        let iz = if s.is_finite() {
            s.clamp(0.0, (self.n_z() - 1) as f64) as usize
        } else {
            0
        };
        self.node_index(it, iz)
    }

    /// Pairs of nodes coupled by a spring (the off-diagonal block pattern).
    pub fn coupled_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.edges.iter().map(|e| (e.i, e.j))
    }
}
