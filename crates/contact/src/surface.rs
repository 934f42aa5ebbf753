//! Signed distance from a point to the deformed thigh surface (paper §2:
//! "the minimum distance from the probe to the thigh as well as the partial
//! derivatives of this distance with respect to the probe position").
//!
//! The surface is the model's triangle mesh at the current node positions.
//! Only triangles near the query point are examined: the broad-phase grid
//! gives the nearest node at distance `d_n`; the nearest point of the surface
//! is at most `d_n` away, and any point of a triangle lies within the
//! triangle's longest edge of one of its vertices, so the closest triangle
//! has a vertex within `d_n + ℓ_max` of the query point. Those vertices'
//! triangles are tested exactly (Ericson, *Real-Time Collision Detection*
//! §5.1.5).
//!
//! Sign: positive outside. Triangles are oriented once, at construction, so
//! that their normals agree with the mesh's outward rest normals. When the
//! closest point is shared by several triangles (an edge or a vertex), the
//! sign is taken from the triangle whose normal is best aligned with
//! `p − q`, which is exact on convex parts and on faces.

use crate::grid::SurfaceGrid;
use nalgebra::Vector3;

/// The closest surface point to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Signed distance `D` from the query point to the surface, m (> 0 outside).
    pub distance: f64,
    /// `∇D` with respect to the query point: the unit vector from the surface
    /// towards the query point (outward normal where `D > 0`).
    pub gradient: Vector3<f64>,
    /// The closest surface point `q`, m.
    pub closest: Vector3<f64>,
    /// Index of the triangle holding `q`.
    pub triangle: usize,
}

/// Node → triangle adjacency (CSR) with a per-query visit marker, so that
/// a triangle shared by several candidate nodes is examined once.
#[derive(Debug, Clone)]
pub struct Adjacency {
    /// `start[i]..start[i+1]` indexes `list` for node `i`.
    start: Vec<u32>,
    list: Vec<u32>,
    stamp: Vec<u32>,
    epoch: u32,
}

impl Adjacency {
    /// The triangles around each of `n` nodes.
    pub fn new(n: usize, triangles: &[[usize; 3]]) -> Self {
        let mut start = vec![0u32; n + 1];
        for t in triangles {
            for &v in t {
                start[v + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut cursor = start.clone();
        let mut list = vec![0u32; start[n] as usize];
        for (ti, t) in triangles.iter().enumerate() {
            for &v in t {
                list[cursor[v] as usize] = ti as u32;
                cursor[v] += 1;
            }
        }
        Self {
            start,
            list,
            stamp: vec![0; triangles.len()],
            epoch: 0,
        }
    }

    /// Positions in the adjacency list of node `i`'s triangles.
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i] as usize..self.start[i + 1] as usize
    }

    /// The triangle at position `k` of the list.
    pub fn triangle_at(&self, k: usize) -> usize {
        self.list[k] as usize
    }

    /// Starts a new query: every triangle becomes unvisited.
    pub fn next_epoch(&mut self) {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.fill(0);
            self.epoch = 1;
        }
    }

    /// Marks triangle `t` visited; true if it was not yet in this query.
    pub fn visit(&mut self, t: usize) -> bool {
        let first = self.stamp[t] != self.epoch;
        self.stamp[t] = self.epoch;
        first
    }
}

/// Scratch and topology for signed-distance queries; reusable across steps
/// without allocation.
#[derive(Debug, Clone)]
pub struct SurfaceDistance {
    triangles: Vec<[usize; 3]>,
    adjacency: Adjacency,
    nodes: Vec<usize>,
}

impl SurfaceDistance {
    /// Builds the node→triangle adjacency and orients the triangles outward
    /// with the nodes' rest positions and outward rest normals.
    pub fn new(
        rest: &[Vector3<f64>],
        rest_normals: &[Vector3<f64>],
        triangles: &[[usize; 3]],
    ) -> Self {
        let n = rest.len();
        let oriented: Vec<[usize; 3]> = triangles
            .iter()
            .map(|&[a, b, c]| {
                let nf = (rest[b] - rest[a]).cross(&(rest[c] - rest[a]));
                let nv = rest_normals[a] + rest_normals[b] + rest_normals[c];
                if nf.dot(&nv) < 0.0 {
                    [a, c, b]
                } else {
                    [a, b, c]
                }
            })
            .collect();
        Self {
            adjacency: Adjacency::new(n, &oriented),
            triangles: oriented,
            nodes: Vec::with_capacity(n),
        }
    }

    /// The triangles, oriented with outward normals.
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Outward unit normal of triangle `t` at positions `x`.
    pub fn triangle_normal(&self, x: &[Vector3<f64>], t: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangles[t];
        (x[b] - x[a]).cross(&(x[c] - x[a])).normalize()
    }

    /// Signed distance from `p` to the surface at positions `x` (m), using
    /// `grid` (rebuilt on `x`) to restrict the search. `None` if the mesh
    /// has no triangles or `p` is not finite. Allocation-free once the
    /// scratch has grown to the number of nodes.
    pub fn query(
        &mut self,
        grid: &SurfaceGrid,
        x: &[Vector3<f64>],
        p: &Vector3<f64>,
    ) -> Option<SurfacePoint> {
        if self.triangles.is_empty() || !p.iter().all(|c| c.is_finite()) {
            return None;
        }
        let (_, d_node) = grid.nearest(x, p)?;
        let mut l_max2: f64 = 0.0;
        for &[a, b, c] in &self.triangles {
            l_max2 = l_max2
                .max((x[b] - x[a]).norm_squared())
                .max((x[c] - x[b]).norm_squared())
                .max((x[a] - x[c]).norm_squared());
        }
        let radius = d_node + l_max2.sqrt();
        let mut nodes = std::mem::take(&mut self.nodes);
        grid.query_sphere(x, p, radius * (1.0 + 1e-12), &mut nodes);
        self.adjacency.next_epoch();
        let mut best: Option<(f64, f64, Vector3<f64>, usize)> = None; // (d², |cos|, q, t)
        for &i in &nodes {
            for k in self.adjacency.range(i) {
                let t = self.adjacency.triangle_at(k);
                if !self.adjacency.visit(t) {
                    continue;
                }
                let [a, b, c] = self.triangles[t];
                let q = closest_on_triangle(p, &x[a], &x[b], &x[c]);
                let d2 = (p - q).norm_squared();
                let nf = (x[b] - x[a]).cross(&(x[c] - x[a]));
                let cos = (p - q).dot(&nf).abs() / (nf.norm() * d2.sqrt()).max(f64::MIN_POSITIVE);
                let better = match best {
                    None => true,
                    Some((bd2, bcos, _, _)) => {
                        let tie = (d2 - bd2).abs() <= 1e-12 * bd2.max(1e-30);
                        (tie && cos > bcos) || (!tie && d2 < bd2)
                    }
                };
                if better {
                    best = Some((d2, cos, q, t));
                }
            }
        }
        self.nodes = nodes;
        let (d2, _, q, t) = best?;
        let nf = self.triangle_normal(x, t);
        let d = d2.sqrt();
        let outside = (p - q).dot(&nf) >= 0.0;
        let sign = if outside { 1.0 } else { -1.0 };
        let gradient = if d > 1e-12 { sign * (p - q) / d } else { nf };
        Some(SurfacePoint {
            distance: sign * d,
            gradient,
            closest: q,
            triangle: t,
        })
    }
}

/// Closest point to `p` on triangle `abc` (Ericson, *Real-Time Collision
/// Detection*, §5.1.5: Voronoi regions of vertices, edges, face), m.
pub fn closest_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> Vector3<f64> {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A closed octahedron-like sphere: a UV sphere of radius `r`.
    fn uv_sphere(r: f64, nt: usize, np: usize) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
        let mut x = vec![Vector3::new(0.0, 0.0, r), Vector3::new(0.0, 0.0, -r)];
        for j in 1..np {
            let ph = std::f64::consts::PI * j as f64 / np as f64;
            for i in 0..nt {
                let th = 2.0 * std::f64::consts::PI * i as f64 / nt as f64;
                x.push(r * Vector3::new(ph.sin() * th.cos(), ph.sin() * th.sin(), ph.cos()));
            }
        }
        let id = |j: usize, i: usize| 2 + (j - 1) * nt + i % nt;
        let mut t = Vec::new();
        for i in 0..nt {
            t.push([0, id(1, i + 1), id(1, i)]); // deliberately mixed winding
            t.push([1, id(np - 1, i), id(np - 1, i + 1)]);
            for j in 1..np - 1 {
                t.push([id(j, i), id(j + 1, i), id(j + 1, i + 1)]);
                t.push([id(j, i), id(j, i + 1), id(j + 1, i + 1)]);
            }
        }
        (x, t)
    }

    #[test]
    fn closest_point_matches_dense_sampling() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let v: Vec<Vector3<f64>> = (0..4)
                .map(|_| {
                    Vector3::new(
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                    )
                })
                .collect();
            let q = closest_on_triangle(&v[3], &v[0], &v[1], &v[2]);
            let dq = (v[3] - q).norm();
            let n = 200;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let y = v[0] + s * (v[1] - v[0]) + t * (v[2] - v[0]);
                    assert!((v[3] - y).norm() >= dq - 1e-12);
                }
            }
        }
    }

    #[test]
    fn signed_distance_equals_brute_force_on_sphere() {
        let (x, tris) = uv_sphere(0.08, 24, 12);
        let normals: Vec<_> = x.iter().map(|p| p.normalize()).collect();
        let mut sd = SurfaceDistance::new(&x, &normals, &tris);
        let mut grid = SurfaceGrid::new(x.len(), 0.01);
        grid.rebuild(&x);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..300 {
            let p = Vector3::new(
                rng.gen_range(-0.2..0.2),
                rng.gen_range(-0.2..0.2),
                rng.gen_range(-0.2..0.2),
            );
            let s = sd.query(&grid, &x, &p).unwrap();
            let brute = sd
                .triangles()
                .iter()
                .map(|&[a, b, c]| (p - closest_on_triangle(&p, &x[a], &x[b], &x[c])).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                (s.distance.abs() - brute).abs() < 1e-14,
                "{} vs {brute}",
                s.distance
            );
            // Sign: the faceted sphere lies between radius 0.08·cos(π/12) and 0.08.
            if p.norm() > 0.0801 {
                assert!(s.distance > 0.0);
            }
            if p.norm() < 0.07 {
                assert!(s.distance < 0.0);
            }
            assert!((s.gradient.norm() - 1.0).abs() < 1e-12);
            assert!((p - s.gradient * s.distance - s.closest).norm() < 1e-12);
        }
    }
}
