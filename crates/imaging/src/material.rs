//! Scatterers fixed in the tissue's 3-D material coordinates (issue 12:
//! speckle continuous as the probe slides along the leg).
//!
//! The 2-D field of [`crate::scatterers`] stands for the whole elevation
//! slice at once (its weight `√∫w² dy`, `w` the two-way elevation weight),
//! so it cannot tell one slice from the next. Here each scatterer also has
//! an elevation `y` (m) in the tissue, and the plane at elevation `e` weighs
//! it by `w(y − e)`, the slice modelled as a Gaussian
//! `w(y) = w(0) e^{−y²/(2σ²)}` with the beam's own `w(0)` and `∫w² dy` at the
//! scatterer's depth (`σ` from [`crate::psf::PsfTables::slice_sigma`]). The
//! intensity correlation of the speckle between planes `Δ` apart is then
//! `exp(−Δ²/(2σ²))` (the squared field correlation
//! `∫w(y)w(y−Δ)dy / ∫w² = e^{−Δ²/(4σ²)}` of a circular Gaussian field;
//! Wagner et al. 1983), which the tests check.
//!
//! **Material coordinates** (m): lateral `a` (on the leg, arc length around
//! it), depth `d` below the rest skin, elevation `y` (on the leg, `s`).
//! Space is cut into cells of one lateral pixel `Δx` by [`SLICE`] of
//! elevation; each cell draws its scatterers from its own seed
//! (`seed`, column, slice), so the same tissue holds the same scatterers
//! whatever window of it is built. Depths are stratified in
//! `q(d) = ∫₀^d dd'/σ(d')`: the density `K/σ(d)` keeps the number of
//! scatterers inside the `±H σ` slab ([`SLAB_SIGMAS`]) the same at every
//! depth, `2 H K = ρ` (the 2-D density), whether the slice is thin (focus)
//! or thick (near field). Amplitudes are scaled by `√(2H/√π)` so that the
//! mean power per unit area, `K/σ · σ√π · 2H/√π = ρ`, is the 2-D field's:
//! the image's brightness does not change.
//!
//! Connective-tissue lines (fat septa, perimysium) are sheets along the
//! elevation, drawn per 8 mm tile of `a` from the tile's own seed; the
//! septa, coherent sheets, are one scatterer per column of weight 1 in
//! every plane ([`crate::texture`]).

use crate::anatomy::Anatomy;
use crate::config::ImagingConfig;
use crate::psf::PsfTables;
use crate::scatterers::{tissue_amplitude, Line, LineIndex, ScattererField};
use crate::texture::{self, TextureConfig};
use crate::tissue::Tissue;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Elevation thickness of a material cell (m): a fraction of the thinnest
/// slice (`σ` ≈ 0.3 mm at the focus), so that cells do not show.
pub const SLICE: f64 = 0.25e-3;
/// Half-thickness of the slab kept around the plane, in `σ`: the power
/// left out, `erfc(H)`, is 4·10⁻⁴ at `H = 2.5`.
pub const SLAB_SIGMAS: f64 = 2.5;
/// Lateral width of a tile of connective-tissue lines (m): wider than half
/// the longest line (12 mm), so lines from the next tiles suffice.
const LINE_TILE: f64 = 8e-3;

/// Where the image plane lies in the tissue's material coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialWindow {
    /// Material lateral coordinate (m) of the image's centre line
    /// (quantized to the lateral pixel pitch).
    pub lateral: f64,
    /// Material elevation coordinate (m) of the plane.
    pub elevation: f64,
    /// Elevation travel (m) either side of `elevation` that
    /// [`crate::Renderer::set_elevation`] may move the plane without a new
    /// field.
    pub margin: f64,
}

/// The elevation data of a material field, parallel to its scatterers.
#[derive(Debug, Clone)]
pub(crate) struct Slab {
    /// The window the field was built for.
    pub window: MaterialWindow,
    /// Elevation of each scatterer relative to `window.elevation` (m).
    pub y: Vec<f32>,
    /// `1/(2σ²)` of each scatterer's slice (1/m²).
    pub inv_2s2: Vec<f32>,
    /// Amplitude of each scatterer before the elevation weight.
    pub base: Vec<[f32; 2]>,
    /// Current plane, relative to `window.elevation` (m).
    pub offset: f64,
}

impl Slab {
    /// Sets `amp` to the weights of the plane at `offset` (m, relative to
    /// the window's elevation).
    pub fn weigh(&mut self, offset: f64, amp: &mut [[f32; 2]]) {
        let e = offset as f32;
        for (((a, b), &y), &k) in amp
            .iter_mut()
            .zip(&self.base)
            .zip(&self.y)
            .zip(&self.inv_2s2)
        {
            let w = (-(y - e) * (y - e) * k).exp();
            *a = [b[0] * w, b[1] * w];
        }
        self.offset = offset;
    }
}

/// Thickness of a depth band of material cells (m): each band reaches only
/// the slices its own thickest slice needs.
const BAND: f64 = 4e-3;

/// A SplitMix64 stream (hand-written: the cells need millions of cheap,
/// independent, seekable streams, which a cryptographic generator's
/// per-stream set-up would make slow).
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// A 64-bit mix of a seed and two cell indices (SplitMix64 finalizer;
/// hand-written: three multiplies, no crate needed for a cell seed).
fn cell_seed(seed: u64, a: i64, b: i64, tag: u64) -> u64 {
    let mut z = seed
        ^ (a as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (b as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ tag.wrapping_mul(0x1656_67b1_9e37_79f9);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The material lines of the tiles that reach `[lo, hi]` (material lateral,
/// m), in the window's frame (lateral minus `origin`), down to `deep` (m),
/// with the textures of `tex` ([`crate::texture`]): septa (~1 per 12 mm²,
/// 3–12 mm) in fat only, perimysium in muscle only. Returns the index of
/// the lines that brighten scatterers and the septa drawn as coherent
/// sheets (empty unless `tex.coherent_septa`).
pub(crate) fn material_lines(
    seed: u64,
    tex: &TextureConfig,
    lo: f64,
    hi: f64,
    origin: f64,
    deep: f64,
) -> (LineIndex, Vec<Line>) {
    let t0 = (lo / LINE_TILE).floor() as i64 - 1;
    let t1 = (hi / LINE_TILE).floor() as i64 + 1;
    let (mut all, mut sheets) = (Vec::new(), Vec::new());
    for t in t0..=t1 {
        let mut rng = ChaCha8Rng::seed_from_u64(cell_seed(seed, t, 0, 2));
        let (u0, u1) = (
            t as f64 * LINE_TILE - origin,
            (t + 1) as f64 * LINE_TILE - origin,
        );
        let area = LINE_TILE * deep;
        let septa = texture::septa(&mut rng, tex.coherent_septa, area, (u0, u1), (0.0, deep));
        let peri = texture::perimysium(&mut rng, tex.muscle_fascicles, area, (u0, u1), (0.0, deep));
        if tex.coherent_septa {
            sheets.extend(septa);
        } else {
            all.extend(septa);
        }
        all.extend(peri);
    }
    let background = if tex.muscle_fascicles {
        texture::fascicle_amplitude()
    } else {
        1.0
    };
    (
        LineIndex::new(all, deep).with_muscle_background(background),
        sheets,
    )
}

impl ScattererField {
    /// The scatterers of `anatomy` (tissue classes in the window's frame)
    /// drawn from the material cells around `window` (see the module docs),
    /// weighted for the plane at `window.elevation`.
    pub fn in_tissue(
        cfg: &ImagingConfig,
        tables: &PsfTables,
        anatomy: &Anatomy,
        window: MaterialWindow,
    ) -> Self {
        let (halo, pan, bins, u_first) = Self::bins(cfg, tables.lat_half);
        let dx = cfg.pixel_width();
        let dz = cfg.pixel_depth();
        let dmax = Self::max_depth(cfg);
        let sig = &tables.slice_sigma;
        let pad = tables.pad() as f64;
        // σ at rest depth d: the splat row whose centre is d.
        let sigma_at =
            |d: f64| sig[((d / dz + pad - 0.5).round().max(0.0) as usize).min(sig.len() - 1)];
        // q(d) = ∫ dd/σ on the depth grid, and its inverse by bisection.
        let nq = (dmax / dz).ceil() as usize;
        let mut qtab = Vec::with_capacity(nq + 1);
        qtab.push(0.0);
        for i in 0..nq {
            let q = qtab[i] + dz / sigma_at((i as f64 + 0.5) * dz);
            qtab.push(q);
        }
        let depth_of = |q: f64| {
            let i = qtab.partition_point(|&v| v <= q).clamp(1, nq);
            let (a, b) = (qtab[i - 1], qtab[i]);
            ((i - 1) as f64 + (q - a) / (b - a)) * dz
        };
        let k_density = cfg.scatterer_density / (2.0 * SLAB_SIGMAS);
        let scale = (2.0 * SLAB_SIGMAS / std::f64::consts::PI.sqrt()).sqrt();
        let e = window.elevation;
        // Depth bands, each with the slices its thickest slice reaches.
        let n_bands = (dmax / BAND).ceil() as usize;
        let bands: Vec<(f64, f64, i64, i64)> = (0..n_bands)
            .map(|i| {
                let (d0, d1) = (i as f64 * BAND, ((i + 1) as f64 * BAND).min(dmax));
                let s_max = (0..=8)
                    .map(|t| sigma_at(d0 + (d1 - d0) * t as f64 / 8.0))
                    .fold(0.0f64, f64::max);
                let reach = SLAB_SIGMAS * s_max + window.margin;
                let q = |d: f64| {
                    let x = d / dz;
                    let i = (x.floor() as usize).min(nq - 1);
                    qtab[i] + (x - i as f64) * (qtab[i + 1] - qtab[i])
                };
                (
                    q(d0),
                    q(d1),
                    ((e - reach) / SLICE).floor() as i64,
                    ((e + reach) / SLICE).ceil() as i64,
                )
            })
            .collect();
        let m_origin = (window.lateral / dx).round() as i64;
        let origin = m_origin as f64 * dx;
        let m_first = m_origin - (halo + pan + cfg.columns / 2) as i64;
        let (lines, sheets) = material_lines(
            cfg.seed,
            &cfg.texture,
            origin + u_first - dx,
            origin + u_first + bins as f64 * dx,
            origin,
            dmax,
        );
        let fat_db = anatomy.echo_of(Tissue::Fat, None).unwrap_or(0.0);
        let mut bin_start = Vec::with_capacity(bins + 1);
        let (mut depth, mut amp) = (Vec::new(), Vec::new());
        let (mut ys, mut inv, mut base) = (Vec::new(), Vec::new(), Vec::new());
        let mut col: Vec<(f32, f32, f32, [f32; 2])> = Vec::new();
        for b in 0..bins {
            bin_start.push(depth.len() as u32);
            col.clear();
            let uc = u_first + b as f64 * dx;
            let m = m_first + b as i64;
            for (i, &(q0, q1, k0, k1)) in bands.iter().enumerate() {
                let lambda = k_density * dx * SLICE * (q1 - q0);
                for k in k0..=k1 {
                    let cell = cell_seed(cfg.seed, m, k, 16 + i as u64);
                    let mut rng = Mix(cell);
                    let n = lambda.floor() as usize + usize::from(rng.uniform() < lambda.fract());
                    for j in 0..n {
                        let q = q0 + (q1 - q0) * (j as f64 + rng.uniform()) / n as f64;
                        let y = (k as f64 + rng.uniform()) * SLICE - e;
                        let u = uc + dx * (rng.uniform() - 0.5);
                        let g = rng.next();
                        let d = depth_of(q);
                        let s = sigma_at(d);
                        if y.abs() > SLAB_SIGMAS * s + window.margin {
                            continue;
                        }
                        if let Some(a) = tissue_amplitude(anatomy, &lines, u, d) {
                            // The circular Gaussian amplitude from the
                            // scatterer's own draw (Box–Muller).
                            let mut own = Mix(g);
                            let r = (-2.0 * (1.0 - own.uniform()).ln()).sqrt();
                            let phi = std::f64::consts::TAU * own.uniform();
                            let c = a * scale * std::f64::consts::FRAC_1_SQRT_2 * r;
                            let k2 = 1.0 / (2.0 * s * s);
                            col.push((
                                d as f32,
                                y as f32,
                                k2 as f32,
                                [(c * phi.cos()) as f32, (c * phi.sin()) as f32],
                            ));
                        }
                    }
                }
            }
            // The septa's sheets: one coherent scatterer per column on each
            // septum, the same in every plane (a sheet along the elevation:
            // `1/(2σ²)` = 0, weight 1).
            for d in sheets.iter().filter_map(|l| texture::septum_depth(l, uc)) {
                if d > 0.0 && anatomy.classify(uc, d).0 == Tissue::Fat {
                    let s = texture::septum_amplitude(tables, cfg.scatterer_density, fat_db, dz, d);
                    col.push((d as f32, 0.0, 0.0, [s as f32, 0.0]));
                }
            }
            col.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
            for &(d, y, k2, a) in &col {
                depth.push(d);
                ys.push(y);
                inv.push(k2);
                base.push(a);
                amp.push([0.0, 0.0]);
            }
        }
        bin_start.push(depth.len() as u32);
        let mut slab = Slab {
            window: MaterialWindow {
                lateral: origin,
                ..window
            },
            y: ys,
            inv_2s2: inv,
            base,
            offset: 0.0,
        };
        slab.weigh(0.0, &mut amp);
        ScattererField {
            halo,
            pan,
            bin_start,
            depth,
            amp,
            points: false,
            slab: Some(slab),
        }
    }
}

#[cfg(test)]
#[path = "material_tests.rs"]
mod tests;
