//! The flow of one vessel segment, driven by the case (issue 17).
//!
//! For a vein at `s`: the open fraction of its lumen (`1 − fill` of the
//! case's thrombus state there); whether the path towards the heart is
//! obstructed (the case's `proximal_obstruction` flag, or an occluded
//! stretch of the vein line between `s` and the groin: flow continuous,
//! not phasic, no Valsalva response); whether the path from the calf is
//! (an occluded stretch below `s`: no augmentation). The velocity follows
//! continuity — the same flow through the open part, `v / open` — so a
//! non-occlusive thrombus has a jet around it and a recanalized chronic
//! segment fast flow in its channels; an occluded segment (open fraction
//! under `occluded_open_fraction`) has none. Arteries are triphasic
//! ([`crate::arterial`]).
//!
//! Velocities are centreline (spectral maximum) values in m/s along the
//! vessel's own flow direction (veins towards the heart, arteries away).

use crate::arterial::triphasic;
use crate::maneuver::Maneuvers;
use crate::physiology::FlowConfig;
use echothigh_anatomy::{Anatomy, Kind, StructureId, Thrombi};
use serde::Serialize;

/// Step (m) at which the vein line is sampled for occlusions.
const PATH_STEP: f64 = 2e-3;

/// Whether a segment carries venous or arterial flow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FlowKind {
    /// Venous: phasic with breathing, augmentable.
    Vein,
    /// Arterial: triphasic at the heart rate.
    Artery,
}

/// The flow of one vessel at one `s` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SegmentFlow {
    /// Venous or arterial.
    pub kind: FlowKind,
    /// Resting peak centreline velocity of the healthy vessel here (m/s).
    pub rest_peak: f64,
    /// Fraction of the lumen that is open (blood), 0 to 1.
    pub open_fraction: f64,
    /// Whether the segment is occluded (no flow).
    pub occluded: bool,
    /// Phasic with breathing and responsive to Valsalva (no proximal obstruction).
    pub phasic: bool,
    /// Augments on a calf squeeze (no occlusion below).
    pub augmentable: bool,
    /// Thrombus here or proximal obstruction: dampened Valsalva distension.
    pub obstructed: bool,
}

/// Whether the lumen of `id` is occluded at `s`.
fn occluded_at(thrombi: &Thrombi, id: StructureId, s: f64, cfg: &FlowConfig) -> bool {
    1.0 - thrombi.state(id, s).fill < cfg.occluded_open_fraction
}

/// Whether any sample of `f` over `[a, b)` is true.
fn any_on(a: f64, b: f64, mut f: impl FnMut(f64) -> bool) -> bool {
    let n = ((b - a) / PATH_STEP).ceil().max(0.0) as usize;
    (0..n).any(|i| f(a + i as f64 * PATH_STEP))
}

impl SegmentFlow {
    /// The flow of vessel `id` at `s` (m) in a case (`thrombi` on
    /// `anatomy`); `proximal_obstruction` is the case's iliac obstruction flag.
    pub fn of(
        cfg: &FlowConfig,
        anatomy: &Anatomy,
        thrombi: &Thrombi,
        id: StructureId,
        s: f64,
        proximal_obstruction: bool,
    ) -> SegmentFlow {
        use StructureId as S;
        let kind = anatomy.tube(id).map(|t| t.kind());
        if kind == Some(Kind::Artery) {
            let psv = match id {
                S::Cfa => cfg.cfa_psv,
                S::Pa => cfg.pa_psv,
                _ => cfg.fa_psv,
            };
            return SegmentFlow {
                kind: FlowKind::Artery,
                rest_peak: psv,
                open_fraction: 1.0,
                occluded: false,
                phasic: false,
                augmentable: false,
                obstructed: false,
            };
        }
        let rest_peak = cfg.cfv_peak_velocity
            * match id {
                S::Cfv => 1.0,
                S::Fv | S::Dfv | S::Fv2 => cfg.thigh_vein_ratio,
                _ => cfg.distal_vein_ratio,
            };
        let deep_line = matches!(id, S::Cfv | S::Fv | S::Pv);
        let (s0, s1) = anatomy
            .tube(id)
            .map_or((0.0, anatomy.length()), |t| t.s_range());
        let line = |x: f64| occluded_at(thrombi, anatomy.deep_vein_at(x), x, cfg);
        let own = |x: f64| occluded_at(thrombi, id, x, cfg);
        // Towards the heart: the deep line up to `s` (or up to the
        // tributary's junction, then its own tube up to `s`).
        let above = if deep_line {
            any_on(0.0, s, line)
        } else {
            any_on(0.0, s0, line) || any_on(s0, s, own)
        };
        // From the calf: the vessel below `s` (the deep line below it).
        let below = if deep_line {
            any_on(s + PATH_STEP, anatomy.length(), line)
        } else {
            any_on(s + PATH_STEP, s1, own)
        };
        let st = thrombi.state(id, s);
        let open = (1.0 - st.fill).clamp(0.0, 1.0);
        let occluded = open < cfg.occluded_open_fraction;
        let prox = proximal_obstruction || above;
        SegmentFlow {
            kind: FlowKind::Vein,
            rest_peak,
            open_fraction: open,
            occluded,
            phasic: !prox && !occluded,
            augmentable: !below && !occluded,
            obstructed: prox || st.fill > 0.0,
        }
    }

    /// A healthy vessel of `kind` with resting peak `rest_peak` (m/s), for
    /// phantoms and tests.
    pub fn healthy(kind: FlowKind, rest_peak: f64) -> SegmentFlow {
        SegmentFlow {
            kind,
            rest_peak,
            open_fraction: 1.0,
            occluded: false,
            phasic: kind == FlowKind::Vein,
            augmentable: kind == FlowKind::Vein,
            obstructed: false,
        }
    }

    /// Centreline velocity (m/s, along the flow direction) at time `t` (s)
    /// with the manoeuvres `m`, the lumen under the probe at
    /// `probe_lumen_ratio` of rest (1 when not pressed; below
    /// `closed_ratio` the vein is closed and carries nothing).
    ///
    /// Vein: `base = peak · b(t) · r(t)` with the breathing term
    /// `r = max(0, 1 + d sin 2πft)/(1 + d)` (phasic; `1/(1 + d)`, its
    /// mean level, when continuous) and the Valsalva term `b` (1 when
    /// not responsive), then an augmentation `(γ, F)` gives
    /// `base + (F·peak − base)·γ` (none when not augmentable), divided by
    /// the open fraction (continuity).
    pub fn velocity(&self, cfg: &FlowConfig, m: &Maneuvers, t: f64, probe_lumen_ratio: f64) -> f64 {
        if self.occluded || probe_lumen_ratio < cfg.closed_ratio {
            return 0.0;
        }
        match self.kind {
            FlowKind::Artery => self.rest_peak * triphasic(t, cfg.heart_rate),
            FlowKind::Vein => {
                let d = cfg.breathing_depth;
                let r = if self.phasic {
                    (1.0 + d * (std::f64::consts::TAU * cfg.breathing_rate * t).sin()).max(0.0)
                        / (1.0 + d)
                } else {
                    1.0 / (1.0 + d)
                };
                let b = if self.phasic {
                    m.valsalva_flow(cfg, t)
                } else {
                    1.0
                };
                let base = self.rest_peak * r * b;
                let v = if self.augmentable {
                    let (g, f) = m.augmentation(cfg, t);
                    base + (f * self.rest_peak - base) * g
                } else {
                    base
                };
                v / self.open_fraction
            }
        }
    }

    /// Diameter of the vein relative to its resting diameter at `t` under
    /// the manoeuvres `m`: `1 + D · strain(t)`, `D` the healthy or the
    /// obstructed Valsalva distension; 1 for an artery.
    pub fn diameter_factor(&self, cfg: &FlowConfig, m: &Maneuvers, t: f64) -> f64 {
        if self.kind == FlowKind::Artery {
            return 1.0;
        }
        let d = if self.obstructed || self.occluded {
            cfg.valsalva_distension_obstructed
        } else {
            cfg.valsalva_distension_healthy
        };
        1.0 + d * m.valsalva_strain(cfg, t)
    }
}
