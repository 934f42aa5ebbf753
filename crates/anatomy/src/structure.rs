//! Structure ids and kinds (DESIGN.md §7 vessel ids), and the two shapes
//! every structure is one of: a [`Tube`] around a centreline parametrised
//! by `s`, or an [`Ellipsoid`].
//!
//! A tube is defined by its **transverse** cross-sections: at each `s` in
//! its range, the ellipse with centre `(x(s), y(s))`, semi-axes `r1(s)`
//! (along the in-plane direction at angle `ω(s)` from `+x`) and `r2(s)`.
//! A vessel is a circular tube of true radius `r(s)` (its normal section, the
//! size ultrasound measures): inclined by α to the leg's axis, its transverse
//! section is the ellipse with `r2 = r` across the inclination and
//! `r1 = r / cos α` along it ([`Tube::tabulate_vessel`]); any plane then
//! cuts it in an ellipse whose smaller semi-axis is `r`.
//! The centreline and radii are tabulated every [`SAMPLE_STEP`] from their
//! defining functions (`crate::vessels`) and read back by Catmull–Rom
//! (centre) and linear (radii, ω) interpolation.

use crate::frame::Vec3;
use nalgebra::{Matrix3, Vector3};

/// Tabulation step of the tubes along `s` (m): 0.5 mm.
pub const SAMPLE_STEP: f64 = 5e-4;

/// Identifier of an anatomical structure (the ids of the `anatomy` JSON;
/// serialized as [`StructureId::as_str`]).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum StructureId {
    /// Common femoral vein.
    Cfv,
    /// Common femoral artery.
    Cfa,
    /// Great saphenous vein.
    Gsv,
    /// Deep femoral (profunda) vein.
    Dfv,
    /// Deep femoral (profunda) artery.
    Dfa,
    /// Femoral vein.
    Fv,
    /// Femoral (superficial femoral) artery.
    Fa,
    /// Popliteal vein.
    Pv,
    /// Popliteal artery.
    Pa,
    /// Duplicated femoral vein (variant).
    Fv2,
    /// Femur.
    Femur,
    /// Tibia (below the knee joint line).
    Tibia,
    /// Sartorius muscle (the adductor canal's roof).
    Sartorius,
    /// Inguinal lymph node (variant).
    LymphNode,
}

impl StructureId {
    /// The id as printed (`cfv`, `lymph_node`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            StructureId::Cfv => "cfv",
            StructureId::Cfa => "cfa",
            StructureId::Gsv => "gsv",
            StructureId::Dfv => "dfv",
            StructureId::Dfa => "dfa",
            StructureId::Fv => "fv",
            StructureId::Fa => "fa",
            StructureId::Pv => "pv",
            StructureId::Pa => "pa",
            StructureId::Fv2 => "fv2",
            StructureId::Femur => "femur",
            StructureId::Tibia => "tibia",
            StructureId::Sartorius => "sartorius",
            StructureId::LymphNode => "lymph_node",
        }
    }
}

/// What a structure is (the `kind` of the `anatomy` JSON).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// A deep vein (runs with an artery): cfv, fv, dfv, pv, fv2.
    DeepVein,
    /// A superficial vein (no companion artery): gsv.
    SuperficialVein,
    /// An artery.
    Artery,
    /// Bone.
    Bone,
    /// Muscle (landmark).
    Muscle,
    /// Lymph node.
    LymphNode,
}

impl Kind {
    /// The kind as printed (`deep_vein`, `superficial_vein`, `artery`,
    /// `bone`, `muscle`, `lymph_node`).
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::DeepVein => "deep_vein",
            Kind::SuperficialVein => "superficial_vein",
            Kind::Artery => "artery",
            Kind::Bone => "bone",
            Kind::Muscle => "muscle",
            Kind::LymphNode => "lymph_node",
        }
    }

    /// Whether this is a vessel (a vein or an artery).
    pub fn is_vessel(self) -> bool {
        matches!(self, Kind::DeepVein | Kind::SuperficialVein | Kind::Artery)
    }
}

/// One transverse cross-section of a tube: centre `(x, y)` (m), semi-axes
/// `r1`, `r2` (m) and the angle `ω` (rad) of the `r1` axis from `+x`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrossSection {
    /// Centre x (m, lateral).
    pub x: f64,
    /// Centre y (m, anterior).
    pub y: f64,
    /// Semi-axis along the direction at ω (m).
    pub r1: f64,
    /// Semi-axis perpendicular to it (m).
    pub r2: f64,
    /// Angle of the r1 axis from +x in the transverse plane (rad).
    pub omega: f64,
}

/// A structure swept along `s` (vessels, bones, the sartorius band).
#[derive(Debug, Clone, PartialEq)]
pub struct Tube {
    id: StructureId,
    kind: Kind,
    s0: f64,
    s1: f64,
    closed_end: bool,
    samples: Vec<CrossSection>,
}

impl Tube {
    /// Tabulates `f(s)` every [`SAMPLE_STEP`] over `[s0, s1]` (both ends
    /// sampled). The tube holds `s ∈ [s0, s1)`, or `[s0, s1]` when
    /// `closed_end` (a tube that ends at the end of the model).
    pub fn tabulate(
        id: StructureId,
        kind: Kind,
        s0: f64,
        s1: f64,
        closed_end: bool,
        f: impl Fn(f64) -> CrossSection,
    ) -> Tube {
        let n = ((s1 - s0) / SAMPLE_STEP).ceil().max(1.0) as usize;
        let samples = (0..=n)
            .map(|i| f(s0 + (s1 - s0) * i as f64 / n as f64))
            .collect();
        Tube {
            id,
            kind,
            s0,
            s1,
            closed_end,
            samples,
        }
    }

    /// Tabulates a vessel from its centre `f(s)` (m, transverse x, y) and
    /// true radius `r(s)` (m): the transverse section is the ellipse with
    /// semi-axes `r √(1 + |c'|²)` along `c' = d(x, y)/ds` (`1/cos α`) and
    /// `r` across it; `c'` by central differences of `f` (step 0.1 mm).
    /// ω is unwrapped modulo π between samples so that it interpolates.
    pub fn tabulate_vessel(
        id: StructureId,
        kind: Kind,
        s0: f64,
        s1: f64,
        closed_end: bool,
        f: impl Fn(f64) -> (nalgebra::Vector2<f64>, f64),
    ) -> Tube {
        let mut last_omega: Option<f64> = None;
        let mut tube = Tube::tabulate(id, kind, s0, s1, closed_end, |s| {
            let (c, r) = f(s);
            let h = 1e-4;
            let slope = (f(s + h).0 - f(s - h).0) / (2.0 * h);
            CrossSection {
                x: c.x,
                y: c.y,
                r1: r * (1.0 + slope.norm_squared()).sqrt(),
                r2: r,
                omega: slope.y.atan2(slope.x),
            }
        });
        for cs in &mut tube.samples {
            if let Some(prev) = last_omega {
                let d = (cs.omega - prev + std::f64::consts::FRAC_PI_2)
                    .rem_euclid(std::f64::consts::PI)
                    - std::f64::consts::FRAC_PI_2;
                cs.omega = prev + d;
            }
            last_omega = Some(cs.omega);
        }
        tube
    }

    /// The structure's id.
    pub fn id(&self) -> StructureId {
        self.id
    }

    /// The structure's kind.
    pub fn kind(&self) -> Kind {
        self.kind
    }

    /// The range of `s` (m) the tube spans: `[start, end)` (or closed, see
    /// [`Tube::tabulate`]).
    pub fn s_range(&self) -> (f64, f64) {
        (self.s0, self.s1)
    }

    /// Whether the tube exists at `s`.
    pub fn exists_at(&self, s: f64) -> bool {
        s >= self.s0 && (s < self.s1 || (self.closed_end && s <= self.s1))
    }

    fn locate(&self, s: f64) -> (usize, f64) {
        let n = self.samples.len() - 1;
        let u = ((s - self.s0) / (self.s1 - self.s0) * n as f64).clamp(0.0, n as f64);
        let i = (u.floor() as usize).min(n.saturating_sub(1));
        (i, u - i as f64)
    }

    /// The cross-section at `s` (clamped to the tube's range): centre by
    /// uniform Catmull–Rom through the samples, radii and ω linearly.
    pub fn cross_section(&self, s: f64) -> CrossSection {
        let n = self.samples.len() - 1;
        if n == 0 {
            return self.samples[0];
        }
        let (i, t) = self.locate(s);
        let p = |k: isize| self.samples[k.clamp(0, n as isize) as usize];
        let (p0, p1, p2, p3) = (
            p(i as isize - 1),
            p(i as isize),
            p(i as isize + 1),
            p(i as isize + 2),
        );
        let cr = |a: f64, b: f64, c: f64, d: f64| {
            0.5 * (2.0 * b
                + (-a + c) * t
                + (2.0 * a - 5.0 * b + 4.0 * c - d) * t * t
                + (-a + 3.0 * b - 3.0 * c + d) * t * t * t)
        };
        let lerp = |a: f64, b: f64| a + (b - a) * t;
        CrossSection {
            x: cr(p0.x, p1.x, p2.x, p3.x),
            y: cr(p0.y, p1.y, p2.y, p3.y),
            r1: lerp(p1.r1, p2.r1),
            r2: lerp(p1.r2, p2.r2),
            omega: lerp(p1.omega, p2.omega),
        }
    }

    /// Centre of the cross-section at `s` in the leg frame (m).
    pub fn centre(&self, s: f64) -> Vec3 {
        let c = self.cross_section(s);
        Vec3::new(c.x, c.y, -s)
    }

    /// The smaller semi-axis at `s` (m): a vessel's true radius, the
    /// sartorius' half-thickness, a bone's radius.
    pub fn radius(&self, s: f64) -> f64 {
        let c = self.cross_section(s);
        c.r1.min(c.r2)
    }

    /// `d(centre)/ds` at `s` (central difference over one sample step;
    /// the z component is −1).
    pub fn axis_derivative(&self, s: f64) -> Vec3 {
        let h = 0.5 * SAMPLE_STEP;
        let (a, b) = ((s - h).max(self.s0), (s + h).min(self.s1));
        (self.centre(b) - self.centre(a)) / (b - a)
    }
}

/// An ellipsoid (the lymph node): centre (m), unit axes as the columns of
/// `axes`, semi-axes (m).
#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    /// Structure id.
    pub id: StructureId,
    /// Kind.
    pub kind: Kind,
    /// Centre in the leg frame (m).
    pub centre: Vec3,
    /// Orthonormal axes (columns).
    pub axes: Matrix3<f64>,
    /// Semi-axes along the columns of `axes` (m).
    pub semi_axes: Vector3<f64>,
}

#[cfg(test)]
mod id_tests {
    use super::StructureId;

    /// The serialized id is the printed one (the live state's `vein`, the
    /// `anatomy` JSON), for every id, and parses back.
    #[test]
    fn serialized_ids_are_the_printed_ones() {
        use StructureId::*;
        for id in [
            Cfv, Cfa, Gsv, Dfv, Dfa, Fv, Fa, Pv, Pa, Fv2, Femur, Tibia, Sartorius, LymphNode,
        ] {
            let j = serde_json::to_string(&id).unwrap();
            assert_eq!(j, format!("\"{}\"", id.as_str()));
            assert_eq!(serde_json::from_str::<StructureId>(&j).unwrap(), id);
        }
    }
}
