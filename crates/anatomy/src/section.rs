//! The probe's image plane and the section of the anatomy in it.
//!
//! **Image convention** (DESIGN.md §7; AIUM/radiological convention for a
//! transverse view, probe marker towards the patient's right, shown on the
//! screen's left): depth grows down the image from the probe's face, and the
//! image's right is the **patient's left**. On this right leg the patient's
//! left is medial, so in every transverse view — from the front or from
//! behind the knee — the image's right is the medial side. Precisely, the
//! lateral axis `u` is the skin's transverse tangent of increasing θ when
//! `cos θ ≥ 0` (front half, anterior approach) and of decreasing θ
//! otherwise (back half, e.g. the popliteal fossa from behind); the choice
//! flips at the medial and lateral faces (θ = ±π/2), where no transverse
//! direction points to the patient's left.
//!
//! **Pose**: `s` and `θ` of the probe's face centre on the skin, then `tilt`
//! (rad; rocking about `u`, positive aims the beam distally, towards the
//! knee) and `spin` (rad; rotation about the beam, positive turns the
//! image's right towards distal). `tilt = spin = 0` is the transverse view
//! with the probe held normal to the skin.

use crate::cut::Ellipse;
use crate::error::AnatomyError;
use crate::frame::Vec3;
use crate::structure::{Kind, StructureId};
use std::str::FromStr;

/// Largest |tilt| and |spin| accepted (rad): 60°. Beyond, the plane nears a
/// longitudinal view, whose cut of a vessel is a band, not an ellipse.
pub const MAX_ANGLE: f64 = std::f64::consts::FRAC_PI_3;

/// Where the probe is and how it is held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbePose {
    /// Face centre: m below the inguinal ligament.
    pub s: f64,
    /// Face centre: angle around the leg (rad; 0 anterior, +medial).
    pub theta: f64,
    /// Rocking about the image's lateral axis (rad; + aims distally).
    pub tilt: f64,
    /// Rotation about the beam (rad; + turns the image's right distally).
    pub spin: f64,
}

impl ProbePose {
    /// The transverse view at `(s, θ)`, probe normal to the skin.
    pub fn transverse(s: f64, theta: f64) -> ProbePose {
        ProbePose {
            s,
            theta,
            tilt: 0.0,
            spin: 0.0,
        }
    }
}

/// The image plane in the leg frame: the probe face's centre on the skin
/// and the orthonormal image axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImagePlane {
    /// Face centre on the skin (m).
    pub origin: Vec3,
    /// Unit vector of the image's right (lateral axis `u`).
    pub lateral: Vec3,
    /// Unit vector of increasing depth (the beam, `w`).
    pub depth: Vec3,
    /// Unit normal of the plane, `u × w` (the elevation direction).
    pub normal: Vec3,
}

impl ImagePlane {
    /// The point at `(lateral, depth)` (m) of the image, in the leg frame.
    pub fn point(&self, lateral: f64, depth: f64) -> Vec3 {
        self.origin + lateral * self.lateral + depth * self.depth
    }

    /// Image coordinates `(lateral, depth)` (m) of the projection of `p`.
    pub fn coordinates(&self, p: &Vec3) -> (f64, f64) {
        let d = p - self.origin;
        (d.dot(&self.lateral), d.dot(&self.depth))
    }
}

/// One structure cut by the image plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionStructure {
    /// Which structure.
    pub id: StructureId,
    /// What it is.
    pub kind: Kind,
    /// The cut ellipse in image coordinates (m).
    pub ellipse: Ellipse,
    /// `s` (m) where the plane crosses the structure's centreline.
    pub s: f64,
}

/// The section under a probe.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// The probe's pose.
    pub pose: ProbePose,
    /// The image plane.
    pub plane: ImagePlane,
    /// Depth (m) of the skin's inner surface along the beam at the centre.
    pub skin_depth: f64,
    /// Depth (m) of the muscular fascia (fascia lata; the floor of the
    /// subcutaneous fat and of the saphenous compartment) along the beam at
    /// the centre.
    pub fascia_depth: f64,
    /// The structures cut, sorted by depth.
    pub structures: Vec<SectionStructure>,
}

impl Section {
    /// The cut of structure `id`, if present (the first by depth).
    pub fn get(&self, id: StructureId) -> Option<&SectionStructure> {
        self.structures.iter().find(|x| x.id == id)
    }
}

/// The named exam sites (DESIGN.md §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Site {
    /// Common femoral vein between the ligament and the SFJ.
    Cfv,
    /// Saphenofemoral junction (0.015 knee_s = 6 mm below it: the GSV's mouth
    /// beside the CFV, below the plane's tilt from the groin's taper).
    Sfj,
    /// Femoral vein just below the profunda confluence (FV and DFV both seen).
    FvProximal,
    /// Femoral vein at mid-thigh (adductor canal).
    FvMid,
    /// Femoral vein in the distal adductor canal.
    FvDistal,
    /// Popliteal vein behind the knee, probe from behind.
    Popliteal,
}

impl Site {
    /// All sites, groin to knee.
    pub const ALL: [Site; 6] = [
        Site::Cfv,
        Site::Sfj,
        Site::FvProximal,
        Site::FvMid,
        Site::FvDistal,
        Site::Popliteal,
    ];

    /// The site's name (`cfv`, `sfj`, `fv-proximal`, `fv-mid`, `fv-distal`, `popliteal`).
    pub fn name(self) -> &'static str {
        match self {
            Site::Cfv => "cfv",
            Site::Sfj => "sfj",
            Site::FvProximal => "fv-proximal",
            Site::FvMid => "fv-mid",
            Site::FvDistal => "fv-distal",
            Site::Popliteal => "popliteal",
        }
    }

    /// The vein the probe is centred on at this site.
    pub fn target(self) -> StructureId {
        match self {
            Site::Cfv | Site::Sfj => StructureId::Cfv,
            Site::FvProximal | Site::FvMid | Site::FvDistal => StructureId::Fv,
            Site::Popliteal => StructureId::Pv,
        }
    }
}

impl FromStr for Site {
    type Err = AnatomyError;
    fn from_str(s: &str) -> Result<Site, AnatomyError> {
        Site::ALL
            .into_iter()
            .find(|x| x.name() == s)
            .ok_or_else(|| AnatomyError::UnknownSite(s.to_string()))
    }
}
