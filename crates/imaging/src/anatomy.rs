//! The transverse section of the mid-thigh in tissue (material) coordinates —
//! `u` lateral (m, from the probe's centre, negative medial) and depth below
//! the undeformed skin (m) — and the lumen laws of the femoral vessels.
//!
//! Lumen laws (beyond the paper, DESIGN.md §5): a vessel's lumen is flattened
//! vertically by the factor `c` (its area is `c` times the rest area). For
//! the vein, `c = 1 − (1 − c_min) S(t)` with `S(t) = 3t² − 2t³` and
//! `t = (p − p_onset)/(p_full − p_onset)` clamped to [0, 1], where `p` is the
//! tissue pressure at the vein (see [`crate::pressure`]): a smooth version of
//! the collapsible-tube law (Shapiro 1977), closed above `p_full` when
//! healthy (`c_min = 0`). The artery uses the same law with its own,
//! higher thresholds (the arterial pressure holds it open), times the pulse
//! `1 + ε P(t)`, with `P(t) = (φ/τ) e^{1 − φ/τ}`, `φ` the phase of the heart
//! cycle and `τ` = 0.12 (a fast systolic upstroke, a slow diastolic decay).

use crate::anatomy_config::{AnatomyConfig, VeinState, VeinStateParams};
use crate::error::ImagingError;
use crate::tissue::Tissue;
use std::f64::consts::PI;

/// Largest number of breakpoints [`Anatomy::column_breakpoints`] returns.
pub const MAX_BREAKPOINTS: usize = 16;

/// Time to the systolic peak as a fraction of the heart cycle.
const PULSE_PEAK: f64 = 0.12;

/// A circular vessel at rest, in tissue coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vessel {
    /// Lateral position of the centre (m).
    pub lateral: f64,
    /// Depth of the centre below the undeformed skin (m).
    pub depth: f64,
    /// Lumen radius at rest (m).
    pub radius: f64,
    /// Wall thickness (m).
    pub wall: f64,
}

impl Vessel {
    /// Half-height of the rest lumen in the column `u` (m; 0 outside).
    pub fn lumen_half_height(&self, u: f64) -> f64 {
        let du = u - self.lateral;
        (self.radius * self.radius - du * du).max(0.0).sqrt()
    }

    /// Half-height of the rest vessel with its wall in the column `u` (m; 0 outside).
    pub fn outer_half_height(&self, u: f64) -> f64 {
        let r = self.radius + self.wall;
        let du = u - self.lateral;
        (r * r - du * du).max(0.0).sqrt()
    }

    /// Rest lumen area (m²): `π r²`.
    pub fn rest_area(&self) -> f64 {
        PI * self.radius * self.radius
    }
}

/// The section's anatomy for one vein state.
#[derive(Debug, Clone, PartialEq)]
pub struct Anatomy {
    cfg: AnatomyConfig,
    state: VeinState,
    vein_params: VeinStateParams,
    vein: Vessel,
    artery: Vessel,
}

/// Smooth step `3t² − 2t³` of `t` clamped to [0, 1].
fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Anatomy {
    /// The anatomy of `cfg` with the vein in `state`; validates `cfg` with
    /// the prefix `imaging.anatomy`.
    pub fn new(cfg: &AnatomyConfig, state: VeinState) -> Result<Self, ImagingError> {
        cfg.validate("imaging.anatomy")?;
        let vp = *cfg.vein(state);
        let vein = Vessel {
            lateral: cfg.vein_lateral,
            depth: cfg.vein_depth,
            radius: 0.5 * cfg.vein_diameter * vp.diameter_factor,
            wall: vp.wall_thickness,
        };
        let artery = Vessel {
            lateral: cfg.artery_lateral,
            depth: cfg.artery_depth,
            radius: 0.5 * cfg.artery_diameter,
            wall: cfg.artery_wall_thickness,
        };
        Ok(Anatomy {
            cfg: cfg.clone(),
            state,
            vein_params: vp,
            vein,
            artery,
        })
    }

    /// The parameters this anatomy was built from.
    pub fn config(&self) -> &AnatomyConfig {
        &self.cfg
    }

    /// The vein state.
    pub fn state(&self) -> VeinState {
        self.state
    }

    /// The femoral vein at rest (its size depends on the state).
    pub fn vein(&self) -> &Vessel {
        &self.vein
    }

    /// The femoral artery at rest (diastole).
    pub fn artery(&self) -> &Vessel {
        &self.artery
    }

    /// Depth of the femur's top below the undeformed skin (m), the default
    /// `bone_depth` of the normal springs' column.
    pub fn femur_top(&self) -> f64 {
        self.cfg.femur_top()
    }

    /// The femur's centre `(lateral, depth)` in tissue coordinates (m).
    pub fn femur_centre(&self) -> (f64, f64) {
        (
            self.cfg.femur_lateral,
            self.femur_top() + self.cfg.femur_radius,
        )
    }

    /// Depth of the intermuscular fascia below the skin in the column `u` (m):
    /// a gentle curve `d₀ + 3 mm (u/20 mm)² + 1 mm (u/20 mm)`.
    pub fn intermuscular_fascia(&self, u: f64) -> f64 {
        let x = u / 0.020;
        self.cfg.intermuscular_fascia_depth + 3e-3 * x * x + 1e-3 * x
    }

    /// The tissue at `(u, depth)` in tissue coordinates (m).
    pub fn tissue_at(&self, u: f64, depth: f64) -> Tissue {
        let c = &self.cfg;
        if depth < 0.0 {
            return Tissue::Gel;
        }
        if depth < c.skin_thickness {
            return Tissue::Skin;
        }
        let muscle_top = c.skin_thickness + c.fat_thickness;
        if depth < muscle_top {
            return Tissue::Fat;
        }
        let (fu, fd) = self.femur_centre();
        let rf = ((u - fu).powi(2) + (depth - fd).powi(2)).sqrt();
        if rf < c.femur_radius {
            return if rf > c.femur_radius - c.cortex_thickness {
                Tissue::Cortex
            } else {
                Tissue::Marrow
            };
        }
        for (v, lumen, wall) in [
            (&self.vein, Tissue::VeinLumen, Tissue::VeinWall),
            (&self.artery, Tissue::ArteryLumen, Tissue::ArteryWall),
        ] {
            let r = ((u - v.lateral).powi(2) + (depth - v.depth).powi(2)).sqrt();
            if r < v.radius {
                return lumen;
            }
            if r < v.radius + v.wall {
                return wall;
            }
        }
        if depth < muscle_top + c.fascia_thickness
            || (depth - self.intermuscular_fascia(u)).abs() < 0.5 * c.fascia_thickness
        {
            return Tissue::Fascia;
        }
        Tissue::Muscle
    }

    /// Mean backscatter of `tissue` relative to muscle (dB) in this vein
    /// state; `None` where there are no scatterers.
    pub fn echo_db(&self, tissue: Tissue) -> Option<f64> {
        match tissue {
            Tissue::VeinLumen => Some(self.vein_params.content_echo),
            Tissue::VeinWall => Some(self.vein_params.wall_echo),
            t => t.acoustics().echo_db,
        }
    }

    /// One-way attenuation slope of `tissue` (dB/(cm·MHz)) in this vein state.
    pub fn attenuation(&self, tissue: Tissue) -> f64 {
        match tissue {
            Tissue::VeinLumen => self.vein_params.content_attenuation,
            t => t.acoustics().attenuation,
        }
    }

    /// Writes into `out` the sorted depths (m, tissue coordinates) where the
    /// tissue may change along the column `u`, starting with 0 (the skin);
    /// returns how many. Between two consecutive breakpoints the tissue is
    /// the same up to thin fascia lines (which attenuate like muscle).
    pub fn column_breakpoints(&self, u: f64, out: &mut [f64; MAX_BREAKPOINTS]) -> usize {
        let c = &self.cfg;
        let mut n = 0;
        let mut push = |d: f64, n: &mut usize| {
            if *n < MAX_BREAKPOINTS {
                out[*n] = d;
                *n += 1;
            }
        };
        push(0.0, &mut n);
        push(c.skin_thickness, &mut n);
        push(c.skin_thickness + c.fat_thickness, &mut n);
        for v in [&self.vein, &self.artery] {
            let ho = v.outer_half_height(u);
            if ho > 0.0 {
                push(v.depth - ho, &mut n);
                push(v.depth + ho, &mut n);
                let hl = v.lumen_half_height(u);
                if hl > 0.0 {
                    push(v.depth - hl, &mut n);
                    push(v.depth + hl, &mut n);
                }
            }
        }
        let (fu, fd) = self.femur_centre();
        let du = u - fu;
        if du.abs() < c.femur_radius {
            push(fd - (c.femur_radius.powi(2) - du * du).sqrt(), &mut n);
        }
        out[..n].sort_unstable_by(f64::total_cmp);
        n
    }

    /// Arterial pulse waveform `P(t) ∈ [0, 1]` at time `t` (s): 1 at the
    /// systolic peak, ≈ 0 at end-diastole.
    pub fn pulse(&self, time: f64) -> f64 {
        if self.cfg.heart_rate <= 0.0 || !time.is_finite() {
            return 0.0;
        }
        let phase = (time * self.cfg.heart_rate).rem_euclid(1.0);
        let x = phase / PULSE_PEAK;
        x * (1.0 - x).exp()
    }

    /// Vein lumen area relative to rest (the vertical flattening `c`) under
    /// the tissue pressure `pressure` (Pa) at the vein.
    pub fn vein_lumen_ratio(&self, pressure: f64) -> f64 {
        let v = &self.vein_params;
        let t = (pressure - v.collapse_onset) / (v.collapse_full - v.collapse_onset);
        1.0 - (1.0 - v.min_lumen_ratio) * smoothstep(t)
    }

    /// Artery lumen area relative to its diastolic rest, under the tissue
    /// pressure `pressure` (Pa) at the artery and at time `time` (s).
    pub fn artery_lumen_ratio(&self, pressure: f64, time: f64) -> f64 {
        let c = &self.cfg;
        let t = (pressure - c.artery_collapse_onset)
            / (c.artery_collapse_full - c.artery_collapse_onset);
        let squeeze = 1.0 - (1.0 - c.artery_min_lumen_ratio) * smoothstep(t);
        squeeze * (1.0 + c.artery_distension * self.pulse(time))
    }

    /// Vein lumen area (m²) under the tissue pressure `pressure` (Pa) at the vein.
    pub fn vein_lumen_area(&self, pressure: f64) -> f64 {
        self.vein.rest_area() * self.vein_lumen_ratio(pressure)
    }

    /// Artery lumen area (m²) under the tissue pressure `pressure` (Pa) at time `time` (s).
    pub fn artery_lumen_area(&self, pressure: f64, time: f64) -> f64 {
        self.artery.rest_area() * self.artery_lumen_ratio(pressure, time)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anatomy_config::MMHG;

    fn anatomy(state: VeinState) -> Anatomy {
        Anatomy::new(&AnatomyConfig::default(), state).unwrap()
    }

    #[test]
    fn layers_in_order_down_a_column() {
        let a = anatomy(VeinState::Healthy);
        let u = 0.018; // beside the vessels, over the femur
        assert_eq!(a.tissue_at(u, -1e-3), Tissue::Gel);
        assert_eq!(a.tissue_at(u, 1e-3), Tissue::Skin);
        assert_eq!(a.tissue_at(u, 6e-3), Tissue::Fat);
        assert_eq!(a.tissue_at(u, 12.0e-3), Tissue::Fascia);
        assert_eq!(a.tissue_at(u, 15e-3), Tissue::Muscle);
        assert_eq!(a.tissue_at(-8e-3, 30e-3), Tissue::VeinLumen);
        assert_eq!(a.tissue_at(3e-3, 29e-3), Tissue::ArteryLumen);
        assert_eq!(a.tissue_at(6e-3, 41e-3), Tissue::Cortex);
        assert_eq!(a.tissue_at(6e-3, 52e-3), Tissue::Marrow);
    }

    #[test]
    fn healthy_collapses_thrombosed_do_not() {
        let h = anatomy(VeinState::Healthy);
        assert_eq!(h.vein_lumen_ratio(0.0), 1.0);
        assert!(h.vein_lumen_ratio(40.0 * MMHG) < 1e-12);
        let mut last = 1.0;
        for i in 0..100 {
            let r = h.vein_lumen_ratio(i as f64 * MMHG);
            assert!(r <= last + 1e-15);
            last = r;
        }
        for s in [VeinState::Acute, VeinState::Chronic] {
            let a = anatomy(s);
            assert!(a.vein_lumen_ratio(1e6) >= 0.8 - 1e-12);
        }
        let acute = anatomy(VeinState::Acute);
        assert!(acute.vein().radius > h.vein().radius);
    }

    #[test]
    fn artery_pulses_once_per_beat() {
        let a = anatomy(VeinState::Healthy);
        let peak = a.pulse(PULSE_PEAK);
        assert!((peak - 1.0).abs() < 1e-12);
        assert!(a.pulse(0.0).abs() < 1e-12);
        assert!((a.pulse(2.0 + PULSE_PEAK) - 1.0).abs() < 1e-9);
        let r = a.artery_lumen_ratio(0.0, PULSE_PEAK);
        assert!((r - 1.07).abs() < 1e-12);
    }

    #[test]
    fn breakpoints_sorted_and_bound_the_vessels() {
        let a = anatomy(VeinState::Chronic);
        let mut b = [0.0; MAX_BREAKPOINTS];
        let n = a.column_breakpoints(a.vein().lateral, &mut b);
        assert!(b[..n].windows(2).all(|w| w[0] <= w[1]));
        let v = a.vein();
        assert!(b[..n]
            .iter()
            .any(|&d| (d - (v.depth - v.radius)).abs() < 1e-12));
        assert!(b[..n]
            .iter()
            .any(|&d| (d - (v.depth + v.radius + v.wall)).abs() < 1e-12));
    }
}
