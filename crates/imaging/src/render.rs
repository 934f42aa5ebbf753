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

use crate::anatomy::{Anatomy, Vessel};
use crate::anatomy_config::VeinState;
use crate::config::ImagingConfig;
use crate::deformation::{column_depth, SectionDeformation};
use crate::error::ImagingError;
use crate::pressure::stress_under_rectangle;
use crate::psf::PsfTables;
use crate::scatterers::ScattererField;
use crate::stages::{
    compress_column, convolve_column, splat_column, FrameGeometry, LogCompression,
};
use crate::warp::{compensated_ratio, VesselWarp};

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

/// The state of one vessel's lumen in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lumen {
    /// Lumen area (m²).
    pub area: f64,
    /// Lumen area at rest (m²).
    pub rest_area: f64,
    /// Tissue pressure at the vessel (Pa), from the probe pressure.
    pub tissue_pressure: f64,
    /// Lateral position of the centre (m, image frame).
    pub lateral: f64,
    /// Depth of the deformed lumen's centre below the probe face (m).
    pub depth: f64,
    /// Half-height of the deformed lumen (m).
    pub half_height: f64,
    /// Half-width of the lumen (m).
    pub half_width: f64,
}

/// Vein and artery lumens of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumenReport {
    /// The femoral vein.
    pub vein: Lumen,
    /// The femoral artery.
    pub artery: Lumen,
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
}

/// Renders B-mode frames of one anatomy (or phantom) and vein state.
#[derive(Debug)]
pub struct Renderer {
    cfg: ImagingConfig,
    anatomy: Option<Anatomy>,
    field: ScattererField,
    tables: PsfTables,
    lc: LogCompression,
    padded_rows: usize,
    pad: usize,
    /// Lateral centre of each window bin (m, image frame).
    bin_u: Vec<f64>,
    /// The current frame's pan, in columns (see [`Renderer::pan`]).
    pan_columns: isize,
    surface: Vec<f64>,
    warps: Vec<[VesselWarp; 2]>,
    rf: Vec<[f32; 2]>,
    iq: Vec<[f32; 2]>,
    gray: Vec<u8>,
    geometry: FrameGeometry,
}

impl Renderer {
    /// A renderer of the thigh section of `cfg` with the vein in `state`
    /// (validates `cfg` with the prefix `imaging`).
    pub fn new(cfg: &ImagingConfig, state: VeinState) -> Result<Self, ImagingError> {
        cfg.validate("imaging")?;
        let anatomy = Anatomy::new(&cfg.anatomy, state)?;
        let field = ScattererField::from_anatomy(cfg, &anatomy);
        Ok(Self::build(cfg, Some(anatomy), field))
    }

    /// A renderer of a phantom (speckle and PSF measurements).
    pub fn phantom(cfg: &ImagingConfig, phantom: &Phantom) -> Result<Self, ImagingError> {
        cfg.validate("imaging")?;
        let field = match phantom {
            Phantom::Uniform { density, seed } => {
                ImagingError::positive("phantom", "density", *density)?;
                ScattererField::uniform(cfg, *density, *seed)
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
                ScattererField::points(cfg, p)
            }
        };
        Ok(Self::build(cfg, None, field))
    }

    fn build(cfg: &ImagingConfig, anatomy: Option<Anatomy>, field: ScattererField) -> Self {
        let tables = PsfTables::new(cfg);
        let pad = 2 * tables.axial_half;
        let padded_rows = cfg.rows + 2 * pad;
        let bins = cfg.columns + 2 * field.halo;
        let dx = cfg.pixel_width();
        let bin_u = (0..bins)
            .map(|b| -0.5 * cfg.width + (b as f64 - field.halo as f64 + 0.5) * dx)
            .collect();
        let dr = cfg.dynamic_range as f32;
        let white = 10.0 * tables.muscle_intensity.log10() + cfg.headroom;
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
            tables,
            lc,
            padded_rows,
            pad,
            bin_u,
            pan_columns: 0,
            surface: vec![0.0; bins],
            warps: vec![[VesselWarp::default(); 2]; bins],
            rf: vec![[0.0; 2]; bins * padded_rows],
            iq: vec![[0.0; 2]; cfg.columns * cfg.rows],
            gray: vec![0; cfg.columns * cfg.rows],
            field,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &ImagingConfig {
        &self.cfg
    }

    /// The anatomy (`None` for a phantom).
    pub fn anatomy(&self) -> Option<&Anatomy> {
        self.anatomy.as_ref()
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

    fn lumen_of(
        &self,
        v: &Vessel,
        input: &FrameInput,
        face: f64,
        ratio_of: impl Fn(f64) -> f64,
    ) -> Lumen {
        let def = input.deformation;
        // The vessel in the image's frame.
        let lateral = v.lateral - self.pan(input.lateral_offset).0;
        let s = def.surface_at(lateral);
        let centre = column_depth(s, def.bone_depth, v.depth) - face;
        let p = stress_under_rectangle(
            input.probe_pressure.max(0.0),
            self.cfg.probe_width,
            self.cfg.probe_elevation,
            lateral,
            0.0,
            centre.max(0.0),
        );
        let ratio = ratio_of(p);
        let warp = VesselWarp::new(v, v.lateral, compensated_ratio(ratio, s, def.bone_depth));
        let top = column_depth(s, def.bone_depth, warp.apply(v.depth - v.radius)) - face;
        let bottom = column_depth(s, def.bone_depth, v.depth + v.radius) - face;
        Lumen {
            area: ratio * v.rest_area(),
            rest_area: v.rest_area(),
            tissue_pressure: p,
            lateral,
            depth: 0.5 * (top + bottom),
            half_height: 0.5 * (bottom - top),
            half_width: v.radius,
        }
    }

    /// The vein's and artery's lumens for `input` (`None` for a phantom).
    /// Lumen areas follow [`Anatomy::vein_lumen_area`] and
    /// [`Anatomy::artery_lumen_area`] at the tissue pressure that reaches
    /// each vessel's centre ([`crate::pressure`]).
    pub fn lumens(&self, input: &FrameInput) -> Result<Option<LumenReport>, ImagingError> {
        check_input(input)?;
        let Some(a) = &self.anatomy else {
            return Ok(None);
        };
        let face = input.deformation.face_depth(0.5 * self.cfg.width);
        Ok(Some(LumenReport {
            vein: self.lumen_of(a.vein(), input, face, |p| a.vein_lumen_ratio(p)),
            artery: self.lumen_of(a.artery(), input, face, |p| {
                a.artery_lumen_ratio(p, input.time)
            }),
        }))
    }

    /// Stage 1: frame geometry, per-column skin displacement and warps.
    fn prepare(&mut self, input: &FrameInput) -> Result<(), ImagingError> {
        let def = input.deformation;
        let face = def.face_depth(0.5 * self.cfg.width);
        self.geometry.face = face;
        self.geometry.bone = def.bone_depth;
        let (pan_m, pan) = self.pan(input.lateral_offset);
        self.pan_columns = pan;
        let ratios = self.lumens(input)?.map(|r| {
            (
                r.vein.area / r.vein.rest_area,
                r.artery.area / r.artery.rest_area,
            )
        });
        for (b, &u_image) in self.bin_u.iter().enumerate() {
            let s = def.surface_at(u_image);
            self.surface[b] = s;
            let u = u_image + pan_m;
            self.warps[b] = match (ratios, &self.anatomy) {
                (Some((rv, ra)), Some(a)) => [
                    VesselWarp::new(a.vein(), u, compensated_ratio(rv, s, def.bone_depth)),
                    VesselWarp::new(a.artery(), u, compensated_ratio(ra, s, def.bone_depth)),
                ],
                _ => [VesselWarp::default(); 2],
            };
        }
        Ok(())
    }

    /// Renders one frame into `out` (`columns · rows` bytes, row-major, row
    /// 0 at the probe face) on the calling thread. Allocates nothing.
    pub fn render_into(&mut self, input: &FrameInput, out: &mut [u8]) -> Result<(), ImagingError> {
        self.check_out(out)?;
        self.prepare(input)?;
        let (t, g, f, pr) = (&self.tables, &self.geometry, &self.field, self.padded_rows);
        let w0 = self.window_start(self.pan_columns);
        for (b, col) in self.rf.chunks_mut(pr).enumerate() {
            let r = f.bin_start[w0 + b] as usize..f.bin_start[w0 + b + 1] as usize;
            splat_column(
                t,
                g,
                &f.depth[r.clone()],
                &f.amp[r],
                self.surface[b],
                &self.warps[b],
                col,
            );
        }
        let rows = self.cfg.rows;
        for (j, col) in self.iq.chunks_mut(rows).enumerate() {
            convolve_column(t, &self.rf, pr, self.pad, j, col);
        }
        let h = f.halo;
        let pan_m = self.pan_columns as f64 * self.cfg.pixel_width();
        for (j, (col, iq)) in self
            .gray
            .chunks_mut(rows)
            .zip(self.iq.chunks(rows))
            .enumerate()
        {
            let b = j + h;
            compress_column(
                &self.lc,
                g,
                self.anatomy.as_ref(),
                self.bin_u[b] + pan_m,
                self.surface[b],
                &self.warps[b],
                iq,
                col,
            );
        }
        let cols = self.cfg.columns;
        for (i, row) in out.chunks_mut(cols).enumerate() {
            for (j, px) in row.iter_mut().enumerate() {
                *px = self.gray[j * rows + i];
            }
        }
        Ok(())
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
