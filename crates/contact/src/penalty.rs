//! The penalty response of the paper's Eq. 2 as a [`ForceModel`]:
//!
//! `F_c = (−λ_c v − μ_c v̇) k̂` if `v < 0`, else `0`,
//!
//! `v` the penetrated volume (negative when penetrating), `k̂` the contact
//! direction (the face normal into the tissue), `λ_c, μ_c` the contact
//! rigidity (N/m³) and damping (N·s/m³).
//!
//! **Penetrated volume.** The face is sampled by a regular grid of points
//! `s_j`, each standing for the area `a_j` (cell-centred, spacing
//! `sample_spacing`). Under each sample the surface is the highest triangle
//! (in the face's frame) whose projection on the face plane contains it;
//! with barycentric weights `β_jm` on its nodes `m`, the surface height above
//! the face is `d_j = Σ_m β_jm y_m` (local `y`), and the penetrated volume
//! under the sample is `a_j d_j` where `d_j > 0`. Each node receives its
//! barycentric share: the node force is Eq. 2 with `v` the node's share of
//! the penetrated volume, `v_m = −Σ_j β_jm a_j d_j`. Sampling the face
//! rather than testing nodes against the box keeps the force continuous as
//! the probe slides over a mesh coarser than the face (the default rings are
//! 15 mm apart, the face 10 mm thick: a node test would let the face fall
//! between two rings) and makes `Σ v` the penetrated volume itself.
//!
//! **Lagged geometry.** The triangle and weights of each sample are found
//! once per step, in [`PenaltyContact::prepare`], and kept during the
//! step's Newton iterations; `d_j` is then linear in the node positions, and
//! the Jacobians below are exact. (The dependence of `β` on the nodes'
//! motion across the face is negligible under a flat face: it is the
//! surface slope under the face.)
//!
//! **Jacobians.** With `d_j = −Σ_m β_jm (x_m − p)·k̂` and
//! `ḋ_j = (ṗ − Σ_m β_jm v_m)·k̂`, for a penetrating sample
//! `∂F_m/∂x_n = −λ_c a_j β_jm β_jn k̂k̂ᵀ` and `∂F_m/∂v_n = −μ_c a_j β_jm β_jn k̂k̂ᵀ`:
//! symmetric, negative semi-definite, coupling only nodes of one triangle
//! (mesh edges, so within the fixed pattern). A stiff `λ_c` stays stable
//! under implicit Euler.
//!
//! **No adhesion** (beyond the paper): when the damper would pull
//! (`λ_c d + μ_c ḋ < 0`) the sample's force is clamped to zero and its
//! Jacobian dropped.
//!
//! **Damper onset** (beyond the paper; issue 18). Eq. 2's damper makes the
//! force jump at first touch: a sample reaching the surface at the rate
//! `ḋ > 0` is pushed with `a_j μ_c ḋ` at zero depth, and nothing just before.
//! Within an implicit step of `h` (`λ = 1`: the force is evaluated at
//! `x₀ + h v`, the probe at its end pose) the depth and its rate are tied,
//! `d = d₀ + h ḋ`, with `d₀` the sample's depth at the step's start, so a
//! sample outside at the start (`d₀ < 0`) sees the force jump by
//! `a_j μ_c |d₀| / h` as `d` crosses 0. The step's equations then have no
//! root (the balance wants the sample exactly at the surface with a force
//! inside the jump) and Newton cycles: the sample enters and leaves on
//! alternate iterates, the residual never falls (the Newton 2-cycle of
//! issue 18, four steps per direct exam at the 8-iteration cap). The
//! damper is therefore made to act on the penetration only: its rate is
//! capped at the rate of a penetration that began at the step's start,
//!
//! `ḋ_c = min(ḋ, d / h)`, so `F = a_j (λ_c d + μ_c ḋ_c)`,
//!
//! which changes nothing for a sample penetrating at the step's start
//! (`d₀ ≥ 0` gives `ḋ = (d − d₀)/h ≤ d/h`) and gives an entering one the
//! force `a_j (λ_c + μ_c/h) d`, continuous from zero. The force is then
//! continuous and non-decreasing in the depth, a kink where the cap or the
//! clamp starts, and the step's equations have their root. In the capped
//! branch `∂F/∂x = −(λ_c + μ_c/h) a_j ββᵀ k̂k̂ᵀ` and `∂F/∂v = 0`, whose
//! implicit-Euler combination `−(h² ∂F/∂x + h ∂F/∂v)` is the uncapped one:
//! the Newton matrix is the same on both sides of the cap. (This is the
//! discrete counterpart of Hunt & Crossley's objection to the linear
//! spring–damper contact, J. Appl. Mech. 42, 1975: the damping force must
//! vanish at zero penetration.) With a blend `λ < 1` of Eq. 1 the force
//! is evaluated at `x₀ + λ h v`, where `d = d₀ + λ h ḋ`: the cap still
//! removes the jump, and also caps a sample already in whose depth grows
//! faster than `d/h` (the default is `λ = 1`). The cap only lowers the
//! damper's force and keeps its sign (`0 ≤ ḋ_c ≤ ḋ` when it acts): the
//! contact stays passive. `h` is the step given to
//! [`PenaltyContact::prepare`]; a query at `h = 0` keeps the last step's,
//! so the wrench after a step is the force the step applied.

use crate::grid::SurfaceGrid;
use crate::params::ContactParams;
use crate::probe::{OrientedBox, Probe};
use crate::surface::Adjacency;
use echothigh_model::{BlockSparse, EdgeMatrix, ForceModel, JacobianScratch, ThighModel, Vec3};
use nalgebra::{Isometry3, Matrix3, Translation3, Vector3};

/// The surface under one face sample, found by [`PenaltyContact::prepare`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleSurface {
    /// Triangle index.
    pub triangle: usize,
    /// Its nodes.
    pub nodes: [usize; 3],
    /// Barycentric weights of the sample on the triangle (sum 1).
    pub beta: [f64; 3],
    /// Height of the surface above the face plane at `prepare`, m.
    pub height: f64,
}

/// Contact state of one face sample at a given state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleContact {
    /// Penetration `d_j` (surface height above the face), m, > 0.
    pub depth: f64,
    /// `ḋ_j`, m/s (positive while penetrating further), as the damper
    /// uses it: capped at `d_j / h` (see the module docs, damper onset).
    pub depth_rate: f64,
    /// True if the cap `ḋ_j ≤ d_j / h` acted (the sample entered within the
    /// step): its force is then `a_j (λ_c + μ_c/h) d_j`, with no velocity
    /// dependence.
    pub onset: bool,
    /// Force magnitude along `k̂` on the tissue, N (≥ 0), clamped.
    pub force: f64,
    /// True if the damper would have pulled and the force was clamped to 0.
    pub clamped: bool,
}

/// Net contact force and torque on the probe.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    /// Force on the probe, N (along `−k̂`).
    pub force: Vec3,
    /// Torque on the probe about the face centre `p`, N·m.
    pub torque: Vec3,
    /// Face samples pressing on the tissue.
    pub samples: usize,
    /// Penetrated volume `Σ a_j d_j`, m³ (≥ 0).
    pub volume: f64,
}

/// Penalty contact between the rigid probe and the thigh surface (Eq. 2).
#[derive(Debug, Clone)]
pub struct PenaltyContact {
    params: ContactParams,
    probe: Probe,
    pose: Isometry3<f64>,
    velocity: Vec3,
    triangles: Vec<[usize; 3]>,
    /// Storage indices of the 9 blocks `(m, n)` of each triangle.
    tri_blocks: Vec<[usize; 9]>,
    adjacency: Adjacency,
    reach: f64,
    grid: SurfaceGrid,
    candidates: Vec<usize>,
    samples_local: Vec<Vec3>,
    sample_area: f64,
    n_sx: usize,
    n_sz: usize,
    surface: Vec<Option<SampleSurface>>,
    /// Step `h` (s) of the damper-onset cap `ḋ ≤ d/h`, from the last
    /// [`Self::prepare`] with `h > 0`; 0 until then (no cap).
    onset_step: f64,
}

impl PenaltyContact {
    /// Contact with `model`'s surface; the probe starts at the identity
    /// pose, at rest. Parameters must have been validated.
    pub fn new(model: &ThighModel, probe: Probe, params: ContactParams) -> Self {
        let mesh = model.mesh();
        let n = mesh.node_count();
        let x = mesh.rest_positions();
        let pattern = model.pattern();
        let triangles = mesh.triangles().to_vec();
        let tri_blocks = triangles
            .iter()
            .map(|t| {
                let mut b = [0usize; 9];
                for (r, &m) in t.iter().enumerate() {
                    for (c, &k) in t.iter().enumerate() {
                        // Triangle edges are mesh edges: in the pattern.
                        b[3 * r + c] = pattern
                            .block_index(m, k)
                            .unwrap_or_else(|| pattern.diagonal_index(m));
                    }
                }
                b
            })
            .collect();
        let max_edge = triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(i, j)| (x[i] - x[j]).norm())
            .fold(0.0, f64::max);
        let spacing = (mesh.areas().iter().sum::<f64>() / n.max(1) as f64).sqrt();
        let n_sx = ((2.0 * probe.half_width / params.sample_spacing).ceil() as usize).max(1);
        let n_sz = ((2.0 * probe.half_elevation / params.sample_spacing).ceil() as usize).max(1);
        let (dx, dz) = (
            2.0 * probe.half_width / n_sx as f64,
            2.0 * probe.half_elevation / n_sz as f64,
        );
        let mut samples_local = Vec::with_capacity(n_sx * n_sz);
        for k in 0..n_sz {
            for i in 0..n_sx {
                samples_local.push(Vec3::new(
                    -probe.half_width + (i as f64 + 0.5) * dx,
                    0.0,
                    -probe.half_elevation + (k as f64 + 0.5) * dz,
                ));
            }
        }
        Self {
            params,
            probe,
            pose: Isometry3::identity(),
            velocity: Vec3::zeros(),
            adjacency: Adjacency::new(n, &triangles),
            triangles,
            tri_blocks,
            // Deformation may stretch edges: 1.5× the longest rest edge.
            reach: 1.5 * max_edge,
            grid: SurfaceGrid::new(n, spacing.max(1e-4)),
            candidates: Vec::with_capacity(n),
            sample_area: dx * dz,
            surface: vec![None; samples_local.len()],
            samples_local,
            n_sx,
            n_sz,
            onset_step: 0.0,
        }
    }

    /// Parameters.
    pub fn params(&self) -> &ContactParams {
        &self.params
    }

    /// Sets the rigidity `λ_c` (N/m³) and damping `μ_c` (N·s/m³).
    pub fn set_rigidity(&mut self, stiffness: f64, damping: f64) {
        self.params.stiffness = stiffness;
        self.params.damping = damping;
    }

    /// Probe geometry.
    pub fn probe(&self) -> &Probe {
        &self.probe
    }

    /// Current probe pose.
    pub fn pose(&self) -> &Isometry3<f64> {
        &self.pose
    }

    /// Contact direction `k̂` at the current pose (unit).
    pub fn direction(&self) -> Vec3 {
        Probe::contact_direction(&self.pose)
    }

    /// Poses the probe (kinematic) with linear velocity `velocity` (m/s).
    pub fn set_probe(&mut self, pose: Isometry3<f64>, velocity: Vec3) {
        self.pose = pose;
        self.velocity = velocity;
    }

    /// The broad-phase grid (rebuilt by [`Self::prepare`]).
    pub fn grid(&self) -> &SurfaceGrid {
        &self.grid
    }

    /// Keeps the broad-phase grid up to date in place (`true`, the default)
    /// or rebuilds it from scratch at every [`Self::prepare`] (`false`, the
    /// implementation before issue 18); see [`SurfaceGrid::set_incremental`].
    pub fn set_incremental_grid(&mut self, on: bool) {
        self.grid.set_incremental(on);
    }

    /// Face samples in the probe frame (m) and the area of each (m²).
    pub fn samples(&self) -> (&[Vec3], f64) {
        (&self.samples_local, self.sample_area)
    }

    /// The surface under each face sample, as found by the last
    /// [`Self::prepare`] (`None`: no triangle under it within the body).
    pub fn sample_surfaces(&self) -> &[Option<SampleSurface>] {
        &self.surface
    }

    /// Storage indices of the 9 blocks of triangle `t` in the model's pattern.
    pub fn triangle_blocks(&self, t: usize) -> &[usize; 9] {
        &self.tri_blocks[t]
    }

    /// Broad and narrow phase: rebuilds the grid on `x` (m), gathers the
    /// nodes near the probe body (inflated by the triangle size, the margin
    /// and what a node or the probe can travel in `h` s at velocities `v`),
    /// and finds the surface under every face sample: the highest triangle,
    /// within `below` (m) under the face and at most the body's height above
    /// it. Allocation-free.
    pub fn prepare(&mut self, x: &[Vec3], v: &[Vec3], h: f64) {
        self.prepare_with_reach(x, v, h, 0.0);
    }

    /// [`Self::prepare`], also finding surfaces up to `below` (m) under the
    /// face (used for the first-touch stiffness). A step `h > 0` becomes
    /// the damper-onset cap's (module docs); `h = 0` keeps the last one.
    pub fn prepare_with_reach(&mut self, x: &[Vec3], v: &[Vec3], h: f64, below: f64) {
        if h.is_finite() && h > 0.0 {
            self.onset_step = h;
        }
        self.grid.rebuild(x);
        // The fastest node (one square root, and none for h = 0).
        let vmax = if h == 0.0 {
            0.0
        } else {
            v.iter()
                .map(|v| v.norm_squared())
                .fold(0.0, f64::max)
                .sqrt()
        };
        let travel = h.abs() * (vmax + self.velocity.norm());
        let travel = if travel.is_finite() { travel } else { 0.0 };
        let inflate = self.reach + self.params.margin + travel;
        let below = below.max(0.0) + self.params.margin + travel;
        let pr = &self.probe;
        let centre = self.pose * Translation3::new(0.0, 0.5 * (pr.height - below), 0.0);
        let obb = OrientedBox {
            pose: centre,
            half_extents: Vector3::new(
                pr.half_width + inflate,
                0.5 * (pr.height + below) + inflate,
                pr.half_elevation + inflate,
            ),
        };
        self.grid.query_box(x, &obb, &mut self.candidates);
        self.surface.fill(None);
        self.adjacency.next_epoch();
        let (dx, dz) = (
            2.0 * pr.half_width / self.n_sx as f64,
            2.0 * pr.half_elevation / self.n_sz as f64,
        );
        for c in 0..self.candidates.len() {
            let node = self.candidates[c];
            for k in self.adjacency.range(node) {
                let t = self.adjacency.triangle_at(k);
                if !self.adjacency.visit(t) {
                    continue;
                }
                let nodes = self.triangles[t];
                let l = nodes.map(|m| Probe::to_local(&self.pose, &x[m]));
                let (xmin, xmax) = (
                    l[0].x.min(l[1].x).min(l[2].x),
                    l[0].x.max(l[1].x).max(l[2].x),
                );
                let (zmin, zmax) = (
                    l[0].z.min(l[1].z).min(l[2].z),
                    l[0].z.max(l[1].z).max(l[2].z),
                );
                let Some((i0, i1)) = index_range(xmin, xmax, -pr.half_width, dx, self.n_sx) else {
                    continue;
                };
                let Some((k0, k1)) = index_range(zmin, zmax, -pr.half_elevation, dz, self.n_sz)
                else {
                    continue;
                };
                for sk in k0..=k1 {
                    for si in i0..=i1 {
                        let j = sk * self.n_sx + si;
                        let s = self.samples_local[j];
                        let Some(beta) = barycentric_xz(&l, s.x, s.z) else {
                            continue;
                        };
                        let height = beta[0] * l[0].y + beta[1] * l[1].y + beta[2] * l[2].y;
                        if height > pr.height || height < -below {
                            continue;
                        }
                        if self.surface[j].map(|o| height > o.height).unwrap_or(true) {
                            self.surface[j] = Some(SampleSurface {
                                triangle: t,
                                nodes,
                                beta,
                                height,
                            });
                        }
                    }
                }
            }
        }
    }

    /// The contact of face sample `j` over surface `s` at `(x, v)`, if the
    /// surface penetrates the face there.
    pub fn sample_contact(
        &self,
        s: &SampleSurface,
        x: &[Vec3],
        v: &[Vec3],
    ) -> Option<SampleContact> {
        let k = self.direction();
        let p = Probe::reference_point(&self.pose);
        let mut depth = 0.0;
        let mut vel = 0.0;
        for (&m, &b) in s.nodes.iter().zip(&s.beta) {
            depth -= b * (x[m] - p).dot(&k);
            vel += b * v[m].dot(&k);
        }
        // NaN depth: no contact.
        if depth.is_nan() || depth <= 0.0 || depth > self.probe.height {
            return None;
        }
        let rate = self.velocity.dot(&k) - vel;
        // Damper onset: ḋ_c = min(ḋ, d/h) (module docs).
        let cap = if self.onset_step > 0.0 {
            depth / self.onset_step
        } else {
            f64::INFINITY
        };
        let onset = rate > cap;
        let depth_rate = if onset { cap } else { rate };
        let a = self.sample_area;
        let raw = a * (self.params.stiffness * depth + self.params.damping * depth_rate);
        let clamped = raw.is_nan() || raw < 0.0;
        Some(SampleContact {
            depth,
            depth_rate,
            onset,
            force: if clamped { 0.0 } else { raw },
            clamped,
        })
    }

    /// The sample's `(−∂F/∂d, −∂F/∂ḋ)` per unit area (N/m³, N·s/m³) of a
    /// contact that is not clamped: `(λ_c, μ_c)`, or `(λ_c + μ_c/h, 0)` where
    /// the damper-onset cap acted (module docs).
    fn rigidity(&self, c: &SampleContact) -> (f64, f64) {
        let (lambda, mu) = (self.params.stiffness, self.params.damping);
        if c.onset {
            (lambda + mu / self.onset_step, 0.0)
        } else {
            (lambda, mu)
        }
    }

    /// Net force and torque of the contact on the probe at `(x, v)`.
    pub fn wrench(&self, x: &[Vec3], v: &[Vec3]) -> Wrench {
        let k = self.direction();
        let mut w = Wrench::default();
        for (j, s) in self.surface.iter().enumerate() {
            let Some(s) = s else { continue };
            if let Some(c) = self.sample_contact(s, x, v) {
                w.volume += self.sample_area * c.depth;
                if c.force > 0.0 {
                    let f = -c.force * k;
                    let arm = self.pose.rotation * self.samples_local[j];
                    w.force += f;
                    w.torque += arm.cross(&f);
                    w.samples += 1;
                }
            }
        }
        w
    }

    /// Calls `visit(surface, contact)` for every face sample in contact
    /// with a non-zero stiffness (not clamped).
    pub fn for_each_contact(
        &self,
        x: &[Vec3],
        v: &[Vec3],
        mut visit: impl FnMut(&SampleSurface, &SampleContact),
    ) {
        for s in self.surface.iter().flatten() {
            if let Some(c) = self.sample_contact(s, x, v) {
                if !c.clamped {
                    visit(s, &c);
                }
            }
        }
    }

    /// Adds `−c ββᵀ ⊗ k̂k̂ᵀ` of one sample (`c` in N/m) into `mat`.
    pub(crate) fn add_sample_block(
        mat: &mut BlockSparse,
        blocks: &[usize; 9],
        beta: &[f64; 3],
        kk: &Matrix3<f64>,
        c: f64,
    ) {
        for r in 0..3 {
            for q in 0..3 {
                mat.add_at(blocks[3 * r + q], &(kk * (-c * beta[r] * beta[q])));
            }
        }
    }
}

/// Range of sample indices `i` with centre `origin + (i + ½) d` in
/// `[lo, hi]`, clamped to `0..n`; `None` if empty.
fn index_range(lo: f64, hi: f64, origin: f64, d: f64, n: usize) -> Option<(usize, usize)> {
    let a = ((lo - origin) / d - 0.5).ceil();
    let b = ((hi - origin) / d - 0.5).floor();
    if a.is_nan() || b.is_nan() || a > b || b < 0.0 || a > (n - 1) as f64 {
        return None;
    }
    Some((a.max(0.0) as usize, (b as usize).min(n - 1)))
}

/// Barycentric weights of the point `(px, pz)` in the projection of the
/// triangle `l` on the local x–z plane, if inside (with a tolerance of
/// 1e-12 so that a sample on a shared edge is found in both triangles).
fn barycentric_xz(l: &[Vec3; 3], px: f64, pz: f64) -> Option<[f64; 3]> {
    let (ax, az) = (l[1].x - l[0].x, l[1].z - l[0].z);
    let (bx, bz) = (l[2].x - l[0].x, l[2].z - l[0].z);
    let det = ax * bz - az * bx;
    if det.abs() < 1e-18 {
        return None;
    }
    let (qx, qz) = (px - l[0].x, pz - l[0].z);
    let b1 = (qx * bz - qz * bx) / det;
    let b2 = (ax * qz - az * qx) / det;
    let b0 = 1.0 - b1 - b2;
    let tol = -1e-12;
    (b0 >= tol && b1 >= tol && b2 >= tol).then_some([b0, b1, b2])
}

impl ForceModel for PenaltyContact {
    fn add_forces(&mut self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        let k = self.direction();
        for s in self.surface.iter().flatten() {
            if let Some(c) = self.sample_contact(s, x, v) {
                for (&m, &b) in s.nodes.iter().zip(&s.beta) {
                    f[m] += (b * c.force) * k;
                }
            }
        }
    }

    fn add_jacobians(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        kmat: &mut BlockSparse,
        bmat: &mut BlockSparse,
    ) {
        let k = self.direction();
        let kk: Matrix3<f64> = k * k.transpose();
        let a = self.sample_area;
        for s in self.surface.iter().flatten() {
            if let Some(c) = self.sample_contact(s, x, v) {
                if !c.clamped {
                    let (lambda, mu) = self.rigidity(&c);
                    let blocks = &self.tri_blocks[s.triangle];
                    Self::add_sample_block(kmat, blocks, &s.beta, &kk, lambda * a);
                    Self::add_sample_block(bmat, blocks, &s.beta, &kk, mu * a);
                }
            }
        }
    }

    /// Direct assembly of `α ∂F/∂x + β ∂F/∂v` into `a`: one block per pair
    /// of a penetrating sample's triangle nodes, `−(α λ_c + β μ_c) a_j β_m β_n k̂k̂ᵀ`
    /// (no scratch matrices, no pass over the whole pattern; `λ_c + μ_c/h`
    /// and 0 where the damper-onset cap acted).
    fn add_scaled_jacobians(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut BlockSparse,
        _scratch: &mut JacobianScratch,
    ) {
        let k = self.direction();
        let kk: Matrix3<f64> = k * k.transpose();
        for s in self.surface.iter().flatten() {
            if let Some(contact) = self.sample_contact(s, x, v) {
                if !contact.clamped {
                    let (lambda, mu) = self.rigidity(&contact);
                    let c = (alpha * lambda + beta * mu) * self.sample_area;
                    Self::add_sample_block(a, &self.tri_blocks[s.triangle], &s.beta, &kk, c);
                }
            }
        }
    }

    /// Edge-form assembly: each penetrating sample is the rank-one term
    /// `−(α λ_c + β μ_c) a_j (β ⊗ k̂)(β ⊗ k̂)ᵀ` on its triangle (`λ_c + μ_c/h`
    /// and 0 where the damper-onset cap acted).
    fn add_scaled_jacobians_edge(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        alpha: f64,
        beta: f64,
        a: &mut EdgeMatrix,
        _scratch: &mut JacobianScratch,
    ) {
        let k = self.direction();
        for s in self.surface.iter().flatten() {
            if let Some(contact) = self.sample_contact(s, x, v) {
                if !contact.clamped {
                    let (lambda, mu) = self.rigidity(&contact);
                    let c = (alpha * lambda + beta * mu) * self.sample_area;
                    // Triangle edges are mesh edges: in the side pattern.
                    let written = a.add_rank_one(s.nodes, s.beta, &k, -c);
                    debug_assert!(written.is_ok());
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_range_picks_cell_centres_inside() {
        // Centres at 0.5, 1.5, ..., 9.5 (origin 0, d 1, n 10).
        assert_eq!(index_range(1.2, 3.7, 0.0, 1.0, 10), Some((1, 3)));
        assert_eq!(index_range(-5.0, 0.4, 0.0, 1.0, 10), None);
        assert_eq!(index_range(-5.0, 20.0, 0.0, 1.0, 10), Some((0, 9)));
        assert_eq!(index_range(9.6, 20.0, 0.0, 1.0, 10), None);
    }

    #[test]
    fn barycentric_reproduces_the_point() {
        let l = [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(0.0, 3.0, 2.0),
        ];
        let b = barycentric_xz(&l, 0.5, 0.5).unwrap();
        let x = b[0] * l[0].x + b[1] * l[1].x + b[2] * l[2].x;
        let z = b[0] * l[0].z + b[1] * l[1].z + b[2] * l[2].z;
        assert!((x - 0.5).abs() < 1e-15 && (z - 0.5).abs() < 1e-15);
        assert!(barycentric_xz(&l, 1.5, 1.5).is_none());
    }
}
