//! Scatterers fixed in tissue (material) coordinates, binned by image column.
//!
//! Each column of the image (plus a halo of the lateral PSF's half-width in
//! columns on each side, so that the lateral PSF is complete at the edges, plus
//! `pan_range / Δx` columns on each side, where the image window can pan
//! to) owns scatterers at stratified random depths (see `generate`), sorted by
//! depth. A scatterer
//! carries a circular complex Gaussian amplitude whose power is the mean
//! backscatter of its tissue (dB relative to muscle), modulated along
//! connective-tissue lines: septa in the fat, perimysium in the muscle.
//! Its lateral position is its column's centre (the section deforms along
//! the depth only, so a column's scatterers stay in their column); its depth
//! is where the deformation acts. Same seed, same field.

use crate::anatomy::Anatomy;
use crate::config::ImagingConfig;
use crate::psf::PsfTables;
use crate::texture;
use crate::tissue::Tissue;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The binned scatterer field.
#[derive(Debug, Clone)]
pub(crate) struct ScattererField {
    /// Halo columns on each side of the image.
    pub halo: usize,
    /// Pan columns on each side of the halo: the window of the image at pan
    /// `p` columns (`|p| ≤ pan`) is bins `pan + p .. pan + p + columns + 2 halo`.
    pub pan: usize,
    /// `bin_start[b]..bin_start[b + 1]`: scatterers of bin `b` (image column
    /// `b − halo − pan` at zero pan).
    pub bin_start: Vec<u32>,
    /// Depth below the undeformed skin (m), increasing within a bin.
    pub depth: Vec<f32>,
    /// Complex amplitude `[re, im]`.
    pub amp: Vec<[f32; 2]>,
    /// Point targets on the image plane (elevation weight of the plane)
    /// rather than tissue (elevation weight of the slice).
    pub points: bool,
    /// A field in material coordinates ([`crate::material`]): each
    /// scatterer's elevation, Gaussian width and unweighted amplitude, so
    /// that the plane can move across the slice; `None` for a 2-D field.
    pub slab: Option<crate::material::Slab>,
}

/// Half-width of the specular lobe (rad): a smooth interface tilted by `θ`
/// sends its echo `2θ` off the beam's axis, and the receive aperture (F#
/// 1.7: half-angle ≈ 16°) collects it only for `2θ ≲ 16°` (Szabo 2014,
/// ch. 3, reflection at a specular interface).
pub(crate) const SPECULAR_LOBE: f64 = 8.0 * std::f64::consts::PI / 180.0;
/// Diffuse backscatter of the bone's surface relative to its specular echo
/// (amplitude, −26 dB): a smooth cortex seen edge-on is a little brighter
/// than muscle (+35 − 26 dB) over its thin attenuated layer.
const SPECULAR_FLOOR: f64 = 0.05;

/// Amplitude gain of a specular surface whose outward normal is `n`
/// (lateral, depth; any length): `floor + (1 − floor) exp(−θ²/(2 θ₀²))`,
/// `θ` the angle between `n` and the direction to the probe (−depth).
pub(crate) fn specular_gain(n: (f64, f64)) -> f64 {
    let len = n.0.hypot(n.1);
    if len == 0.0 {
        return 1.0;
    }
    let theta = (-n.1 / len).clamp(-1.0, 1.0).acos();
    SPECULAR_FLOOR + (1.0 - SPECULAR_FLOOR) * (-0.5 * (theta / SPECULAR_LOBE).powi(2)).exp()
}

/// A straight line of connective tissue in the section (tissue coordinates, m).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line {
    pub a: (f64, f64),
    pub b: (f64, f64),
    pub half_width: f64,
    pub gain: f64,
    /// The tissue it brightens (`None`: fat and muscle alike).
    pub only: Option<Tissue>,
}

impl Line {
    fn distance(&self, u: f64, d: f64) -> f64 {
        let (ex, ey) = (self.b.0 - self.a.0, self.b.1 - self.a.1);
        let len2 = ex * ex + ey * ey;
        let t = (((u - self.a.0) * ex + (d - self.a.1) * ey) / len2).clamp(0.0, 1.0);
        let (px, py) = (self.a.0 + t * ex - u, self.a.1 + t * ey - d);
        (px * px + py * py).sqrt()
    }
}

/// Random connective-tissue lines: `count` lines with centres in
/// `[u0, u1] × [d0, d1]`, lengths in `len`, tilts within `±tilt` (rad).
#[allow(clippy::too_many_arguments)]
pub(crate) fn lines(
    rng: &mut ChaCha8Rng,
    count: usize,
    (u0, u1): (f64, f64),
    (d0, d1): (f64, f64),
    len: (f64, f64),
    tilt: f64,
    half_width: f64,
    gain_db: f64,
) -> Vec<Line> {
    (0..count)
        .map(|_| {
            let c = (rng.gen_range(u0..u1), rng.gen_range(d0..d1));
            let l = 0.5 * rng.gen_range(len.0..len.1);
            let th: f64 = rng.gen_range(-tilt..tilt);
            let (dx, dy) = (l * th.cos(), l * th.sin());
            Line {
                a: (c.0 - dx, c.1 - dy),
                b: (c.0 + dx, c.1 + dy),
                half_width,
                gain: 10f64.powf(gain_db / 20.0),
                only: None,
            }
        })
        .collect()
}

/// Connective-tissue lines indexed by 1 mm × 1 mm cells for the distance
/// queries.
pub(crate) struct LineIndex {
    all: Vec<Line>,
    /// Lateral position of cell column 0 (m).
    u0: f64,
    cols: usize,
    rows: usize,
    cells: Vec<Vec<u32>>,
    /// Amplitude of muscle between the lines (the fascicle background of
    /// [`crate::texture`], 1 for the former texture).
    muscle_background: f64,
}

impl LineIndex {
    const CELL: f64 = 1e-3;

    /// The index of `all`, down to `deep` (m).
    pub fn new(all: Vec<Line>, deep: f64) -> Self {
        let c = Self::CELL;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for l in &all {
            lo = lo.min(l.a.0.min(l.b.0) - l.half_width);
            hi = hi.max(l.a.0.max(l.b.0) + l.half_width);
        }
        if all.is_empty() {
            (lo, hi) = (0.0, 0.0);
        }
        let cols = ((hi - lo) / c).ceil() as usize + 1;
        let rows = (deep / c).ceil() as usize + 1;
        let mut cells: Vec<Vec<u32>> = vec![Vec::new(); cols * rows];
        for (i, l) in all.iter().enumerate() {
            let d0 = ((l.a.1.min(l.b.1) - l.half_width).max(0.0) / c) as usize;
            let d1 = (((l.a.1.max(l.b.1) + l.half_width) / c) as usize).min(rows - 1);
            let u_0 = ((l.a.0.min(l.b.0) - l.half_width - lo) / c) as usize;
            let u_1 = (((l.a.0.max(l.b.0) + l.half_width - lo) / c) as usize).min(cols - 1);
            for r in d0..=d1 {
                for k in u_0..=u_1 {
                    cells[r * cols + k].push(i as u32);
                }
            }
        }
        LineIndex {
            all,
            u0: lo,
            cols,
            rows,
            cells,
            muscle_background: 1.0,
        }
    }

    /// The index with muscle's background amplitude set to `amplitude`.
    pub fn with_muscle_background(mut self, amplitude: f64) -> Self {
        self.muscle_background = amplitude;
        self
    }

    /// Amplitude gain at `(u, d)` in `tissue`: the largest of the lines
    /// through it, else 1; times the muscle's background in muscle.
    fn boost(&self, u: f64, d: f64, tissue: Tissue) -> f64 {
        let background = if tissue == Tissue::Muscle {
            self.muscle_background
        } else {
            1.0
        };
        background * self.line_gain(u, d, tissue)
    }

    /// The largest gain of the lines through `(u, d)` in `tissue`, else 1.
    fn line_gain(&self, u: f64, d: f64, tissue: Tissue) -> f64 {
        let k = (u - self.u0) / Self::CELL;
        if !(k >= 0.0 && (k as usize) < self.cols) || d < 0.0 {
            return 1.0;
        }
        let r = ((d / Self::CELL) as usize).min(self.rows - 1);
        self.cells[r * self.cols + k as usize]
            .iter()
            .map(|&i| &self.all[i as usize])
            .filter(|l| l.only.is_none_or(|t| t == tissue))
            .filter(|l| l.distance(u, d) < l.half_width)
            .map(|l| l.gain)
            .fold(1.0, f64::max)
    }
}

/// RMS amplitude of a tissue scatterer at `(u, d)` (m, tissue
/// coordinates): the tissue's mean backscatter, the bone's specular gain,
/// the connective-tissue lines of `lines` in fat and muscle, the diffuse
/// share of the tissues whose echo is a specular line
/// ([`crate::specular::diffuse_factor`]); `None` where nothing scatters
/// (blood, lumen).
pub(crate) fn tissue_amplitude(
    anatomy: &Anatomy,
    lines: &LineIndex,
    u: f64,
    d: f64,
) -> Option<f64> {
    let (tissue, vessel) = anatomy.classify(u, d);
    let db = anatomy.echo_of(tissue, vessel)?;
    let mut amp =
        10f64.powf(db / 20.0) * crate::specular::diffuse_factor(anatomy, tissue, vessel, u, d);
    if tissue == Tissue::Cortex {
        let (fu, fd) = anatomy.femur_centre();
        amp *= specular_gain((u - fu, d - fd));
    }
    if matches!(tissue, Tissue::Fat | Tissue::Muscle) {
        amp *= lines.boost(u, d, tissue);
    }
    Some(amp)
}

impl ScattererField {
    /// Lateral geometry of `cfg` with `halo` columns each side: (halo, pan,
    /// bins, centre of bin 0 in m, anatomy frame).
    pub(crate) fn bins(cfg: &ImagingConfig, halo: usize) -> (usize, usize, usize, f64) {
        let dx = cfg.pixel_width();
        let pan = cfg.pan_columns();
        let bins = cfg.columns + 2 * halo + 2 * pan;
        let u_first = -0.5 * cfg.width + (0.5 - halo as f64 - pan as f64) * dx;
        (halo, pan, bins, u_first)
    }

    /// Deepest populated tissue depth (m).
    pub(crate) fn max_depth(cfg: &ImagingConfig) -> f64 {
        cfg.depth + cfg.max_indentation + 1e-3
    }

    /// Fills every bin with `density` scatterers per m²; `amplitude(u, d)`
    /// gives each one's RMS amplitude (or `None` to drop it).
    fn generate(
        cfg: &ImagingConfig,
        halo: usize,
        density: f64,
        rng: &mut ChaCha8Rng,
        mut amplitude: impl FnMut(f64, f64) -> Option<f64>,
        mut sheets: impl FnMut(f64, &mut Vec<(f32, [f32; 2])>),
    ) -> Self {
        let (halo, pan, bins, u_first) = Self::bins(cfg, halo);
        let dx = cfg.pixel_width();
        let dmax = Self::max_depth(cfg);
        // Stratified depths: a column of mean count λ = ρ Δx d_max gets
        // ⌊λ⌋ or ⌈λ⌉ scatterers (the mean kept exact), one per stratum of
        // d_max / n at a uniform position within it. The sum under the PSF
        // then varies far less from cell to cell than with Poisson
        // positions, whose compound statistics would lower the speckle SNR
        // below the Rayleigh 1.91 unless ≳ 30 scatterers fill each cell;
        // sparse fields (≲ 1 per cell) stay sparse. A non-positive or
        // non-finite rate leaves the field empty.
        let lambda = density * dx * dmax;
        let lambda = if lambda.is_finite() && lambda > 0.0 {
            lambda
        } else {
            0.0
        };
        let mut bin_start = Vec::with_capacity(bins + 1);
        let mut depth = Vec::new();
        let mut amp = Vec::new();
        let mut col: Vec<(f32, [f32; 2])> = Vec::new();
        for b in 0..bins {
            bin_start.push(depth.len() as u32);
            let n = lambda.floor() as usize + usize::from(rng.gen::<f64>() < lambda.fract());
            col.clear();
            let uc = u_first + b as f64 * dx;
            for k in 0..n {
                let u = uc + dx * (rng.gen::<f64>() - 0.5);
                let d = dmax * (k as f64 + rng.gen::<f64>()) / n as f64;
                let re: f64 = rng.sample(StandardNormal);
                let im: f64 = rng.sample(StandardNormal);
                if let Some(a) = amplitude(u, d) {
                    let s = a * std::f64::consts::FRAC_1_SQRT_2;
                    col.push((d as f32, [(re * s) as f32, (im * s) as f32]));
                }
            }
            sheets(uc, &mut col);
            col.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
            for &(d, a) in &col {
                depth.push(d);
                amp.push(a);
            }
        }
        bin_start.push(depth.len() as u32);
        ScattererField {
            halo,
            pan,
            bin_start,
            depth,
            amp,
            points: false,
            slab: None,
        }
    }

    /// The connective-tissue lines of the 2-D section of `anatomy` drawn
    /// from `rng` with the textures of `cfg.texture`: the lines that
    /// brighten scatterers (with muscle's background amplitude) and the
    /// septa drawn as coherent sheets (empty unless `coherent_septa`).
    pub(crate) fn section_lines(
        cfg: &ImagingConfig,
        anatomy: &Anatomy,
        rng: &mut ChaCha8Rng,
    ) -> (LineIndex, Vec<Line>) {
        let a = anatomy.config();
        let tex = &cfg.texture;
        let half = 0.5 * cfg.width + cfg.pan_columns() as f64 * cfg.pixel_width() + 2e-3;
        let fat = (
            a.skin_thickness + 0.3e-3,
            a.skin_thickness + a.fat_thickness - 0.3e-3,
        );
        let muscle_top = a.skin_thickness + a.fat_thickness;
        let deep = Self::max_depth(cfg);
        let mut septa = texture::septa(
            rng,
            tex.coherent_septa,
            2.0 * half * a.fat_thickness,
            (-half, half),
            fat,
        );
        let mut peri = texture::perimysium(
            rng,
            tex.muscle_fascicles,
            2.0 * half * (deep - muscle_top).max(0.0),
            (-half, half),
            (muscle_top + 1e-3, deep),
        );
        let background = if tex.muscle_fascicles {
            texture::fascicle_amplitude()
        } else {
            // The former 2-D texture, unchanged: lines for fat and muscle alike.
            septa.iter_mut().for_each(|l| l.only = None);
            peri.iter_mut().for_each(|l| l.only = None);
            1.0
        };
        let sheets = if tex.coherent_septa {
            std::mem::take(&mut septa)
        } else {
            Vec::new()
        };
        septa.extend(peri);
        (
            LineIndex::new(septa, deep).with_muscle_background(background),
            sheets,
        )
    }

    /// The scatterers of `anatomy`, at the density of `cfg`, seeded by
    /// `cfg.seed`, with the textures of `cfg.texture` ([`crate::texture`]).
    pub fn from_anatomy(cfg: &ImagingConfig, tables: &PsfTables, anatomy: &Anatomy) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        let (index, sheets) = Self::section_lines(cfg, anatomy, &mut rng);
        let fat_db = anatomy.echo_of(Tissue::Fat, None).unwrap_or(0.0);
        let dz = cfg.pixel_depth();
        Self::generate(
            cfg,
            tables.lat_half,
            cfg.scatterer_density,
            &mut rng,
            |u, d| tissue_amplitude(anatomy, &index, u, d),
            |u, col| {
                for d in sheets.iter().filter_map(|l| texture::septum_depth(l, u)) {
                    if anatomy.classify(u, d).0 == Tissue::Fat {
                        let amp =
                            texture::septum_amplitude(tables, cfg.scatterer_density, fat_db, dz, d);
                        col.push((d as f32, [amp as f32, 0.0]));
                    }
                }
            },
        )
    }

    /// A homogeneous medium of `density` scatterers per m² with unit power.
    pub fn uniform(cfg: &ImagingConfig, halo: usize, density: f64, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Self::generate(cfg, halo, density, &mut rng, |_, _| Some(1.0), |_, _| {})
    }

    /// As [`uniform`](Self::uniform), without scatterers inside the circle
    /// of `radius` (m) about `(u, d)` (lateral, depth below the skin; m): an
    /// anechoic cylinder across the slice, as the cysts of tissue phantoms.
    pub fn cyst(
        cfg: &ImagingConfig,
        halo: usize,
        density: f64,
        seed: u64,
        centre: (f64, f64),
        radius: f64,
    ) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        Self::generate(
            cfg,
            halo,
            density,
            &mut rng,
            |u, d| ((u - centre.0).hypot(d - centre.1) > radius).then_some(1.0),
            |_, _| {},
        )
    }

    /// Unit point scatterers at `(column, depth)` (image column index at
    /// zero pan, depth in m).
    pub fn points(cfg: &ImagingConfig, halo: usize, points: &[(usize, f64)]) -> Self {
        let (halo, pan, bins, _) = Self::bins(cfg, halo);
        let mut sorted: Vec<(usize, f64)> =
            points.iter().map(|&(c, d)| (c + halo + pan, d)).collect();
        sorted.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut bin_start = Vec::with_capacity(bins + 1);
        let mut depth = Vec::new();
        let mut amp = Vec::new();
        let mut next = 0;
        for b in 0..bins {
            bin_start.push(depth.len() as u32);
            while next < sorted.len() && sorted[next].0 == b {
                depth.push(sorted[next].1 as f32);
                amp.push([1.0, 0.0]);
                next += 1;
            }
        }
        bin_start.push(depth.len() as u32);
        ScattererField {
            halo,
            pan,
            bin_start,
            depth,
            amp,
            points: true,
            slab: None,
        }
    }

    /// Number of scatterers.
    pub fn len(&self) -> usize {
        self.depth.len()
    }
}
