//! Slow-flow "smoke" in the studied vein (issue 21, an option:
//! [`crate::TextureConfig::smoke`]).
//!
//! At low shear rates red cells aggregate and blood's echo rises (Yuan &
//! Shung 1988, "Ultrasonic backscatter from flowing whole blood", JASA
//! 84(1)), from the ≈ −50 dB re muscle of flowing blood in this model to
//! the swirling "smoke" of slowly flowing veins, taken at −30 to −40 dB
//! (no published level was found; −32 dB by default). The smoke is a unit-power complex speckle at
//! [`crate::TextureConfig::smoke_db`] re muscle's mean echo at each depth,
//! added to the echo before the attenuation inside the patent lumen of the
//! studied vein. The flow runs along the vein, across the image plane: the
//! cells in the slice are replaced rather than moved, so the speckle
//! decorrelates in time. At time `t` the smoke is
//! `cos(πf/2) F_k + sin(πf/2) F_{k+1}`, `k = ⌊t/τ⌋`, `f = t/τ − k`, `τ`
//! [`crate::TextureConfig::smoke_decorrelation`], `F_k` the field read
//! [`STEP`]` · k` columns further along a wider precomputed field: unit
//! power at every `t` (the two fields are independent), continuous in `t`,
//! uncorrelated after `τ`. A lumen thinner than [`MIN_HEIGHT`] (closed)
//! holds none.

/// Columns of field beyond the image's over which the smoke is read.
pub const ROLL: usize = 127;
/// Columns between the fields of successive decorrelation times (more than
/// the smoothing's 3 columns, so that they are independent).
pub const STEP: usize = 23;
/// Inset of the smoke from the lumen's walls (m): the axial FWHM, so that
/// it does not blur into them.
pub const INSET: f64 = 0.2e-3;
/// Lumen height below which the vein is closed: no smoke (m).
pub const MIN_HEIGHT: f64 = 2.0 * INSET + 0.1e-3;

/// The smoke of a renderer.
#[derive(Debug, Clone)]
pub(crate) struct Smoke {
    /// Unit-power speckle over `columns + ROLL` columns, column-major.
    field: Vec<[f32; 2]>,
    /// Decorrelation time (s).
    tau: f64,
    /// Amplitude relative to muscle's mean echo.
    gain: f32,
}

/// The two fields' column offsets and weights at time `t` (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SmokePhase {
    offsets: [usize; 2],
    weights: [f32; 2],
}

impl Smoke {
    /// The smoke at `level_db` re muscle decorrelating over `tau` (s), on
    /// the unit speckle `field` (`(columns + ROLL) · rows`).
    pub fn new(field: Vec<[f32; 2]>, level_db: f64, tau: f64) -> Self {
        Smoke {
            field,
            tau,
            gain: 10f64.powf(level_db / 20.0) as f32,
        }
    }

    /// The fields and their weights at time `t` (s).
    pub fn phase(&self, t: f64) -> SmokePhase {
        let x = t / self.tau;
        let k = x.floor();
        let f = x - k;
        let k = k.rem_euclid(ROLL as f64) as usize;
        let a = std::f64::consts::FRAC_PI_2 * f;
        SmokePhase {
            offsets: [(k * STEP) % ROLL, ((k + 1) * STEP) % ROLL],
            weights: [a.cos() as f32, a.sin() as f32],
        }
    }

    /// Adds the smoke of column `column` at `phase` inside the lumen
    /// `top..bottom` (image depths, m) to its echo `iq` (before the
    /// attenuation), `muscle[i]` muscle's mean echo per row.
    pub fn add(
        &self,
        iq: &mut [[f32; 2]],
        column: usize,
        phase: SmokePhase,
        dz: f64,
        muscle: &[f32],
        (top, bottom): (f64, f64),
    ) {
        if bottom - top < MIN_HEIGHT {
            return;
        }
        let rows = iq.len();
        let row = |z: f64| ((z / dz - 0.5).ceil().max(0.0) as usize).min(rows);
        let (a, b) = (row(top + INSET), row(bottom - INSET));
        let f0 = &self.field[(column + phase.offsets[0]) * rows..][..rows];
        let f1 = &self.field[(column + phase.offsets[1]) * rows..][..rows];
        let [w0, w1] = phase.weights;
        for i in a..b {
            let k = self.gain * muscle[i];
            iq[i][0] += k * (w0 * f0[i][0] + w1 * f1[i][0]);
            iq[i][1] += k * (w0 * f0[i][1] + w1 * f1[i][1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn successive_fields_differ_and_keep_unit_power() {
        let s = Smoke::new(vec![[0.0; 2]; ROLL], -35.0, 0.05);
        for t in [0.0, 0.012, 0.05, 0.3, -0.07, 1e3] {
            let p = s.phase(t);
            assert_ne!(p.offsets[0], p.offsets[1]);
            let d = (p.offsets[0] as i64 - p.offsets[1] as i64).unsigned_abs() as usize;
            assert!(d.min(ROLL - d) >= 3, "fields {d} columns apart");
            let power = p.weights[0].powi(2) + p.weights[1].powi(2);
            assert!((power - 1.0).abs() < 1e-6);
        }
        // Continuous across a decorrelation time.
        let (a, b) = (s.phase(0.05 - 1e-9), s.phase(0.05));
        assert_eq!(a.offsets[1], b.offsets[0]);
        assert!((a.weights[1] - b.weights[0]).abs() < 1e-4);
    }
}
