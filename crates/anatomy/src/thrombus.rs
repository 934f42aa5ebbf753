//! Thrombus segments on named veins (issue 13): what a case file writes
//! (`[[thrombus]]`), its validation against one patient's anatomy, and the
//! parameters of each kind at full weight.
//!
//! A segment lies on one vein (`cfv`, `fv`, `pv`, `gsv`, `dfv` — alias
//! `profunda` —, `fv2`) between `s_start` and `s_end` (m below the inguinal
//! ligament, along the vein's own `s` range; `s_start` is the proximal end).
//! Its weight along `s` rises from 0 to 1 over `transition` (m), centred on
//! each end (½ at the end itself, so the ground truth's extent is the
//! half-weight extent; "the transition at each end is gradual over a few
//! millimetres", issue 13). The blend of the weights into the lumen's state
//! at one `s` is [`crate::lumen_state`].
//!
//! Kinds and their numbers (sources: `../shared/reference/cus-exam-fidelity.md`,
//! "the reference" below):
//! - `acute_occlusive`: the vein distended (default diameter ×1.18, reference
//!   row 21: "larger than normal, with wide overlap", Hertzberg 1997), the
//!   lumen full of thrombus that is spongy — deforms but never coapts
//!   (area −20 % at most, row 23) —, content echo by default −46 dB re
//!   muscle (near-anechoic, "often looks like blood", row 22);
//! - `acute_non_occlusive`: a mural thrombus filling `fill` of the lumen
//!   (default 0.5), the rest blood that compresses around it ("partial
//!   compression with colour around the thrombus", row 25, SIDV);
//! - `free_floating`: occlusive where attached, with a free proximal `tail`
//!   (m, default 20 mm; estimate) floating in the lumen (filling `fill`,
//!   default 0.35; estimate) that must not be compressed hard (row 25,
//!   abcvascular);
//! - `chronic`: post-thrombotic change: vein normal or smaller (default
//!   ×0.85, row 24), thick wall (1.5 mm, row 24), fibrous synechiae filling
//!   `1 − recanalized` of the lumen (default `recanalized` 0.5: "fully
//!   filled chronic veins are the exception", §4 item 2), rigid (area −5 %
//!   at most, row 24), the recanalized channels compressing only partly.

use crate::anatomy::Anatomy;
use crate::error::AnatomyError;
use crate::structure::{Kind, StructureId};
use serde::{Deserialize, Serialize};

/// Default transition length at each end (m): 4 mm ("a few millimetres").
pub const DEFAULT_TRANSITION: f64 = 4e-3;
/// Default diameter factor of an acute occlusive segment (reference row 21).
pub const ACUTE_DISTENSION: f64 = 1.18;
/// Default diameter factor of a chronic segment (reference row 24).
pub const CHRONIC_DISTENSION: f64 = 0.85;
/// Default content echo of acute thrombus (dB re muscle): near-anechoic,
/// 4 dB above blood's −50 dB (reference row 22 and §4 item 2: "draw acute
/// content from about −50 to −25 dB with most cases near-anechoic").
pub const ACUTE_ECHO_DB: f64 = -46.0;
/// Default content echo of chronic fibrous material (dB re muscle): the
/// previous chronic value, −14 dB (reference row 24).
pub const CHRONIC_ECHO_DB: f64 = -14.0;

/// What a thrombus segment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThrombusKind {
    /// Acute, filling the whole lumen.
    AcuteOcclusive,
    /// Acute, filling part of the lumen (mural).
    AcuteNonOcclusive,
    /// Acute with a free-floating proximal tail.
    FreeFloating,
    /// Chronic post-thrombotic change, partly recanalized.
    Chronic,
}

impl ThrombusKind {
    /// Every kind.
    pub const ALL: [ThrombusKind; 4] = [
        ThrombusKind::AcuteOcclusive,
        ThrombusKind::AcuteNonOcclusive,
        ThrombusKind::FreeFloating,
        ThrombusKind::Chronic,
    ];

    /// The name written in case files (`acute_occlusive`, …).
    pub fn name(self) -> &'static str {
        match self {
            ThrombusKind::AcuteOcclusive => "acute_occlusive",
            ThrombusKind::AcuteNonOcclusive => "acute_non_occlusive",
            ThrombusKind::FreeFloating => "free_floating",
            ThrombusKind::Chronic => "chronic",
        }
    }

    /// Whether the thrombus is acute (a DVT to treat) rather than chronic.
    pub fn is_acute(self) -> bool {
        self != ThrombusKind::Chronic
    }
}

/// One `[[thrombus]]` entry of a case file, as written (SI units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrombusSpec {
    /// The vein: `cfv`, `fv`, `pv`, `gsv`, `dfv` (or `profunda`), `fv2`.
    pub vein: String,
    /// Proximal end (m below the inguinal ligament).
    pub s_start: f64,
    /// Distal end (m below the inguinal ligament), > `s_start`.
    pub s_end: f64,
    /// `acute_occlusive`, `acute_non_occlusive`, `free_floating`, `chronic`.
    pub kind: String,
    /// Fraction of the lumen's area the thrombus fills: non-occlusive
    /// (default 0.5, in [0.1, 0.9]) and the free-floating tail (default 0.35).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<f64>,
    /// Chronic: fraction of the lumen recanalized (open), in [0, 0.9]; default 0.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recanalized: Option<f64>,
    /// Free-floating: length (m) of the free proximal tail, default 0.02,
    /// in [5 mm, segment length − 5 mm].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tail: Option<f64>,
    /// Mean backscatter of the content relative to muscle (dB), in [−60, 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub echo_db: Option<f64>,
    /// Diameter relative to the healthy vein, in [0.6, 1.6]: acute default
    /// 1.18 (non-occlusive 1 + 0.18 fill), chronic 0.85.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distension: Option<f64>,
    /// Transition length (m) at each end, in [1, 10] mm; default 4 mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transition: Option<f64>,
}

/// A validated segment (every default filled in).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thrombus {
    /// The vein.
    pub vein: StructureId,
    /// Proximal end (m).
    pub s_start: f64,
    /// Distal end (m).
    pub s_end: f64,
    /// The kind.
    pub kind: ThrombusKind,
    /// Fraction of the lumen filled (kind-dependent; see [`ThrombusSpec::fill`]).
    pub fill: f64,
    /// Chronic: open fraction of the lumen (0 for other kinds).
    pub recanalized: f64,
    /// Free-floating: free tail length (m; 0 for other kinds).
    pub tail: f64,
    /// Content echo (dB re muscle).
    pub echo_db: f64,
    /// Diameter factor.
    pub distension: f64,
    /// Transition length (m).
    pub transition: f64,
}

/// The vein named `name` in a case file (`profunda` is `dfv`).
pub fn vein_id(name: &str) -> Option<StructureId> {
    Some(match name {
        "cfv" => StructureId::Cfv,
        "fv" => StructureId::Fv,
        "pv" => StructureId::Pv,
        "gsv" => StructureId::Gsv,
        "dfv" | "profunda" => StructureId::Dfv,
        "fv2" => StructureId::Fv2,
        _ => return None,
    })
}

fn err(key: String, reason: impl Into<String>) -> AnatomyError {
    AnatomyError::Thrombus {
        key,
        reason: reason.into(),
    }
}

fn check(
    key: &str,
    field: &str,
    v: f64,
    lo: f64,
    hi: f64,
    what: &str,
) -> Result<f64, AnatomyError> {
    if !(v.is_finite() && v >= lo && v <= hi) {
        return Err(err(format!("{key}.{field}"), format!("= {v}: {what}")));
    }
    Ok(v)
}

impl ThrombusSpec {
    /// Validates this entry (written at `key`, e.g. `thrombus[2]`) against
    /// `anatomy`: the vein must exist for this patient, the extent lie in
    /// its `s` range, the kind be known, every number finite and in range,
    /// and no field given that the kind does not use.
    pub fn resolve(&self, key: &str, anatomy: &Anatomy) -> Result<Thrombus, AnatomyError> {
        let vein = vein_id(&self.vein).ok_or_else(|| {
            err(
                format!("{key}.vein"),
                format!(
                    "= \"{}\": unknown vein (known: cfv, fv, pv, gsv, dfv or profunda, fv2)",
                    self.vein
                ),
            )
        })?;
        let tube = anatomy.tube(vein).ok_or_else(|| {
            err(
                format!("{key}.vein"),
                format!(
                    "= \"{}\": this patient has no such vein (fv2 needs patient.duplicated_fv = true)",
                    self.vein
                ),
            )
        })?;
        debug_assert!(matches!(
            tube.kind(),
            Kind::DeepVein | Kind::SuperficialVein
        ));
        let kind = ThrombusKind::ALL
            .into_iter()
            .find(|k| k.name() == self.kind)
            .ok_or_else(|| {
                err(
                    format!("{key}.kind"),
                    format!(
                        "= \"{}\": unknown kind (known: acute_occlusive, acute_non_occlusive, free_floating, chronic)",
                        self.kind
                    ),
                )
            })?;
        let (lo, hi) = tube.s_range();
        let span = format!(
            "must lie on `{}` for this patient, within [{:.1}, {:.1}] mm",
            self.vein,
            lo * 1e3,
            hi * 1e3
        );
        // Ends written to 0.1 mm at a vein's end (e.g. 0.2667 for a hiatus
        // at 0.26666…) are taken as that end.
        let near = |v: f64| {
            if (lo - 1e-4..=hi + 1e-4).contains(&v) {
                v.clamp(lo, hi)
            } else {
                v
            }
        };
        let s_start = check(key, "s_start", near(self.s_start), lo, hi, &span)?;
        let s_end = check(key, "s_end", near(self.s_end), lo, hi, &span)?;
        let transition = check(
            key,
            "transition",
            self.transition.unwrap_or(DEFAULT_TRANSITION),
            1e-3,
            10e-3,
            "must be between 1 and 10 mm",
        )?;
        if s_end - s_start < 2.0 * transition {
            return Err(err(
                format!("{key}.s_end"),
                format!(
                    "= {s_end}: the segment must be at least twice its transition ({:.0} mm) long, after s_start = {s_start}",
                    2e3 * transition
                ),
            ));
        }
        let only = |field: &str, given: bool, kinds: &str| -> Result<(), AnatomyError> {
            if given {
                return Err(err(
                    format!("{key}.{field}"),
                    format!("is only for kind {kinds}, not {}", kind.name()),
                ));
            }
            Ok(())
        };
        use ThrombusKind::*;
        only(
            "fill",
            self.fill.is_some() && !matches!(kind, AcuteNonOcclusive | FreeFloating),
            "acute_non_occlusive or free_floating",
        )?;
        only(
            "recanalized",
            self.recanalized.is_some() && kind != Chronic,
            "chronic",
        )?;
        only(
            "tail",
            self.tail.is_some() && kind != FreeFloating,
            "free_floating",
        )?;
        let fill = match kind {
            AcuteOcclusive => 1.0,
            AcuteNonOcclusive => self.fill.unwrap_or(0.5),
            FreeFloating => self.fill.unwrap_or(0.35),
            Chronic => 0.0,
        };
        if matches!(kind, AcuteNonOcclusive | FreeFloating) {
            check(key, "fill", fill, 0.1, 0.9, "must be between 0.1 and 0.9")?;
        }
        let recanalized = match kind {
            Chronic => check(
                key,
                "recanalized",
                self.recanalized.unwrap_or(0.5),
                0.0,
                0.9,
                "must be between 0 and 0.9",
            )?,
            _ => 0.0,
        };
        let tail = match kind {
            FreeFloating => check(
                key,
                "tail",
                self.tail.unwrap_or(0.02),
                5e-3,
                s_end - s_start - 5e-3,
                "must be at least 5 mm and leave at least 5 mm of attached thrombus",
            )?,
            _ => 0.0,
        };
        let echo_default = if kind == Chronic {
            CHRONIC_ECHO_DB
        } else {
            ACUTE_ECHO_DB
        };
        let echo_db = check(
            key,
            "echo_db",
            self.echo_db.unwrap_or(echo_default),
            -60.0,
            0.0,
            "must be between -60 and 0 dB re muscle",
        )?;
        let dist_default = match kind {
            AcuteOcclusive | FreeFloating => ACUTE_DISTENSION,
            AcuteNonOcclusive => 1.0 + (ACUTE_DISTENSION - 1.0) * fill,
            Chronic => CHRONIC_DISTENSION,
        };
        let distension = check(
            key,
            "distension",
            self.distension.unwrap_or(dist_default),
            0.6,
            1.6,
            "must be between 0.6 and 1.6",
        )?;
        Ok(Thrombus {
            vein,
            s_start,
            s_end,
            kind,
            fill,
            recanalized,
            tail,
            echo_db,
            distension,
            transition,
        })
    }
}

impl Thrombus {
    /// Weight (0 to 1) of this segment at `s`: a smooth step of width
    /// `transition` centred on each end (C¹, `3t² − 2t³`).
    pub fn weight(&self, s: f64) -> f64 {
        let t = self.transition;
        let up = crate::interp::smoothstep((s - self.s_start) / t + 0.5);
        let down = crate::interp::smoothstep((self.s_end - s) / t + 0.5);
        up * down
    }

    /// Weight (0 to 1) of the free tail at `s` within the segment (0 for
    /// kinds without a tail): 1 from the proximal end to `s_start + tail`,
    /// then down over the transition.
    pub fn tail_weight(&self, s: f64) -> f64 {
        if self.kind != ThrombusKind::FreeFloating {
            return 0.0;
        }
        crate::interp::smoothstep((self.s_start + self.tail - s) / self.transition + 0.5)
    }

    /// Normalised position (0 to 1) of `s` along the free tail, from its
    /// attachment (`s_start + tail`, 0) to its free proximal tip
    /// (`s_start`, 1); 0 for kinds without a tail.
    pub fn tail_position(&self, s: f64) -> f64 {
        if self.kind != ThrombusKind::FreeFloating || self.tail <= 0.0 {
            return 0.0;
        }
        ((self.s_start + self.tail - s) / self.tail).clamp(0.0, 1.0)
    }
}
