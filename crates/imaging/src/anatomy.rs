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

use crate::anatomy_config::{AnatomyConfig, VeinState};
use crate::error::ImagingError;
use crate::post_thrombotic::WEB_THICKNESS;
use crate::structure_config::StructureKind;
use crate::tissue::Tissue;
use crate::vein_condition::{ContentLayout, VeinCondition};
use std::f64::consts::PI;

/// Largest number of breakpoints [`Anatomy::column_breakpoints`] returns.
pub const MAX_BREAKPOINTS: usize = 64;

/// Time to the systolic peak as a fraction of the heart cycle.
const PULSE_PEAK: f64 = 0.12;

/// A vessel at rest, in tissue coordinates: an elliptic lumen (the cut of
/// an oblique plane through a round vessel; a circle when the plane is
/// normal to it) with a wall of uniform thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vessel {
    /// Lateral position of the centre (m).
    pub lateral: f64,
    /// Depth of the centre below the undeformed skin (m).
    pub depth: f64,
    /// Lumen semi-axis `a` at rest (m), at `angle` from the lateral axis.
    pub radius: f64,
    /// Lumen semi-axis `b` at rest (m), across `a`.
    pub radius_b: f64,
    /// Angle of the `a` axis from the lateral axis towards depth (rad).
    pub angle: f64,
    /// Wall thickness (m).
    pub wall: f64,
}

impl Vessel {
    /// A circular vessel of lumen radius `radius` (m).
    pub fn circle(lateral: f64, depth: f64, radius: f64, wall: f64) -> Self {
        Vessel {
            lateral,
            depth,
            radius,
            radius_b: radius,
            angle: 0.0,
            wall,
        }
    }

    /// An upright oval vessel with the area of the circle of radius
    /// `radius` (m) and width/height `aspect`: semi-axes `r √A` across and
    /// `r / √A` in depth (`π a b = π r²`, so the lumen laws' areas keep
    /// their meaning).
    pub fn oval(lateral: f64, depth: f64, radius: f64, aspect: f64, wall: f64) -> Self {
        let k = aspect.max(1e-3).sqrt();
        Vessel {
            lateral,
            depth,
            radius: radius * k,
            radius_b: radius / k,
            angle: 0.0,
            wall,
        }
    }

    /// The vertical chord of the ellipse grown by `grow` (m) in the column
    /// `u`: `(centre depth, half-height)` (m), half-height 0 outside.
    /// With `(ξ, ζ)` the ellipse axes, `ξ²/a² + ζ²/b² ≤ 1` is, along the
    /// column (`Δu` fixed, `Δd` free), `A Δd² + 2 B Δd + C ≤ 0`: the chord
    /// is centred at `−B/A` with half-height `√(B² − A C)/A`.
    pub fn chord(&self, u: f64, grow: f64) -> (f64, f64) {
        let a = (self.radius + grow).max(1e-9);
        let b = (self.radius_b + grow).max(1e-9);
        let (sn, cs) = self.angle.sin_cos();
        let (ia, ib) = (1.0 / (a * a), 1.0 / (b * b));
        let du = u - self.lateral;
        let qa = sn * sn * ia + cs * cs * ib;
        let qb = du * sn * cs * (ia - ib);
        let qc = du * du * (cs * cs * ia + sn * sn * ib) - 1.0;
        let disc = qb * qb - qa * qc;
        if disc <= 0.0 {
            return (self.depth, 0.0);
        }
        (self.depth - qb / qa, disc.sqrt() / qa)
    }

    /// Half-height of the rest lumen in the column `u` (m; 0 outside).
    pub fn lumen_half_height(&self, u: f64) -> f64 {
        self.chord(u, 0.0).1
    }

    /// Half-height of the rest vessel with its wall in the column `u` (m; 0 outside).
    pub fn outer_half_height(&self, u: f64) -> f64 {
        self.chord(u, self.wall).1
    }

    /// Whether `(u, d)` lies inside the lumen grown by `grow` (m).
    pub fn contains(&self, u: f64, d: f64, grow: f64) -> bool {
        let (c, h) = self.chord(u, grow);
        (d - c).abs() < h
    }

    /// Half of the lumen's lateral extent (m).
    pub fn half_width(&self) -> f64 {
        let (sn, cs) = self.angle.sin_cos();
        (self.radius.powi(2) * cs * cs + self.radius_b.powi(2) * sn * sn).sqrt()
    }

    /// Half of the lateral extent (m) of the lumen grown by `grow` (m).
    pub fn chord_half_width(&self, grow: f64) -> f64 {
        let (sn, cs) = self.angle.sin_cos();
        let (a, b) = (self.radius + grow, self.radius_b + grow);
        (a * a * cs * cs + b * b * sn * sn).sqrt()
    }

    /// Half of the lumen's vertical extent (m).
    pub fn half_height(&self) -> f64 {
        let (sn, cs) = self.angle.sin_cos();
        (self.radius.powi(2) * sn * sn + self.radius_b.powi(2) * cs * cs).sqrt()
    }

    /// Rest lumen area (m²): `π a b`.
    pub fn rest_area(&self) -> f64 {
        PI * self.radius * self.radius_b
    }
}

/// How a vessel's lumen responds to the tissue pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LumenLaw {
    /// The vein law of this condition (issue 13: per vein).
    Vein(VeinCondition),
    /// The artery law of the anatomy's configuration.
    Artery,
}

/// One vessel of the section with its lumen law and echoes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionVessel {
    /// The vessel at rest.
    pub vessel: Vessel,
    /// Its lumen law.
    pub law: LumenLaw,
    /// Its tissue classes: (lumen, wall).
    pub tissues: (Tissue, Tissue),
}

impl SectionVessel {
    /// The vein's condition (`None` for an artery).
    pub fn condition(&self) -> Option<&VeinCondition> {
        match &self.law {
            LumenLaw::Vein(c) => Some(c),
            LumenLaw::Artery => None,
        }
    }
}

/// The section's anatomy for one vein state.
#[derive(Debug, Clone, PartialEq)]
pub struct Anatomy {
    cfg: AnatomyConfig,
    state: VeinState,
    /// The studied vein (0), its artery (1), then the extra vessels.
    vessels: Vec<SectionVessel>,
    /// Muscle outlines and lymph nodes.
    others: Vec<(StructureKind, Vessel)>,
}

/// The tissue at `(u, depth)` inside the lumen of `sv` (its chord in this
/// column centred at `centre`, half-height `h`): blood or content by the
/// condition's layout, or, in a post-thrombotic vein, a web (drawn as the
/// wall's fibrous tissue), a recanalized channel (blood) or the residual
/// fibrous content ([`crate::post_thrombotic`]).
fn lumen_tissue(sv: &SectionVessel, u: f64, depth: f64, centre: f64, h: f64) -> Tissue {
    let Some(vc) = sv.condition() else {
        return sv.tissues.0;
    };
    if let Some(pt) = &vc.post_thrombotic {
        let v = &sv.vessel;
        let (sn, cs) = v.angle.sin_cos();
        let (du, dd) = (u - v.lateral, depth - v.depth);
        let (x, y) = (
            (du * cs + dd * sn) / v.radius,
            (-du * sn + dd * cs) / v.radius_b,
        );
        let half = 0.5 * WEB_THICKNESS / v.radius_b;
        return if pt.on_web(x, y, half) {
            sv.tissues.1
        } else if pt.in_channel(x, y, 1.0 - vc.fill, 2.0 * half) {
            sv.tissues.0
        } else {
            Tissue::Thrombus
        };
    }
    if vc.fill > 0.0 && vc.is_content((depth - centre) / h) {
        Tissue::Thrombus
    } else {
        sv.tissues.0
    }
}

/// Whether `(u, depth)` lies in the wall of `sv`: within its wall thickness
/// of the lumen, the post-thrombotic wall's own at the point's polar angle
/// around the centre ([`crate::post_thrombotic::PostThrombotic::wall_at`]).
fn in_wall(sv: &SectionVessel, u: f64, depth: f64) -> bool {
    let v = &sv.vessel;
    let wall = match sv.condition().and_then(|c| c.post_thrombotic.as_ref()) {
        Some(pt) => pt.wall_at(v.wall, (depth - v.depth).atan2(u - v.lateral)),
        None => v.wall,
    };
    v.contains(u, depth, wall)
}

/// Width over height of a patent vein's lumen at rest, supine (an
/// **estimate**, not a measured value: the fidelity review (row 30) notes
/// only that a real vein is oval, not round, at rest; at a venous pressure
/// of ~10 mmHg a thin-walled vein is partly collapsed, and transverse CFV/FV
/// images show width/height ≈ 1.2–1.5; 1.3 is taken).
pub const VEIN_REST_ASPECT: f64 = 1.3;

/// Rest aspect of a vein whose lumen holds content over `fill` of its area:
/// `1 + (A − 1)(1 − fill)`, [`VEIN_REST_ASPECT`] when patent and round when
/// filled (a thrombus distends the vein into a round tube).
pub fn rest_aspect(fill: f64) -> f64 {
    1.0 + (VEIN_REST_ASPECT - 1.0) * (1.0 - fill.clamp(0.0, 1.0))
}

/// Smooth step `3t² − 2t³` of `t` clamped to [0, 1].
fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Anatomy {
    /// The anatomy of `cfg` with the vein in `state`; validates `cfg` with
    /// the prefix `imaging.anatomy`. The studied vein's condition is
    /// `cfg.vein_condition` when set (a case's segment state at the
    /// section), else that of `state` (one segment along the whole vein);
    /// each vein of `structures` has its own `condition` (healthy if none).
    pub fn new(cfg: &AnatomyConfig, state: VeinState) -> Result<Self, ImagingError> {
        cfg.validate("imaging.anatomy")?;
        let vc = cfg.studied_condition(state);
        let vein = Vessel::oval(
            cfg.vein_lateral,
            cfg.vein_depth,
            0.5 * cfg.vein_diameter * vc.diameter_factor,
            rest_aspect(vc.fill),
            vc.wall_thickness,
        );
        let artery = Vessel::circle(
            cfg.artery_lateral,
            cfg.artery_depth,
            0.5 * cfg.artery_diameter,
            cfg.artery_wall_thickness,
        );
        let mut vessels = vec![
            SectionVessel {
                vessel: vein,
                law: LumenLaw::Vein(vc),
                tissues: (Tissue::VeinLumen, Tissue::VeinWall),
            },
            SectionVessel {
                vessel: artery,
                law: LumenLaw::Artery,
                tissues: (Tissue::ArteryLumen, Tissue::ArteryWall),
            },
        ];
        let mut others = Vec::new();
        let healthy = VeinCondition::of_state(VeinState::Healthy, &cfg.healthy, &cfg.healthy);
        for st in &cfg.structures {
            let mut v = Vessel {
                lateral: st.lateral,
                depth: st.depth,
                radius: st.radii[0],
                radius_b: st.radii[1],
                angle: st.angle,
                wall: st.wall,
            };
            match st.kind {
                StructureKind::Vein => {
                    let c = st.condition.unwrap_or(healthy);
                    if let Some(own) = &st.condition {
                        v.radius *= own.diameter_factor;
                        v.radius_b *= own.diameter_factor;
                        v.wall = own.wall_thickness;
                    }
                    vessels.push(SectionVessel {
                        vessel: v,
                        law: LumenLaw::Vein(c),
                        tissues: (Tissue::Blood, Tissue::VesselWall),
                    })
                }
                StructureKind::Artery => vessels.push(SectionVessel {
                    vessel: v,
                    law: LumenLaw::Artery,
                    tissues: (Tissue::ArteryLumen, Tissue::ArteryWall),
                }),
                k => others.push((k, v)),
            }
        }
        Ok(Anatomy {
            cfg: cfg.clone(),
            state,
            vessels,
            others,
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

    /// The studied vein at rest (its size depends on the state).
    pub fn vein(&self) -> &Vessel {
        &self.vessels[0].vessel
    }

    /// The studied vein's artery at rest (diastole).
    pub fn artery(&self) -> &Vessel {
        &self.vessels[1].vessel
    }

    /// Every vessel of the section: the studied vein (0), its artery (1),
    /// then the `structures` vessels in their configured order.
    pub fn vessels(&self) -> &[SectionVessel] {
        &self.vessels
    }

    /// Lumen area relative to rest of vessel `i` of [`Anatomy::vessels`]
    /// under the tissue pressure `pressure` (Pa) at it and at time `time` (s).
    pub fn lumen_ratio(&self, i: usize, pressure: f64, time: f64) -> f64 {
        match self.vessels[i].law {
            LumenLaw::Vein(c) => c.lumen_ratio(pressure),
            LumenLaw::Artery => self.artery_lumen_ratio(pressure, time),
        }
    }

    /// The outlines of the muscles among the structures (their fascia).
    pub(crate) fn muscle_outlines(&self) -> impl Iterator<Item = &Vessel> {
        self.others
            .iter()
            .filter_map(|(k, v)| (*k == StructureKind::Muscle).then_some(v))
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
        self.classify(u, depth).0
    }

    /// The tissue at `(u, depth)` and, inside a vessel (lumen, content or
    /// wall), the vessel's index in [`Anatomy::vessels`].
    pub fn classify(&self, u: f64, depth: f64) -> (Tissue, Option<usize>) {
        let c = &self.cfg;
        if depth < 0.0 {
            return (Tissue::Gel, None);
        }
        if depth < c.skin_thickness {
            return (Tissue::Skin, None);
        }
        // Lumens first, then walls: where two vessels join (the GSV into
        // the CFV at the SFJ) one's wall inside the other's lumen is lumen.
        for (i, sv) in self.vessels.iter().enumerate() {
            let (centre, h) = sv.vessel.chord(u, 0.0);
            if (depth - centre).abs() < h {
                return (lumen_tissue(sv, u, depth, centre, h), Some(i));
            }
        }
        if let Some(i) = self.vessels.iter().position(|x| in_wall(x, u, depth)) {
            return (self.vessels[i].tissues.1, Some(i));
        }
        (self.tissue_outside_vessels(u, depth), None)
    }

    fn tissue_outside_vessels(&self, u: f64, depth: f64) -> Tissue {
        let c = &self.cfg;
        let half_line = 0.5 * c.fascia_thickness;
        for (kind, v) in &self.others {
            match kind {
                StructureKind::LymphNode if v.contains(u, depth, 0.0) => {
                    // The fatty hilum: the inner 45 % of the node's size.
                    let hilum = Vessel {
                        radius: 0.45 * v.radius,
                        radius_b: 0.45 * v.radius_b,
                        ..*v
                    };
                    return if hilum.contains(u, depth, 0.0) {
                        Tissue::NodeHilum
                    } else {
                        Tissue::NodeCortex
                    };
                }
                StructureKind::Muscle
                    if v.contains(u, depth, half_line) && !v.contains(u, depth, -half_line) =>
                {
                    return Tissue::Fascia;
                }
                _ => {}
            }
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
        if depth < muscle_top + c.fascia_thickness
            || (depth - self.intermuscular_fascia(u)).abs() < 0.5 * c.fascia_thickness
        {
            return Tissue::Fascia;
        }
        Tissue::Muscle
    }

    /// Mean backscatter of `tissue` relative to muscle (dB) for the studied
    /// vein's condition; `None` where there are no scatterers. Vessel
    /// tissues of other veins: [`Anatomy::echo_at`].
    pub fn echo_db(&self, tissue: Tissue) -> Option<f64> {
        self.echo_of(tissue, Some(0))
    }

    /// One-way attenuation slope of `tissue` (dB/(cm·MHz)) for the studied vein.
    pub fn attenuation(&self, tissue: Tissue) -> f64 {
        self.attenuation_of(tissue, Some(0))
    }

    /// Mean backscatter (dB re muscle) at `(u, depth)`, each vein by its own condition.
    pub fn echo_at(&self, u: f64, depth: f64) -> Option<f64> {
        let (t, i) = self.classify(u, depth);
        self.echo_of(t, i)
    }

    /// One-way attenuation slope (dB/(cm·MHz)) at `(u, depth)`.
    pub fn attenuation_at(&self, u: f64, depth: f64) -> f64 {
        let (t, i) = self.classify(u, depth);
        self.attenuation_of(t, i)
    }

    fn condition_of(&self, vessel: Option<usize>) -> Option<&VeinCondition> {
        vessel
            .and_then(|i| self.vessels.get(i))
            .and_then(|v| v.condition())
    }

    pub(crate) fn echo_of(&self, tissue: Tissue, vessel: Option<usize>) -> Option<f64> {
        let vc = self.condition_of(vessel);
        match (tissue, vc) {
            (Tissue::Thrombus, Some(c)) => Some(c.content_echo),
            (Tissue::VeinWall | Tissue::VesselWall, Some(c)) => Some(c.wall_echo),
            // Blood of the studied vein: the healthy state's content.
            (Tissue::VeinLumen, _) => Some(self.cfg.healthy.content_echo),
            (t, _) => t.acoustics().echo_db,
        }
    }

    fn attenuation_of(&self, tissue: Tissue, vessel: Option<usize>) -> f64 {
        match (tissue, self.condition_of(vessel)) {
            (Tissue::Thrombus, Some(c)) => c.content_attenuation,
            (Tissue::VeinLumen, _) => self.cfg.healthy.content_attenuation,
            (t, _) => t.acoustics().attenuation,
        }
    }

    /// Writes into `out` the sorted depths (m, tissue coordinates) where the
    /// tissue may change along the column `u`, starting with 0 (the skin);
    /// returns how many. Between two consecutive breakpoints the tissue is
    /// the same (the attenuation takes one slope per segment, read at its
    /// middle): the fascia lines (deep, intermuscular, muscle outlines) have
    /// their own breakpoints, else a segment of muscle whose middle fell in
    /// a line would take the line's slope over its whole length.
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
        // The fascia lines, as `classify` draws them.
        let half_line = 0.5 * c.fascia_thickness;
        push(
            c.skin_thickness + c.fat_thickness + c.fascia_thickness,
            &mut n,
        );
        let inter = self.intermuscular_fascia(u);
        push(inter - half_line, &mut n);
        push(inter + half_line, &mut n);
        for v in self.muscle_outlines() {
            for grow in [half_line, -half_line] {
                let (cm, hm) = v.chord(u, grow);
                if hm > 0.0 {
                    push(cm - hm, &mut n);
                    push(cm + hm, &mut n);
                }
            }
        }
        // Content boundaries inside vein lumens (see `VeinCondition::is_content`).
        for sv in &self.vessels {
            if let Some(vc) = sv.condition().filter(|vc| vc.fill > 0.0 && vc.fill < 1.0) {
                let (cl, hl) = sv.vessel.chord(u, 0.0);
                if hl > 0.0 {
                    match vc.layout {
                        ContentLayout::Mural => push(cl + hl * (1.0 - 2.0 * vc.fill), &mut n),
                        ContentLayout::Central => {
                            push(cl - hl * vc.fill, &mut n);
                            push(cl + hl * vc.fill, &mut n);
                        }
                    }
                }
            }
        }
        for v in self.vessels.iter().map(|x| &x.vessel).chain(
            self.others
                .iter()
                .filter_map(|(k, v)| (*k == StructureKind::LymphNode).then_some(v)),
        ) {
            let (co, ho) = v.chord(u, v.wall);
            if ho > 0.0 {
                push(co - ho, &mut n);
                push(co + ho, &mut n);
                let (cl, hl) = v.chord(u, 0.0);
                if hl > 0.0 {
                    push(cl - hl, &mut n);
                    push(cl + hl, &mut n);
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
        self.lumen_ratio(0, pressure, 0.0)
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
        self.vein().rest_area() * self.vein_lumen_ratio(pressure)
    }

    /// Artery lumen area (m²) under the tissue pressure `pressure` (Pa) at time `time` (s).
    pub fn artery_lumen_area(&self, pressure: f64, time: f64) -> f64 {
        self.artery().rest_area() * self.artery_lumen_ratio(pressure, time)
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
    fn patent_vein_is_oval_filled_vein_and_artery_round() {
        let h = anatomy(VeinState::Healthy);
        let v = h.vein();
        let aspect = v.half_width() / v.half_height();
        assert!((aspect - VEIN_REST_ASPECT).abs() < 1e-12);
        // The area is that of the configured diameter's circle.
        let r = 0.5 * h.config().vein_diameter;
        assert!((v.rest_area() - PI * r * r).abs() < 1e-15);
        let a = h.artery();
        assert_eq!(a.half_width(), a.half_height());
        let acute = anatomy(VeinState::Acute);
        assert_eq!(acute.vein().half_width(), acute.vein().half_height());
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
