//! The state of a vein's lumen at one `s`: the blend of the healthy vein and
//! the thrombus segments on it ([`Thrombi::state`]), and the ground truth
//! of a leg ([`Thrombi::ground_truth`]): per vein, consecutive pieces that
//! cover its `s` range exactly once.
//!
//! Blend: with `wᵢ(s)` the weights of the segments on the vein
//! ([`Thrombus::weight`]; if they sum above 1 in a shared transition they
//! are scaled to sum to 1), every quantity `q` is
//! `q = (1 − Σwᵢ) q_healthy + Σ wᵢ qᵢ`. A segment's own values are those of
//! its kind at full weight ([`kind_state`]).

use crate::anatomy::Anatomy;
use crate::error::AnatomyError;
use crate::structure::{Kind, StructureId};
use crate::thrombus::{Thrombus, ThrombusKind, ThrombusSpec};
use serde::Serialize;

/// Healthy vein wall thickness (m): 0.5 mm (imaging's healthy default).
pub const HEALTHY_WALL: f64 = 0.5e-3;
/// Chronic post-thrombotic wall thickness (m): 1.5 mm (reference row 24).
pub const CHRONIC_WALL: f64 = 1.5e-3;
/// Smallest area ratio of acute thrombus under full compression: 0.8
/// ("spongy", area −20 % at most, reference row 23).
pub const ACUTE_MIN_RATIO: f64 = 0.8;
/// Smallest area ratio of chronic fibrous content: 0.95 (rigid, reference row 24).
pub const CHRONIC_MIN_RATIO: f64 = 0.95;
/// Smallest area ratio of a recanalized channel under full compression:
/// 0.5 (estimate: "partly recanalized channels, which compress partly",
/// issue 13; no measured value found).
pub const CHANNEL_MIN_RATIO: f64 = 0.5;

/// Where the thrombus sits in the lumen's cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Layout {
    /// Against the deep wall (mural thrombus, chronic synechiae, occlusive).
    Mural,
    /// In the middle of the lumen, blood all around (a free-floating tail).
    Central,
}

/// The lumen of one vein at one `s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LumenState {
    /// Fraction of the rest lumen's area that is thrombus or fibrous content (0 to 1).
    pub fill: f64,
    /// Smallest area ratio the filled part reaches under full compression.
    pub fill_min_ratio: f64,
    /// Smallest area ratio the open (blood) part reaches under full compression.
    pub open_min_ratio: f64,
    /// Diameter relative to the healthy vein.
    pub distension: f64,
    /// Wall thickness (m).
    pub wall_thickness: f64,
    /// Backscatter of the content relative to muscle (dB).
    pub echo_db: f64,
    /// Where the content sits.
    pub layout: Layout,
    /// Weight (0 to 1) of acute thrombus here.
    pub acute: f64,
    /// Weight (0 to 1) of chronic change here.
    pub chronic: f64,
    /// Weight (0 to 1) of a free-floating tail here (must not be compressed hard).
    pub free_floating: f64,
    /// How far the tail here sways with breathing relative to its free tip
    /// (0 where attached, 1 at the tip; [`tail_sway`]).
    pub sway: f64,
}

/// Relative sway of a free tail at normalised distance `xi` (0 to 1) from
/// its attachment towards its free tip: the deflection of a cantilever
/// under a uniform load (the drag of the flow along it),
/// `ξ² (6 − 4ξ + ξ²) / 3`, which is 0 with zero slope at the attachment
/// and 1 at the tip (Timoshenko, *Strength of Materials*, cantilever with
/// uniform load: `w(x) = q x² (6L² − 4Lx + x²) / (24 E I)`).
pub fn tail_sway(xi: f64) -> f64 {
    let x = xi.clamp(0.0, 1.0);
    x * x * (6.0 - 4.0 * x + x * x) / 3.0
}

impl LumenState {
    /// A healthy vein.
    pub const HEALTHY: LumenState = LumenState {
        fill: 0.0,
        fill_min_ratio: ACUTE_MIN_RATIO,
        open_min_ratio: 0.0,
        distension: 1.0,
        wall_thickness: HEALTHY_WALL,
        echo_db: -50.0,
        layout: Layout::Mural,
        acute: 0.0,
        chronic: 0.0,
        free_floating: 0.0,
        sway: 0.0,
    };

    /// Smallest lumen area relative to rest under full compression:
    /// `fill · fill_min + (1 − fill) · open_min` ("how compressible").
    pub fn min_lumen_ratio(&self) -> f64 {
        self.fill * self.fill_min_ratio + (1.0 - self.fill) * self.open_min_ratio
    }

    fn lerp(&self, o: &LumenState, w: f64) -> LumenState {
        let m = |a: f64, b: f64| a + w * (b - a);
        LumenState {
            fill: m(self.fill, o.fill),
            fill_min_ratio: if o.fill > 0.0 {
                o.fill_min_ratio
            } else {
                self.fill_min_ratio
            },
            open_min_ratio: m(self.open_min_ratio, o.open_min_ratio),
            distension: m(self.distension, o.distension),
            wall_thickness: m(self.wall_thickness, o.wall_thickness),
            echo_db: if o.fill > 0.0 {
                o.echo_db
            } else {
                self.echo_db
            },
            layout: o.layout,
            acute: m(self.acute, o.acute),
            chronic: m(self.chronic, o.chronic),
            free_floating: m(self.free_floating, o.free_floating),
            sway: m(self.sway, o.sway),
        }
    }
}

/// The state of segment `t` at full weight; `tail` (0 to 1) is the weight
/// of its free-floating tail at this `s`, `sway` the tail's relative sway
/// there ([`tail_sway`]; 0 for other kinds).
pub fn kind_state(t: &Thrombus, tail: f64, sway: f64) -> LumenState {
    let acute = LumenState {
        fill: 1.0,
        fill_min_ratio: ACUTE_MIN_RATIO,
        open_min_ratio: 0.0,
        distension: t.distension,
        wall_thickness: HEALTHY_WALL,
        echo_db: t.echo_db,
        layout: Layout::Mural,
        acute: 1.0,
        chronic: 0.0,
        free_floating: 0.0,
        sway: 0.0,
    };
    match t.kind {
        ThrombusKind::AcuteOcclusive => acute,
        ThrombusKind::AcuteNonOcclusive => LumenState {
            fill: t.fill,
            ..acute
        },
        ThrombusKind::FreeFloating => {
            let floating = LumenState {
                fill: t.fill,
                layout: Layout::Central,
                free_floating: 1.0,
                sway,
                ..acute
            };
            let mut s = acute.lerp(&floating, tail);
            s.layout = if tail >= 0.5 {
                Layout::Central
            } else {
                Layout::Mural
            };
            s
        }
        ThrombusKind::Chronic => LumenState {
            fill: 1.0 - t.recanalized,
            fill_min_ratio: CHRONIC_MIN_RATIO,
            open_min_ratio: CHANNEL_MIN_RATIO,
            distension: t.distension,
            wall_thickness: CHRONIC_WALL,
            echo_db: t.echo_db,
            layout: Layout::Mural,
            acute: 0.0,
            chronic: 1.0,
            free_floating: 0.0,
            sway: 0.0,
        },
    }
}

/// One piece of a vein's ground truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TruthPiece {
    /// Proximal end (m).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// `normal` or a thrombus kind's name.
    pub kind: &'static str,
}

/// The ground truth of one vein: pieces covering its `s` range exactly once.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VeinTruth {
    /// The vein's id (`cfv`, `fv`, …).
    pub vein: &'static str,
    /// Consecutive pieces, proximal to distal.
    pub pieces: Vec<TruthPiece>,
}

/// The validated thrombus segments of one leg.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Thrombi {
    segments: Vec<Thrombus>,
}

impl Thrombi {
    /// Validates `specs` (keys `thrombus[i]`) against `anatomy`; also refuses
    /// two segments on one vein whose extents overlap, naming both.
    pub fn new(anatomy: &Anatomy, specs: &[ThrombusSpec]) -> Result<Thrombi, AnatomyError> {
        let mut segments: Vec<Thrombus> = Vec::with_capacity(specs.len());
        for (i, spec) in specs.iter().enumerate() {
            let key = format!("thrombus[{i}]");
            let t = spec.resolve(&key, anatomy)?;
            if let Some(j) = segments
                .iter()
                .position(|o| o.vein == t.vein && t.s_start < o.s_end && o.s_start < t.s_end)
            {
                return Err(AnatomyError::Thrombus {
                    key: format!("{key}.s_start"),
                    reason: format!(
                        "[{:.1}, {:.1}] mm overlaps thrombus[{j}] on `{}` ([{:.1}, {:.1}] mm)",
                        t.s_start * 1e3,
                        t.s_end * 1e3,
                        t.vein.as_str(),
                        segments[j].s_start * 1e3,
                        segments[j].s_end * 1e3
                    ),
                });
            }
            segments.push(t);
        }
        Ok(Thrombi { segments })
    }

    /// The segments, in file order.
    pub fn segments(&self) -> &[Thrombus] {
        &self.segments
    }

    /// The state of vein `vein` at `s` (healthy where no segment reaches).
    pub fn state(&self, vein: StructureId, s: f64) -> LumenState {
        let on: Vec<(f64, &Thrombus)> = self
            .segments
            .iter()
            .filter(|t| t.vein == vein)
            .map(|t| (t.weight(s), t))
            .filter(|(w, _)| *w > 0.0)
            .collect();
        let total: f64 = on.iter().map(|(w, _)| w).sum();
        let scale = if total > 1.0 { 1.0 / total } else { 1.0 };
        // Blend the strongest segment last so that its layout and echo win.
        let mut on = on;
        on.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut st = LumenState::HEALTHY;
        for (w, t) in on {
            st = add_weighted(
                &st,
                &kind_state(t, t.tail_weight(s), tail_sway(t.tail_position(s))),
                w * scale,
            );
        }
        st
    }

    /// Per vein of `anatomy` (cfv, fv, pv, gsv, dfv, fv2 when present), its
    /// pieces proximal to distal: `normal` between segments, each segment's
    /// kind over its extent; together they cover the vein's range once.
    pub fn ground_truth(&self, anatomy: &Anatomy) -> Vec<VeinTruth> {
        anatomy
            .tubes()
            .iter()
            .filter(|t| matches!(t.kind(), Kind::DeepVein | Kind::SuperficialVein))
            .map(|tube| {
                let (lo, hi) = tube.s_range();
                let mut segs: Vec<&Thrombus> = self
                    .segments
                    .iter()
                    .filter(|t| t.vein == tube.id())
                    .collect();
                segs.sort_by(|a, b| a.s_start.total_cmp(&b.s_start));
                let mut pieces = Vec::new();
                let mut at = lo;
                for t in segs {
                    if t.s_start > at {
                        pieces.push(TruthPiece {
                            s_start: at,
                            s_end: t.s_start,
                            kind: "normal",
                        });
                    }
                    pieces.push(TruthPiece {
                        s_start: t.s_start,
                        s_end: t.s_end,
                        kind: t.kind.name(),
                    });
                    at = t.s_end;
                }
                if at < hi {
                    pieces.push(TruthPiece {
                        s_start: at,
                        s_end: hi,
                        kind: "normal",
                    });
                }
                VeinTruth {
                    vein: tube.id().as_str(),
                    pieces,
                }
            })
            .collect()
    }
}

/// `st + w (q_k − q_healthy)` for the linear fields: starting from the
/// healthy state, adding each segment this way gives the blend
/// `(1 − Σw) q_healthy + Σ wᵢ qᵢ` of the module docs. The content's echo,
/// compliance and layout are those of the last segment added (the
/// strongest, as [`Thrombi::state`] adds them in increasing weight).
fn add_weighted(st: &LumenState, k: &LumenState, w: f64) -> LumenState {
    let h = LumenState::HEALTHY;
    let m = |s: f64, kk: f64, hh: f64| s + w * (kk - hh);
    LumenState {
        fill: m(st.fill, k.fill, h.fill),
        fill_min_ratio: if k.fill > 0.0 {
            k.fill_min_ratio
        } else {
            st.fill_min_ratio
        },
        open_min_ratio: m(st.open_min_ratio, k.open_min_ratio, h.open_min_ratio),
        distension: m(st.distension, k.distension, h.distension),
        wall_thickness: m(st.wall_thickness, k.wall_thickness, h.wall_thickness),
        echo_db: if k.fill > 0.0 { k.echo_db } else { st.echo_db },
        layout: k.layout,
        acute: m(st.acute, k.acute, h.acute),
        chronic: m(st.chronic, k.chronic, h.chronic),
        free_floating: m(st.free_floating, k.free_floating, h.free_floating),
        sway: m(st.sway, k.sway, h.sway),
    }
}
