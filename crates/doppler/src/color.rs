//! Colour flow imaging over the B-mode frame.
//!
//! For each pixel of the colour box an ensemble of `M` slow-time samples
//! at the colour PRF is formed: the blood echo (a speckle amplitude per
//! pixel and frame, turning at the Doppler shift `2 f₀ v_ax / c` of the
//! scene's axial velocity there), the tissue echo (amplitude from the
//! B-mode grey, `clutter_db` above blood at full grey, turning at the
//! probe's own motion: the flash artefact) and electronic noise. The
//! order-1 regression wall filter removes stationary tissue; the lag-one
//! autocorrelation `R₁ = Σ x[m+1] x*[m]` gives the mean velocity
//! `v̂ = c · prf · arg R₁ / (4π f₀)` (Kasai et al., IEEE Trans Sonics
//! Ultrason 1985), which aliases beyond `±c·prf/(4 f₀)`, and `R₀ = Σ|x|²`
//! the power. A pixel is coloured where the power exceeds the noise by
//! `threshold_db − gain_db`, the B-mode grey is at most `priority`, and
//! `|v̂|` is at least `min_velocity` of Nyquist. Velocity mode: towards
//! the probe red, away blue (BART), brighter with speed; power mode: an
//! orange ramp of power.
//!
//! Speckle and noise come from tables drawn once (seeded), indexed by
//! pixel and frame: deterministic for a seed and allocation-free per frame.

use crate::color_config::ColorConfig;
use crate::error::DopplerError;
use crate::scene::FlowScene;
use crate::wall_filter::regression_filter;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rustfft::num_complex::Complex;

const TABLE: usize = 1 << 16;

/// What the colour encodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorMode {
    /// Mean velocity (direction and speed).
    #[default]
    Velocity,
    /// Power (amplitude of flow, no direction).
    Power,
}

/// The colour flow processor of one image geometry.
pub struct ColorFlow {
    cfg: ColorConfig,
    mode: ColorMode,
    columns: usize,
    rows: usize,
    col_lateral: Vec<f64>,
    row_depth: Vec<f64>,
    table: Vec<Complex<f32>>,
    ens: Vec<Complex<f32>>,
    noise_sigma: f32,
    frame: u64,
    /// Estimated velocity (m/s along the beam, towards the probe positive)
    /// per pixel of the last frame, NaN where no colour was shown.
    pub velocity: Vec<f32>,
}

impl std::fmt::Debug for ColorFlow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ColorFlow")
            .field("cfg", &self.cfg)
            .field("mode", &self.mode)
            .finish()
    }
}

impl ColorFlow {
    /// A processor for frames of `columns × rows` pixels whose column `j`
    /// is at lateral `col_lateral[j]` (m) and row `i` at depth
    /// `(i + ½) · pixel_depth` (m). Validates `cfg` (prefix `doppler.color`).
    pub fn new(
        cfg: &ColorConfig,
        mode: ColorMode,
        col_lateral: &[f64],
        rows: usize,
        pixel_depth: f64,
    ) -> Result<ColorFlow, DopplerError> {
        cfg.validate("doppler.color")?;
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        let table = (0..TABLE)
            .map(|_| {
                let re: f32 = rng.sample(StandardNormal);
                let im: f32 = rng.sample(StandardNormal);
                Complex::new(re, im) * std::f32::consts::FRAC_1_SQRT_2
            })
            .collect();
        Ok(ColorFlow {
            cfg: *cfg,
            mode,
            columns: col_lateral.len(),
            rows,
            col_lateral: col_lateral.to_vec(),
            row_depth: (0..rows).map(|i| (i as f64 + 0.5) * pixel_depth).collect(),
            table,
            ens: vec![Complex::default(); cfg.ensemble],
            noise_sigma: 10f32.powf(cfg.noise_db as f32 / 20.0),
            frame: 0,
            velocity: vec![f32::NAN; col_lateral.len() * rows],
        })
    }

    /// The settings.
    pub fn config(&self) -> &ColorConfig {
        &self.cfg
    }

    /// Sets the colour gain (dB).
    pub fn set_gain(&mut self, gain_db: f64) {
        self.cfg.gain_db = gain_db.clamp(-40.0, 40.0);
    }

    /// Pixels coloured in the last frame.
    pub fn colored(&self) -> usize {
        self.velocity.iter().filter(|v| !v.is_nan()).count()
    }

    /// Processes one frame: `bmode` (grey, `columns · rows`, row-major) and
    /// the `scene`, writing RGB (`3 · columns · rows`) into `rgb`: the grey
    /// frame with the colour overlay. Allocates nothing.
    pub fn frame(
        &mut self,
        bmode: &[u8],
        scene: &FlowScene,
        rgb: &mut [u8],
    ) -> Result<(), DopplerError> {
        let np = self.columns * self.rows;
        DopplerError::size("colour: RGB frame", 3 * np, rgb.len())?;
        let mode = self.mode;
        self.process(bmode, scene, |p, g, colour| {
            let px = colour.map_or([g, g, g], |c| ramp(mode, c));
            rgb[3 * p..3 * p + 3].copy_from_slice(&px);
        })
    }

    /// Processes one frame as [`ColorFlow::frame`] but writes, instead of
    /// RGB, one overlay code per pixel into `codes` (`columns · rows`): 0
    /// where no colour is shown, else [`code_of`] of the pixel's colour (the
    /// live viewer sends these, 1 byte a pixel and mostly zeros, and the
    /// page maps them with the same ramp, [`code_rgb`]). Allocates nothing.
    pub fn codes(
        &mut self,
        bmode: &[u8],
        scene: &FlowScene,
        codes: &mut [u8],
    ) -> Result<(), DopplerError> {
        let np = self.columns * self.rows;
        DopplerError::size("colour: overlay codes", np, codes.len())?;
        self.process(bmode, scene, |p, _, colour| {
            codes[p] = colour.map_or(0, code_of);
        })
    }

    /// The processing shared by [`ColorFlow::frame`] and
    /// [`ColorFlow::codes`]: `out(pixel, grey, colour)` for every pixel,
    /// `colour` `None` where none is shown.
    fn process(
        &mut self,
        bmode: &[u8],
        scene: &FlowScene,
        mut out: impl FnMut(usize, u8, Option<Colour>),
    ) -> Result<(), DopplerError> {
        let np = self.columns * self.rows;
        DopplerError::size("colour: B-mode frame", np, bmode.len())?;
        self.frame = self.frame.wrapping_add(1);
        let c = &self.cfg;
        let m = c.ensemble;
        let k_shift =
            (2.0 * c.center_frequency / c.sound_speed / c.prf) as f32 * std::f32::consts::TAU;
        let v_nyq = c.nyquist_velocity() as f32;
        let clutter_gain = 10f32.powf(c.clutter_db as f32 / 20.0) / 255.0;
        let noise_power = self.noise_sigma * self.noise_sigma;
        let power_min = noise_power * 10f32.powf((c.threshold_db - c.gain_db) as f32 / 10.0);
        let tissue_dphi = k_shift * scene.tissue_velocity as f32;
        let frame_off = (self.frame.wrapping_mul(0x9E37_79B9) % TABLE as u64) as usize;
        // Phasors advanced by one rotation per pulse (a complex multiply
        // instead of a sine and cosine per sample). The tissue's rotation
        // is the frame's, and that of a pixel without blood (v = 0) too:
        // computed once, not per pixel.
        let rot_t = Complex::from_polar(1.0, tissue_dphi);
        let rot_still = Complex::from_polar(1.0, k_shift * 0.0);
        for (i, &depth) in self.row_depth.iter().enumerate() {
            for (j, &lat) in self.col_lateral.iter().enumerate() {
                let p = i * self.columns + j;
                let g = bmode[p];
                self.velocity[p] = f32::NAN;
                // Outside the box, or where the grey wins (priority): no
                // colour, whatever the ensemble would give.
                if lat < c.box_left
                    || lat > c.box_right
                    || depth < c.box_top
                    || depth > c.box_bottom
                    || g > c.priority
                {
                    out(p, g, None);
                    continue;
                }
                let (rot_b, blood) = match scene.blood_at(lat, depth) {
                    Some((v, rho)) => {
                        let v_ax = v.profile.velocity(v.axial_velocity, rho) as f32;
                        (Complex::from_polar(1.0, k_shift * v_ax), 1.0f32)
                    }
                    None => (rot_still, 0.0),
                };
                let base = (p.wrapping_mul(2_654_435_761) + frame_off) % TABLE;
                let a_blood = self.table[base] * blood;
                let a_tissue = self.table[(base + 7919) % TABLE] * (clutter_gain * g as f32);
                let (mut pb, mut pt) = (a_blood, a_tissue);
                for (k, e) in self.ens.iter_mut().enumerate() {
                    let n = self.table[(base + 31 + 97 * k) % TABLE] * self.noise_sigma;
                    *e = pb + pt + n;
                    pb *= rot_b;
                    pt *= rot_t;
                }
                regression_filter(&mut self.ens);
                let mut r0 = 0.0f32;
                let mut r1 = Complex::<f32>::default();
                for k in 0..m {
                    r0 += self.ens[k].norm_sqr();
                    if k + 1 < m {
                        r1 += self.ens[k + 1] * self.ens[k].conj();
                    }
                }
                let power = r0 / m as f32;
                let v = r1.arg() / std::f32::consts::PI * v_nyq;
                if power < power_min || v.abs() < c.min_velocity as f32 * v_nyq {
                    out(p, g, None);
                    continue;
                }
                self.velocity[p] = v;
                let colour = match self.mode {
                    ColorMode::Velocity => Colour::Velocity((v / v_nyq).clamp(-1.0, 1.0)),
                    ColorMode::Power => {
                        let db = 10.0 * (power / power_min).log10();
                        Colour::Power((db / 30.0).clamp(0.0, 1.0))
                    }
                };
                out(p, g, Some(colour));
            }
        }
        Ok(())
    }
}

/// A coloured pixel's value: velocity as a fraction of Nyquist (−1 to 1,
/// towards the probe positive), or power as a fraction (0 to 1) of the
/// 30 dB above the threshold the ramp spans.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Colour {
    /// Mean velocity over the Nyquist velocity.
    Velocity(f32),
    /// Power above the threshold, 0 to 1 over 30 dB.
    Power(f32),
}

/// The RGB of a coloured pixel. Velocity: towards the probe red, away blue
/// (BART), brighter with speed; power: an orange ramp. The same mode is
/// assumed as produced the colour.
fn ramp(_mode: ColorMode, c: Colour) -> [u8; 3] {
    match c {
        Colour::Velocity(f) => {
            let s = f.abs().min(1.0);
            let hi = (110.0 + 145.0 * s) as u8;
            let lo = (60.0 * s * s) as u8;
            if f > 0.0 {
                [hi, lo, 0]
            } else {
                [0, lo, hi]
            }
        }
        Colour::Power(s) => [
            (120.0 + 135.0 * s) as u8,
            (40.0 + 150.0 * s) as u8,
            (20.0 * s) as u8,
        ],
    }
}

/// The overlay code (1 to 255) of a coloured pixel: velocity
/// `128 + round(127 f)` (never 128: a coloured pixel has a sign), power
/// `1 + round(254 s)`. 0 is reserved for "no colour".
pub fn code_of(c: Colour) -> u8 {
    match c {
        Colour::Velocity(f) => {
            let k = 128 + (127.0 * f.clamp(-1.0, 1.0)).round() as i32;
            match k {
                128 if f >= 0.0 => 129,
                128 => 127,
                k => k.clamp(1, 255) as u8,
            }
        }
        Colour::Power(s) => 1 + (254.0 * s.clamp(0.0, 1.0)).round() as u8,
    }
}

/// The RGB of overlay code `code` in `mode` (`None` for 0): the ramp of
/// [`ColorFlow::frame`] at the code's value, which the page reproduces.
pub fn code_rgb(mode: ColorMode, code: u8) -> Option<[u8; 3]> {
    if code == 0 {
        return None;
    }
    let c = match mode {
        ColorMode::Velocity => Colour::Velocity((code as f32 - 128.0) / 127.0),
        ColorMode::Power => Colour::Power((code as f32 - 1.0) / 254.0),
    };
    Some(ramp(mode, c))
}
