//! The B-mode renderer: scatterers → complex baseband PSF → envelope →
//! attenuation and TGC → log compression → 8-bit frame.
//!
//! A frame is four named stages over preallocated buffers (nothing is
//! allocated after construction on the serial path):
//! 1. [`prepare`](Renderer::prepare): probe face, per-column skin
//!    displacement, vessel pressures and lumen ratios, per-column warps;
//! 2. axial splat of each column's scatterers at their deformed depths;
//! 3. lateral convolution with the lateral PSF;
//! 4. per-column attenuation/TGC and log compression, then the transpose
//!    into the row-major output (row = depth).

use crate::anatomy::Anatomy;
use crate::anatomy_config::VeinState;
use crate::config::ImagingConfig;
use crate::deformation::SectionDeformation;
use crate::edge_shadow::EdgeShadows;
use crate::enhancement::LossBlur;
use crate::error::ImagingError;
use crate::lateral_map::{LateralMap, RemapScratch};
use crate::material::MaterialWindow;
use crate::psf::PsfTables;
use crate::reverberation::Reverberation;
use crate::scatterers::ScattererField;
use crate::smoke::{Smoke, SmokePhase, ROLL as SMOKE_ROLL};
use crate::specular::SpecularField;
use crate::stage_times::{wall_seconds, Lap, StageTimes};
use crate::stages::{
    column_loss, compress_column, convolve_frame, splat_add, splat_column, FrameGeometry,
    LogCompression,
};
use crate::warp::{WarpSet, MAX_VESSELS};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

mod fields;
mod lumens;
mod prepare;

use fields::{correlation_length, smoothed_gaussian, Additives, ExtraEchoes};
use lumens::VesselLumen;
pub use lumens::{Lumen, LumenReport};

/// What the application supplies each frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameInput<'a> {
    /// The deformation under the probe (from the physical model).
    pub deformation: &'a SectionDeformation,
    /// Mean normal stress under the probe face (Pa): contact force / face area.
    pub probe_pressure: f64,
    /// Time (s), for the arterial pulse.
    pub time: f64,
    /// Lateral position of the image centre in the anatomy's frame (m): the
    /// arc length along the skin from the vessels' reference line (the exam
    /// site) to the probe, along the image's lateral axis. 0 puts the
    /// anatomy as configured; `s` moves it by `−s` in the image. Quantized
    /// to the lateral pixel pitch and clamped to `±imaging.pan_range`
    /// ([`Renderer::pan`]).
    pub lateral_offset: f64,
}

/// A test medium without anatomy: attenuation equals the TGC's, no vessels.
#[derive(Debug, Clone, PartialEq)]
pub enum Phantom {
    /// Unit-power scatterers at `density` per m², seeded by `seed`.
    Uniform {
        /// Scatterers per m².
        density: f64,
        /// Generator seed.
        seed: u64,
    },
    /// Unit point scatterers at `(column index, depth below the skin in m)`.
    Points(Vec<(usize, f64)>),
    /// A uniform medium as [`Phantom::Uniform`] with an anechoic cylinder
    /// (across the slice) of `radius` (m) centred on the image's axis at
    /// `depth` (m).
    Cyst {
        /// Scatterers per m².
        density: f64,
        /// Generator seed.
        seed: u64,
        /// Depth of the centre below the skin (m).
        depth: f64,
        /// Radius (m).
        radius: f64,
    },
}

/// Lateral reach (m) beyond the beam's main lobe of the averaging of the
/// loss about each vessel margin ([`crate::enhancement`]): the lumen's
/// chord, hence its enhancement, changes fastest within ≈ 0.5 mm of its
/// lateral extreme (`h ∝ √(a² − x²)`).
const BLUR_MARGIN: f64 = 0.5e-3;

/// Columns of noise beyond the image's, over which the noise field rolls
/// from frame to frame.
const NOISE_ROLL: usize = 61;

/// Renders B-mode frames of one anatomy (or phantom) and vein state.
#[derive(Debug)]
pub struct Renderer {
    cfg: ImagingConfig,
    anatomy: Option<Anatomy>,
    field: ScattererField,
    /// Specular interfaces (empty for a phantom), binned as `field`.
    specular: SpecularField,
    /// This frame's refraction edge shadows.
    shadows: EdgeShadows,
    tables: Arc<PsfTables>,
    lc: LogCompression,
    /// Unit-power diffuse clutter, column-major like `iq`.
    clutter: Vec<[f32; 2]>,
    /// RMS clutter amplitude per row.
    clutter_amp: Vec<f32>,
    /// Unit-power electronic noise over `columns + NOISE_ROLL` columns.
    noise: Vec<[f32; 2]>,
    /// RMS noise amplitude.
    noise_amp: f32,
    /// Noise column offset of the current frame.
    noise_roll: usize,
    padded_rows: usize,
    pad: usize,
    /// Lateral centre of each window bin (m, image frame).
    bin_u: Vec<f64>,
    /// The current frame's pan, in columns (see [`Renderer::pan`]).
    pan_columns: isize,
    surface: Vec<f64>,
    warps: Vec<WarpSet>,
    rf: Vec<[f32; 2]>,
    iq: Vec<[f32; 2]>,
    gray: Vec<u8>,
    /// Round-trip loss exponents (Np) of every column, column-major.
    loss: Vec<f64>,
    /// One column's loss exponents as the beam sees them, for the compression.
    loss_scratch: Vec<f64>,
    /// The lateral averaging of the loss near the vessels' margins.
    blur: LossBlur,
    geometry: FrameGeometry,
    /// Factor on the studied vein's (vessel 0's) lumen height: its
    /// Valsalva distension (issue 17), 1 at rest.
    vein_distension: f64,
    /// Near-field and lumen reverberation (`None` for a phantom or when off).
    reverb: Option<Reverberation>,
    /// Slow-flow smoke in the studied vein (`None` unless switched on).
    smoke: Option<Smoke>,
    /// Muscle's mean echo amplitude per row at the scatterer density.
    muscle_amp: Vec<f32>,
    /// The vessels' lumens of the current frame (the first `lumen_count`).
    lumens: [VesselLumen; MAX_VESSELS],
    lumen_count: usize,
    /// The lateral maps of the current frame's widening lumens
    /// ([`crate::lateral_map`]; the first `map_count`).
    lateral_maps: [LateralMap; MAX_VESSELS],
    map_count: usize,
    /// Work memory of the lateral maps.
    remap_scratch: RemapScratch,
    /// The smoke's fields at the frame's time, `None` when the studied
    /// vein holds none (closed, thrombosed, or smoke off).
    smoke_phase: Option<SmokePhase>,
    /// The clock the stages are timed with (s).
    stage_clock: fn() -> f64,
    /// The last frame's stage times.
    times: StageTimes,
}

impl Renderer {
    /// A renderer of the thigh section of `cfg` with the vein in `state`
    /// (validates `cfg` with the prefix `imaging`).
    pub fn new(cfg: &ImagingConfig, state: VeinState) -> Result<Self, ImagingError> {
        cfg.validate("imaging")?;
        let anatomy = Anatomy::new(&cfg.anatomy, state)?;
        let tables = PsfTables::shared(cfg);
        let field = ScattererField::from_anatomy(cfg, &tables, &anatomy);
        Ok(Self::build(cfg, Some(anatomy), field, tables))
    }

    /// A renderer of the thigh section of `cfg` whose scatterers are fixed
    /// in the tissue's 3-D material coordinates around `window`
    /// ([`crate::material`]): moving the plane across the slice
    /// ([`Renderer::set_elevation`]) or building a renderer for the next
    /// window keeps the speckle of the same tissue. Errors as
    /// [`Renderer::new`], and name `window` when it is not finite or its
    /// margin is negative.
    pub fn in_tissue(
        cfg: &ImagingConfig,
        state: VeinState,
        window: MaterialWindow,
    ) -> Result<Self, ImagingError> {
        cfg.validate("imaging")?;
        for (field, v) in [
            ("window.lateral", window.lateral),
            ("window.elevation", window.elevation),
            ("window.margin", window.margin),
        ] {
            if !v.is_finite() {
                return Err(ImagingError::Input {
                    field,
                    reason: "must be finite",
                });
            }
        }
        if window.margin < 0.0 {
            return Err(ImagingError::Input {
                field: "window.margin",
                reason: "must be >= 0",
            });
        }
        let anatomy = Anatomy::new(&cfg.anatomy, state)?;
        let tables = PsfTables::shared(cfg);
        let field = ScattererField::in_tissue(cfg, &tables, &anatomy, window);
        Ok(Self::build(cfg, Some(anatomy), field, tables))
    }

    /// The material window of a renderer built by [`Renderer::in_tissue`].
    pub fn material_window(&self) -> Option<MaterialWindow> {
        self.field.slab.as_ref().map(|s| s.window)
    }

    /// Moves the image plane to material elevation `elevation` (m), within
    /// the window's margin: each scatterer is weighed by the slice at its
    /// distance from the plane. Errors for a 2-D field, a non-finite
    /// elevation or one beyond the margin (build a new renderer there).
    pub fn set_elevation(&mut self, elevation: f64) -> Result<(), ImagingError> {
        let Some(slab) = self.field.slab.as_mut() else {
            return Err(ImagingError::Input {
                field: "elevation",
                reason: "this renderer's scatterers are not in material coordinates",
            });
        };
        let offset = elevation - slab.window.elevation;
        // 1 nm of slack: an elevation clamped to the window's edge comes
        // back from `(e + m) − e` a rounding off `m`.
        if !offset.is_finite() || offset.abs() > slab.window.margin + 1e-9 {
            return Err(ImagingError::Input {
                field: "elevation",
                reason: "must lie within the material window's margin",
            });
        }
        if offset != slab.offset {
            slab.weigh(offset, &mut self.field.amp);
        }
        Ok(())
    }

    /// A renderer of a phantom (speckle and PSF measurements).
    pub fn phantom(cfg: &ImagingConfig, phantom: &Phantom) -> Result<Self, ImagingError> {
        cfg.validate("imaging")?;
        let tables = PsfTables::shared(cfg);
        let halo = tables.lat_half;
        let field = match phantom {
            Phantom::Uniform { density, seed } => {
                ImagingError::positive("phantom", "density", *density)?;
                ScattererField::uniform(cfg, halo, *density, *seed)
            }
            Phantom::Cyst {
                density,
                seed,
                depth,
                radius,
            } => {
                ImagingError::positive("phantom", "density", *density)?;
                ImagingError::positive("phantom", "depth", *depth)?;
                ImagingError::positive("phantom", "radius", *radius)?;
                ScattererField::cyst(cfg, halo, *density, *seed, (0.0, *depth), *radius)
            }
            Phantom::Points(p) => {
                if p.iter()
                    .any(|&(c, d)| c >= cfg.columns || !d.is_finite() || d < 0.0)
                {
                    return Err(ImagingError::Input {
                        field: "phantom.points",
                        reason: "columns must be < imaging.columns and depths finite and >= 0",
                    });
                }
                ScattererField::points(cfg, halo, p)
            }
        };
        Ok(Self::build(cfg, None, field, tables))
    }

    fn build(
        cfg: &ImagingConfig,
        anatomy: Option<Anatomy>,
        field: ScattererField,
        tables: Arc<PsfTables>,
    ) -> Self {
        let pad = tables.pad();
        let padded_rows = cfg.rows + 2 * pad;
        let bins = cfg.columns + 2 * field.halo;
        let dx = cfg.pixel_width();
        let bin_u = (0..bins)
            .map(|b| -0.5 * cfg.width + (b as f64 - field.halo as f64 + 0.5) * dx)
            .collect();
        let (_, _, field_bins, u_first) = ScattererField::bins(cfg, field.halo);
        let specular = match &anatomy {
            Some(a) => SpecularField::new(cfg, &tables, a, field_bins, u_first),
            None => SpecularField::new_empty(field_bins),
        };
        let blur = LossBlur::new(&tables, cfg.rows);
        let dr = cfg.dynamic_range as f32;
        let muscle = cfg.scatterer_density * tables.speckle_unit[tables.focus_row];
        let white = 10.0 * muscle.log10() + cfg.headroom;
        // Clutter and noise fields: circular Gaussian, unit power, smoothed
        // over [¼, ½, ¼] axially (the receive filter's band) and, for the
        // clutter (echoes through the beam), laterally too.
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ 0x005e_edc1_u64);
        let (cols, rows) = (cfg.columns, cfg.rows);
        let clutter = smoothed_gaussian(&mut rng, cols, rows, true);
        let noise = smoothed_gaussian(&mut rng, cols + NOISE_ROLL, rows, false);
        let clutter_amp = tables
            .speckle_unit
            .iter()
            .map(|&u| {
                (cfg.scatterer_density * u * 10f64.powf(cfg.beam.clutter_db / 10.0)).sqrt() as f32
            })
            .collect();
        let noise_amp = (muscle * 10f64.powf(cfg.beam.noise_db / 10.0)).sqrt() as f32;
        let muscle_amp = tables
            .speckle_unit
            .iter()
            .map(|&u| (cfg.scatterer_density * u).sqrt() as f32)
            .collect();
        // Fields of their own seeds: the clutter and noise stay as they were.
        let reverb = (anatomy.is_some() && cfg.reverberation.enabled)
            .then(|| Reverberation::new(&cfg.reverberation, cfg.seed ^ 0x0eeb_e4b0_u64));
        let smoke = (anatomy.is_some() && cfg.texture.smoke).then(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ 0x005e_0c0e_u64);
            Smoke::new(
                smoothed_gaussian(&mut rng, cols + SMOKE_ROLL, rows, true),
                cfg.texture.smoke_db,
                cfg.texture.smoke_decorrelation,
            )
        });
        let lc = LogCompression {
            a: 10.0 * std::f32::consts::LOG10_2 * 255.0 / dr,
            b: (cfg.dynamic_range - white) as f32 * 255.0 / dr,
            c: 255.0 / dr,
            f_mhz: cfg.center_frequency * 1e-6,
            tgc: cfg.tgc_attenuation,
        };
        Renderer {
            geometry: FrameGeometry {
                face: 0.0,
                bone: 1.0,
                dz: cfg.pixel_depth(),
                rows: cfg.rows,
                pad,
            },
            cfg: cfg.clone(),
            anatomy,
            specular,
            shadows: EdgeShadows::default(),
            tables,
            lc,
            clutter,
            clutter_amp,
            noise,
            noise_amp,
            noise_roll: 0,
            padded_rows,
            pad,
            bin_u,
            pan_columns: 0,
            surface: vec![0.0; bins],
            warps: vec![WarpSet::default(); bins],
            rf: vec![[0.0; 2]; bins * padded_rows],
            iq: vec![[0.0; 2]; cfg.columns * cfg.rows],
            gray: vec![0; cfg.columns * cfg.rows],
            loss: vec![0.0; cfg.columns * cfg.rows],
            loss_scratch: vec![0.0; cfg.rows],
            blur,
            field,
            vein_distension: 1.0,
            reverb,
            smoke,
            muscle_amp,
            lumens: [VesselLumen::default(); MAX_VESSELS],
            lumen_count: 0,
            lateral_maps: [LateralMap::default(); MAX_VESSELS],
            map_count: 0,
            remap_scratch: RemapScratch::new(bins, cfg.rows),
            smoke_phase: None,
            stage_clock: wall_seconds,
            times: StageTimes::default(),
        }
    }

    /// Times the stages of each frame with `clock` (s, any origin; the
    /// monotonic wall clock by default): e.g. the thread's CPU time in a
    /// benchmark. Nine reads a frame.
    pub fn set_stage_clock(&mut self, clock: fn() -> f64) {
        self.stage_clock = clock;
    }

    /// The time spent in each stage of the last frame (s).
    pub fn stage_times(&self) -> StageTimes {
        self.times
    }

    /// The configuration.
    pub fn config(&self) -> &ImagingConfig {
        &self.cfg
    }

    /// The anatomy (`None` for a phantom).
    pub fn anatomy(&self) -> Option<&Anatomy> {
        self.anatomy.as_ref()
    }

    /// Taps of the axial kernel each scatterer is splatted with (`2K`,
    /// [`crate::pulse::AxialTables`]).
    pub fn axial_taps(&self) -> usize {
        2 * self.tables.axial.half
    }

    /// Number of scatterers in the field.
    pub fn scatterer_count(&self) -> usize {
        self.field.len()
    }

    /// Frame size `(columns, rows)`; the output buffer holds `columns · rows` bytes.
    pub fn frame_size(&self) -> (usize, usize) {
        (self.cfg.columns, self.cfg.rows)
    }

    /// Lateral position (m) of the centre of image column `j` (image frame).
    pub fn column_lateral(&self, j: usize) -> f64 {
        self.bin_u[j + self.field.halo]
    }

    /// The pan applied for a lateral offset (m): quantized to whole columns
    /// and clamped to `±pan_range` (m, the anatomy's frame). Returns the pan
    /// in m and in columns.
    pub fn pan(&self, lateral_offset: f64) -> (f64, isize) {
        let dx = self.cfg.pixel_width();
        let max = self.field.pan as isize;
        let p = if lateral_offset.is_finite() {
            ((lateral_offset / dx)
                .round()
                .clamp(-(max as f64), max as f64)) as isize
        } else {
            0
        };
        (p as f64 * dx, p)
    }

    /// First field bin of the window at pan `p` columns.
    fn window_start(&self, p: isize) -> usize {
        (self.field.pan as isize + p) as usize
    }

    /// Renders one frame into `out` (`columns · rows` bytes, row-major, row
    /// 0 at the probe face) on the calling thread. Allocates nothing.
    pub fn render_into(&mut self, input: &FrameInput, out: &mut [u8]) -> Result<(), ImagingError> {
        self.check_out(out)?;
        let mut lap = Lap::start(self.stage_clock);
        self.prepare(input)?;
        self.times.prepare = lap.lap();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU has AVX2 and FMA (checked just above), the
            // only requirements of `stages_avx2`.
            unsafe { self.stages_avx2(out, &mut lap) };
            return Ok(());
        }
        self.stages::<false>(out, &mut lap);
        Ok(())
    }

    /// [`Renderer::stages`] compiled for AVX2 and FMA (8 floats per
    /// instruction, `floor`/`round` and the convolution's `mul_add` as single
    /// instructions): the same operations in the same order, hence the same
    /// floats (Rust contracts no other product and sum into an FMA).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn stages_avx2(&mut self, out: &mut [u8], lap: &mut Lap) {
        self.stages::<true>(out, lap);
    }

    /// Stages 2–4 of a frame after [`Renderer::prepare`]: splat, lateral
    /// convolution, compression and the transpose into `out`. `AVX2`: called
    /// from [`Renderer::stages_avx2`] (the splat's taps take AVX2
    /// instructions; the same floats). Each stage's time goes into
    /// `self.times` from `lap` (started before [`Renderer::prepare`]).
    #[inline(always)]
    fn stages<const AVX2: bool>(&mut self, out: &mut [u8], lap: &mut Lap) {
        let w0 = self.window_start(self.pan_columns);
        self.specular.prepare_frame(
            &self.tables,
            &self.geometry,
            self.cfg.pixel_width(),
            w0,
            &self.surface,
            &self.warps,
        );
        let (t, g, f, pr) = (&*self.tables, &self.geometry, &self.field, self.padded_rows);
        let sp = &self.specular;
        let elev = if f.points {
            &t.elev_point[..]
        } else {
            &t.elev_diffuse[..]
        };
        let prepared = lap.lap();
        for (b, col) in self.rf.chunks_mut(pr).enumerate() {
            let r = f.bin_start[w0 + b] as usize..f.bin_start[w0 + b + 1] as usize;
            splat_column::<AVX2>(
                t,
                g,
                elev,
                &f.depth[r.clone()],
                &f.amp[r],
                self.surface[b],
                &self.warps[b],
                col,
            );
            let r = sp.range(w0 + b);
            splat_add::<AVX2>(
                t,
                g,
                &t.elev_diffuse,
                &sp.depth[r.clone()],
                &sp.amp[r],
                self.surface[b],
                &self.warps[b],
                col,
            );
        }
        // The widening lumens move the splatted echo across columns.
        let (dz, dx, u_first) = (g.dz, self.cfg.pixel_width(), self.bin_u[0]);
        for m in &self.lateral_maps[..self.map_count] {
            let rows = self.cfg.rows;
            m.remap(
                &mut self.rf,
                pr,
                self.pad,
                rows,
                dz,
                u_first,
                dx,
                &mut self.remap_scratch,
            );
        }
        self.times.prepare += prepared; // the specular interfaces' depths
        self.times.splat = lap.lap();
        let rows = self.cfg.rows;
        convolve_frame::<AVX2>(t, &self.rf, pr, self.pad, rows, &mut self.iq);
        self.times.convolve = lap.lap();
        let h = f.halo;
        let pan_m = self.pan_columns as f64 * self.cfg.pixel_width();
        let adds = Additives {
            clutter: &self.clutter,
            clutter_amp: &self.clutter_amp,
            noise: &self.noise,
            noise_amp: self.noise_amp,
            roll: self.noise_roll,
            rows,
        };
        let echoes = ExtraEchoes {
            reverb: self.reverb.as_ref(),
            smoke: self.smoke.as_ref().zip(self.smoke_phase),
            lumens: &self.lumens[..self.lumen_count],
            muscle: &self.muscle_amp,
            pan: self.pan_columns as i64,
            fascia: self.anatomy.as_ref().map_or(0.0, |a| {
                let c = a.config();
                c.skin_thickness + c.fat_thickness + c.fascia_thickness
            }),
        };
        // Loss exponents of every column, then each column's as the beam
        // sees it near the vessels' margins (`crate::enhancement`), with
        // the edge shadows, and the compression.
        // A column crossing a widened lumen takes the loss of its source
        // column through the lumen's band (the map at full weight): the
        // enhancement below the lumen widens with it.
        let last = self.bin_u.len() - 1;
        for (j, x) in self.loss.chunks_mut(rows).enumerate() {
            let mut u = self.bin_u[j + h];
            for m in self.lateral_maps[..self.map_count].iter().rev() {
                u = m.source(u, 1.0);
            }
            let b = (((u - self.bin_u[0]) / dx).round().max(0.0) as usize).min(last);
            column_loss(
                &self.lc,
                g,
                self.anatomy.as_ref(),
                self.bin_u[b] + pan_m,
                self.surface[b],
                &self.warps[b],
                x,
            );
        }
        self.times.loss = lap.lap();
        for (j, iq) in self.iq.chunks_mut(rows).enumerate() {
            echoes.column(g, j, self.bin_u[j + h], self.surface[j + h], iq);
        }
        self.times.echoes = lap.lap();
        let dx = self.cfg.pixel_width();
        let reach = (self.blur.half + 1) as f64 * dx + BLUR_MARGIN;
        for (j, (col, iq)) in self
            .gray
            .chunks_mut(rows)
            .zip(self.iq.chunks(rows))
            .enumerate()
        {
            let u = self.bin_u[j + h];
            let near = self.shadows.near(u, reach);
            let shadow = self.shadows.column(u);
            let own = &self.loss[j * rows..(j + 1) * rows];
            let scratch = &mut self.loss_scratch;
            let x: &[f64] = if near.is_some() || !shadow.is_empty() {
                if let Some((distance, top)) = near {
                    let m = BLUR_MARGIN / dx;
                    let start = ((top / g.dz).max(0.0) as usize).min(rows);
                    self.blur
                        .column(&self.loss, rows, j, distance / dx, m, start, scratch);
                } else {
                    scratch.copy_from_slice(own);
                }
                if !shadow.is_empty() {
                    shadow.add_to(scratch, g.dz);
                }
                scratch
            } else {
                own
            };
            compress_column::<AVX2>(&self.lc, g, iq, &adds.column(j), x, col);
        }
        self.times.compress = lap.lap();
        let cols = self.cfg.columns;
        for (i, row) in out.chunks_mut(cols).enumerate() {
            for (j, px) in row.iter_mut().enumerate() {
                *px = self.gray[j * rows + i];
            }
        }
        self.times.transpose = lap.lap();
    }

    /// The speckle cell area (m²) the PSF predicts at image row `row`: the
    /// correlation area `∬ |R_h(Δx, Δz)|² / |R_h(0)|² dΔx dΔz` of the
    /// intensity of a circular Gaussian field blurred by the PSF `h`
    /// (`R_h` its autocorrelation; Wagner et al. 1983, eq. for `S_c`),
    /// separable into lateral and axial factors, summed at the pixel pitch.
    pub fn predicted_speckle_cell(&self, row: usize) -> f64 {
        let t = &self.tables;
        let row = row.min(self.cfg.rows - 1);
        let h = t.lat_half as i64;
        let lat: Vec<f64> = (-h..=h).map(|k| t.lateral_at(k, row) as f64).collect();
        let ax = &t.axial;
        let n = 2 * ax.half;
        let base = ax.knot(row as f64) * crate::pulse::AXIAL_SUBSTEPS * n;
        let axial: Vec<[f64; 2]> = ax.taps[base..base + n]
            .iter()
            .map(|p| [p[0] as f64, p[1] as f64])
            .collect();
        let lat_area = correlation_length(&lat.iter().map(|&v| [v, 0.0]).collect::<Vec<_>>());
        let ax_area = correlation_length(&axial);
        lat_area * self.cfg.pixel_width() * ax_area * self.cfg.pixel_depth()
    }

    /// Renders one frame into a new buffer (serial).
    pub fn render(&mut self, input: &FrameInput) -> Result<Vec<u8>, ImagingError> {
        let mut out = vec![0; self.cfg.columns * self.cfg.rows];
        self.render_into(input, &mut out)?;
        Ok(out)
    }

    /// Envelope `|IQ|` of the last frame at `(column, row)`, before
    /// attenuation, TGC and compression (PSF amplitude units: a unit point
    /// scatterer on a pixel centre gives 1).
    pub fn envelope(&self, column: usize, row: usize) -> f32 {
        let p = self.iq[column * self.cfg.rows + row];
        (p[0] * p[0] + p[1] * p[1]).sqrt()
    }

    /// Complex baseband echo `[I, Q]` of the last frame at `(column, row)`,
    /// before attenuation, TGC, clutter, noise and compression (PSF
    /// amplitude units, as [`Renderer::envelope`]).
    pub fn iq(&self, column: usize, row: usize) -> [f32; 2] {
        self.iq[column * self.cfg.rows + row]
    }

    /// The elevation slice's Gaussian width `σ` (m) at image row `row` (see
    /// [`crate::material`]): the intensity correlation of tissue speckle
    /// between planes `Δ` apart is `exp(−Δ²/(2σ²))`.
    pub fn slice_sigma(&self, row: usize) -> f64 {
        let t = &self.tables;
        t.slice_sigma[(row + t.pad()).min(t.slice_sigma.len() - 1)]
    }

    fn check_out(&self, out: &[u8]) -> Result<(), ImagingError> {
        if out.len() != self.cfg.columns * self.cfg.rows {
            return Err(ImagingError::Input {
                field: "out",
                reason: "must hold columns * rows bytes",
            });
        }
        Ok(())
    }
}

fn check_input(input: &FrameInput) -> Result<(), ImagingError> {
    input.deformation.validate()?;
    if !(input.probe_pressure.is_finite() && input.probe_pressure >= 0.0) {
        return Err(ImagingError::Input {
            field: "probe_pressure",
            reason: "must be finite and >= 0",
        });
    }
    if !input.time.is_finite() {
        return Err(ImagingError::Input {
            field: "time",
            reason: "must be finite",
        });
    }
    if !input.lateral_offset.is_finite() {
        return Err(ImagingError::Input {
            field: "lateral_offset",
            reason: "must be finite",
        });
    }
    Ok(())
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    /// The AVX2 stages (four taps per instruction) and the scalar fallback
    /// give the same echo floats (IQ), through warps, pan and both anatomy
    /// and phantom fields; the AVX2 compression's polynomial `exp` and
    /// `log₂` ([`crate::compress_avx2`]) leave every pixel within one gray
    /// level of libm's, on at most 10⁻³ of the pixels: a level moves by
    /// ≤ 10⁻⁴ (one f32 ulp of `log₂` times ≤ 12.8 gray per unit), so it
    /// rounds differently only within 10⁻⁴ of a half level, ≈ 2·10⁻⁴ of
    /// the pixels if levels spread evenly over a level's width; 5× that
    /// for the clustering of levels about a few values.
    #[test]
    fn avx2_and_scalar_stages_give_the_same_frame() {
        if !std::arch::is_x86_feature_detected!("avx2")
            || !std::arch::is_x86_feature_detected!("fma")
        {
            return;
        }
        let cfg = ImagingConfig {
            columns: 128,
            rows: 192,
            ..Default::default()
        };
        let mut leg = Renderer::new(&cfg, VeinState::Healthy).unwrap();
        let bone = leg.anatomy().unwrap().femur_top();
        let phantom = Phantom::Uniform {
            density: 1e8,
            seed: 3,
        };
        let mut speckle = Renderer::phantom(&cfg, &phantom).unwrap();
        let n = cfg.columns * cfg.rows;
        let (mut differ, mut total) = (0usize, 0usize);
        for r in [&mut leg, &mut speckle] {
            for (k, press) in [2e-3, 9e-3, 14e-3].into_iter().enumerate() {
                let d = SectionDeformation::flat_press(press, 0.04, 1.5e-3, bone).unwrap();
                let input = FrameInput {
                    deformation: &d,
                    probe_pressure: 1e4 * k as f64,
                    time: 0.2 * k as f64,
                    lateral_offset: 2e-3 * k as f64 - 2e-3,
                };
                let (mut a, mut b) = (vec![0u8; n], vec![0u8; n]);
                r.prepare(&input).unwrap();
                // SAFETY: the CPU has AVX2 (checked above).
                let mut lap = Lap::start(wall_seconds);
                unsafe { r.stages_avx2(&mut a, &mut lap) };
                let iq_a = r.iq.clone();
                r.prepare(&input).unwrap();
                r.stages::<false>(&mut b, &mut lap);
                assert!(
                    a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= 1),
                    "frames more than a level apart at press {press}"
                );
                differ += a.iter().zip(&b).filter(|(x, y)| x != y).count();
                total += n;
                assert!(
                    iq_a.iter()
                        .zip(&r.iq)
                        .all(|(x, y)| x[0].to_bits() == y[0].to_bits()
                            && x[1].to_bits() == y[1].to_bits()),
                    "IQ differs at press {press}"
                );
            }
        }
        eprintln!("AVX2 vs scalar frames: {differ} of {total} pixels differ");
        assert!(
            differ as f64 <= 1e-3 * total as f64,
            "{differ} of {total} pixels differ"
        );
    }
}
