//! The PW sample volume: red-cell scatterers moving along a straight
//! vessel through a gate, their echoes summed into slow-time IQ.
//!
//! Geometry (the vessel's frame): `x` along the flow, `h` across it in the
//! plane of the beam, `y` out of that plane; the lumen is the disc
//! `h² + y² < R²` and the gate sits on the vessel's axis. The unit vector
//! from the gate towards the transducer is `û = (cos θ, sin θ, 0)`, θ the
//! Doppler angle; the beam's lateral axis is `n̂ = (−sin θ, cos θ, 0)`.
//! A scatterer at `p` echoes `a · w(p) · exp(i 2k p·û)`, `k = 2π f₀/c`,
//! with the sample-volume weight
//! `w = exp(−(p·û)²/2σ_g² − ((p·n̂)² + y²)/2σ_b²)`,
//! σ = FWHM / 2.3548 of the gate length and the beam width. Moving at `v`
//! along `x`, the phase turns at `2k v cos θ`: the Doppler shift
//! `2 f₀ v cos θ / c`; crossing the beam at `v sin θ` it is weighted in and
//! out over the transit time, which broadens the spectrum by about
//! `v sin θ / beam width` (Newhouse et al., IEEE TBME 1980).
//!
//! Scatterers are uniform over the lumen's area within the beam's
//! elevation slab `|y| < min(R, 3.5 σ_b)` (outside it `w < e⁻⁶`) and over
//! `|x| < X`, the extent where `w` exceeds e⁻⁶ (3.5 σ both ways,
//! `X = 3.5 (σ_g |cos θ| + σ_b sin θ) + R`); one leaving that span
//! re-enters at the other end with a new radius, azimuth and amplitude
//! (a fresh cell). Amplitudes are circular complex Gaussian (Rayleigh
//! speckle of many cells per resolution cell).

use crate::profile::Profile;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rustfft::num_complex::Complex;

const FWHM_PER_SIGMA: f64 = 2.354_820_045;

#[derive(Debug, Clone, Copy, Default)]
struct Cell {
    x: f64,
    h: f64,
    y: f64,
    rho: f64,
    amp: Complex<f64>,
}

/// The scatterers in and around a PW gate (see the module docs).
#[derive(Debug, Clone)]
pub struct SampleVolume {
    cells: Vec<Cell>,
    radius: f64,
    half_span: f64,
    y_max: f64,
    u: (f64, f64),
    n: (f64, f64),
    two_k: f64,
    inv_2sg2: f64,
    inv_2sb2: f64,
    profile: Profile,
    rng: ChaCha8Rng,
}

fn cn(rng: &mut ChaCha8Rng) -> Complex<f64> {
    let re: f64 = rng.sample(StandardNormal);
    let im: f64 = rng.sample(StandardNormal);
    Complex::new(re, im) * std::f64::consts::FRAC_1_SQRT_2
}

impl SampleVolume {
    /// `count` scatterers in a lumen of radius `radius` (m) with `profile`,
    /// gate FWHM `gate` (m), beam FWHM `beam` (m), Doppler angle `theta`
    /// (rad), wavenumber from `f0` (Hz) and `c` (m/s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        count: usize,
        radius: f64,
        profile: Profile,
        gate: f64,
        beam: f64,
        theta: f64,
        f0: f64,
        c: f64,
        rng: ChaCha8Rng,
    ) -> SampleVolume {
        let (sg, sb) = (gate / FWHM_PER_SIGMA, beam / FWHM_PER_SIGMA);
        let half_span = 3.5 * (sg * theta.cos().abs() + sb * theta.sin().abs()) + radius;
        let mut sv = SampleVolume {
            cells: vec![Cell::default(); count],
            radius,
            half_span,
            y_max: (3.5 * sb).min(radius),
            u: (theta.cos(), theta.sin()),
            n: (-theta.sin(), theta.cos()),
            two_k: 2.0 * std::f64::consts::TAU * f0 / c,
            inv_2sg2: 1.0 / (2.0 * sg * sg),
            inv_2sb2: 1.0 / (2.0 * sb * sb),
            profile,
            rng,
        };
        for i in 0..count {
            let x = sv.rng.gen_range(-half_span..half_span);
            sv.cells[i] = sv.fresh(x);
        }
        sv
    }

    fn fresh(&mut self, x: f64) -> Cell {
        // Uniform over the lumen's disc within the slab |y| < y_max
        // (rejection sampling; the slab holds at least 2 y_max/(πR) of the
        // disc's area, so the loop ends quickly).
        let r = self.radius;
        let (h, y) = loop {
            let h = self.rng.gen_range(-r..r);
            let y = self.rng.gen_range(-self.y_max..self.y_max);
            if h * h + y * y < r * r {
                break (h, y);
            }
        };
        Cell {
            x,
            h,
            y,
            rho: (h * h + y * y).sqrt() / r,
            amp: cn(&mut self.rng),
        }
    }

    /// The summed echo at the current positions.
    pub fn echo(&self) -> Complex<f64> {
        let mut s = Complex::default();
        for c in &self.cells {
            let along = c.x * self.u.0 + c.h * self.u.1;
            let across = c.x * self.n.0 + c.h * self.n.1;
            let w = (-(along * along) * self.inv_2sg2
                - (across * across + c.y * c.y) * self.inv_2sb2)
                .exp();
            if w > 1e-6 {
                s += c.amp * w * Complex::from_polar(1.0, self.two_k * along);
            }
        }
        s
    }

    /// The expected echo power `Σ E|a|² w²` over the present cells
    /// (calibrates clutter and noise levels).
    pub fn mean_power(&self) -> f64 {
        self.cells
            .iter()
            .map(|c| {
                let along = c.x * self.u.0 + c.h * self.u.1;
                let across = c.x * self.n.0 + c.h * self.n.1;
                (-2.0
                    * (along * along * self.inv_2sg2
                        + (across * across + c.y * c.y) * self.inv_2sb2))
                    .exp()
            })
            .sum()
    }

    /// Moves every cell for `dt` (s) at centreline velocity `vc` (m/s,
    /// signed along `x`), recycling those that leave the span.
    pub fn advance(&mut self, vc: f64, dt: f64) {
        let span = self.half_span;
        for i in 0..self.cells.len() {
            let c = self.cells[i];
            let x = c.x + self.profile.velocity(vc, c.rho) * dt;
            self.cells[i] = if x > span {
                self.fresh(x - 2.0 * span)
            } else if x < -span {
                self.fresh(x + 2.0 * span)
            } else {
                Cell { x, ..c }
            };
        }
    }
}
