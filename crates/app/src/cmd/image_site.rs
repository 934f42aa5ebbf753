//! `echothigh image --patient P (--at S [--angle A] | --site NAME)`: the
//! probe's placement on the leg from the command line; the imaging anatomy
//! of the section there comes from
//! [`echothigh_runtime::section_image::section_anatomy`].

use crate::cmd::anatomy::load_patient;
use anyhow::{bail, Context, Result};
use echothigh_anatomy::{Anatomy, ProbePose, Site, Thrombi};
use echothigh_imaging::AnatomyConfig;

/// Where the probe is on the leg: a patient and a level (or a site).
#[derive(Debug, Clone)]
pub struct Placement {
    /// The patient's anatomy.
    pub anatomy: Anatomy,
    /// The probe's pose.
    pub pose: ProbePose,
}

/// Resolves `--patient`, `--at` (mm below the inguinal ligament),
/// `--angle` (degrees from the anterior line, + medial) and `--site`;
/// errors name the argument at fault.
pub fn place(
    patient: &str,
    at_mm: Option<f64>,
    angle_deg: Option<f64>,
    site: Option<&str>,
) -> Result<Placement> {
    let p = load_patient(patient)?;
    let anatomy = Anatomy::new(p).with_context(|| format!("patient {patient}"))?;
    place_on(anatomy, at_mm, angle_deg, site)
}

/// As [`place`] on an already built anatomy (a case's, `--case`).
pub fn place_on(
    anatomy: Anatomy,
    at_mm: Option<f64>,
    angle_deg: Option<f64>,
    site: Option<&str>,
) -> Result<Placement> {
    let pose = match (site, at_mm) {
        (Some(_), Some(_)) => bail!("give either --site or --at, not both"),
        (Some(name), None) => {
            if angle_deg.is_some() {
                bail!("--angle goes with --at (a site sets its own angle)");
            }
            let site: Site = name.parse().context("--site")?;
            anatomy.site_pose(site)
        }
        (None, Some(at)) => {
            let s = at * 1e-3;
            anatomy.check_s("--at (m)", s)?;
            match angle_deg {
                Some(deg) if !deg.is_finite() => bail!("--angle {deg} is not a finite angle"),
                Some(deg) => ProbePose::transverse(s, deg.to_radians()),
                None => anatomy.pose_over(s, anatomy.deep_vein_at(s))?,
            }
        }
        (None, None) => bail!("--patient and --case need --at or --site"),
    };
    Ok(Placement { anatomy, pose })
}

/// `base` with its layers, vessels and femur taken from the section under
/// the probe at `placement` (see
/// [`echothigh_runtime::section_image::section_anatomy`]).
pub fn section_anatomy(base: &AnatomyConfig, placement: &Placement) -> Result<AnatomyConfig> {
    echothigh_runtime::section_image::section_anatomy(base, &placement.anatomy, &placement.pose)
}

/// As [`section_anatomy`], each vein with its condition from `thrombi`
/// (a case's segments, `--case`) at the section.
pub fn case_section_anatomy(
    base: &AnatomyConfig,
    placement: &Placement,
    thrombi: &Thrombi,
) -> Result<AnatomyConfig> {
    echothigh_runtime::section_image::section_anatomy_with(
        base,
        &placement.anatomy,
        &placement.pose,
        Some(thrombi),
    )
}
