//! Pulsed-wave spectral Doppler: the slow-time IQ of a sample gate in a
//! vessel (a [`SampleVolume`] plus stationary clutter and electronic
//! noise), the wall filter ([`HighPass`]) and one spectral line per
//! `line_interval` ([`Spectrum`]). Allocation-free after [`PwDoppler::new`].

use crate::error::DopplerError;
use crate::profile::Profile;
use crate::pw_config::PwConfig;
use crate::sample_volume::SampleVolume;
use crate::spectrum::Spectrum;
use crate::wall_filter::HighPass;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rustfft::num_complex::Complex;

/// Slow-time samples run before the first line, so the wall filter has
/// settled (its poles lie inside radius 0.95 for cut-offs ≥ prf/200:
/// 0.95^400 < 1e-8).
const WARM_UP: usize = 400;

/// A PW Doppler gate on one vessel.
pub struct PwDoppler {
    cfg: PwConfig,
    volume: SampleVolume,
    filter: Option<HighPass>,
    clutter: Complex<f64>,
    noise_sigma: f64,
    rng: ChaCha8Rng,
    ring: Vec<Complex<f32>>,
    head: usize,
    spectrum: Spectrum,
    time: f64,
}

impl std::fmt::Debug for PwDoppler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PwDoppler")
            .field("cfg", &self.cfg)
            .field("time", &self.time)
            .finish()
    }
}

impl PwDoppler {
    /// A gate centred on a lumen of radius `radius` (m) with `profile`,
    /// starting at time `t0` (s) with centreline velocity `v0` (m/s) for
    /// the warm-up. Validates `cfg` (prefix `doppler.pw`).
    pub fn new(
        cfg: &PwConfig,
        radius: f64,
        profile: Profile,
        t0: f64,
        v0: f64,
    ) -> Result<Self, DopplerError> {
        cfg.validate("doppler.pw")?;
        DopplerError::in_range(
            "doppler.pw",
            "radius",
            radius,
            2e-4,
            0.05,
            "lumen radius must be 0.2 to 50 mm",
        )?;
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        let volume = SampleVolume::new(
            cfg.scatterers,
            radius,
            profile,
            cfg.gate_length,
            cfg.beam_width,
            cfg.angle_deg.to_radians(),
            cfg.center_frequency,
            cfg.sound_speed,
            ChaCha8Rng::seed_from_u64(cfg.seed ^ 0x5eed_d099),
        );
        let p = volume.mean_power().max(1e-30);
        let clutter = Complex::from_polar(
            p.sqrt() * 10f64.powf(cfg.clutter_db / 20.0),
            rng.gen_range(0.0..std::f64::consts::TAU),
        );
        let n = cfg.fft_size;
        let mut pw = PwDoppler {
            cfg: *cfg,
            volume,
            filter: (cfg.wall_filter > 0.0).then(|| HighPass::new(cfg.wall_filter, cfg.prf)),
            clutter,
            noise_sigma: (p * 10f64.powf(cfg.noise_db / 10.0) / 2.0).sqrt(),
            rng,
            ring: vec![Complex::default(); n],
            head: 0,
            spectrum: Spectrum::new(n, cfg.prf),
            time: t0 - (WARM_UP + n) as f64 / cfg.prf,
        };
        for _ in 0..WARM_UP + n {
            pw.pulse(v0);
        }
        Ok(pw)
    }

    /// The settings.
    pub fn config(&self) -> &PwConfig {
        &self.cfg
    }

    /// Time (s) of the latest pulse.
    pub fn time(&self) -> f64 {
        self.time
    }

    fn pulse(&mut self, vc: f64) {
        let dt = 1.0 / self.cfg.prf;
        self.volume.advance(vc, dt);
        self.time += dt;
        let nr: f64 = self.rng.sample(StandardNormal);
        let ni: f64 = self.rng.sample(StandardNormal);
        let mut x = self.volume.echo() + self.clutter + Complex::new(nr, ni) * self.noise_sigma;
        if let Some(f) = &mut self.filter {
            x = f.step(x);
        }
        self.ring[self.head] = Complex::new(x.re as f32, x.im as f32);
        self.head = (self.head + 1) % self.ring.len();
    }

    /// Advances by one line interval (`hop` pulses), the centreline
    /// velocity (m/s, along the flow) given per pulse time by `velocity`,
    /// and computes the new spectral line. Allocates nothing.
    pub fn line(&mut self, mut velocity: impl FnMut(f64) -> f64) -> &Spectrum {
        for _ in 0..self.cfg.hop() {
            let v = velocity(self.time + 1.0 / self.cfg.prf);
            self.pulse(if v.is_finite() { v } else { 0.0 });
        }
        self.spectrum.compute(&self.ring, self.head);
        &self.spectrum
    }

    /// Expected total power of the electronic noise alone in a line (the
    /// sum over the `N` bins of `E|X_k|²/N = 2σ²` with the unit-power
    /// window; the wall filter takes off a negligible band): a line whose
    /// power is not well above it holds no detectable flow.
    pub fn noise_power(&self) -> f64 {
        self.cfg.fft_size as f64 * 2.0 * self.noise_sigma * self.noise_sigma
    }

    /// Whether the last line holds flow: its power at least 4 times (6 dB)
    /// the noise's expected power.
    pub fn has_signal(&self) -> bool {
        self.spectrum.total_power() > 4.0 * self.noise_power()
    }

    /// The last line.
    pub fn spectrum(&self) -> &Spectrum {
        &self.spectrum
    }
}
