//! `echothigh anatomy`: the transverse section of the 3D anatomy
//! (`echothigh-anatomy`) under a probe held normal to the skin, as JSON or
//! a table, so that the anatomy can be checked without pixels.
//!
//! JSON: `{"s_mm": …, "structures": [{"id", "kind", "depth_mm", "lateral_mm",
//! "radii_mm": [a, b]}]}`, sorted by depth; depth below the skin along the
//! beam, lateral positive towards the image's right (the patient's left, i.e.
//! medial on this right leg; `echothigh_anatomy::section`).

use anyhow::{bail, Context, Result};
use echothigh_anatomy::{Anatomy, Kind, Patient, ProbePose, Site, PRESETS};
use serde::Serialize;
use std::path::Path;

/// Arguments of `echothigh anatomy`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("where").required(true).args(["at", "site"])))]
pub struct Args {
    /// Patient: a preset (lean-male, average-female, obese) or a patient TOML file.
    #[arg(long, default_value = "lean-male")]
    pub patient: String,
    /// Probe position: mm below the inguinal ligament.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<f64>,
    /// Angle around the leg (degrees from the anterior line, + medial);
    /// default: centred over the deep vein at that level. Only with --at.
    #[arg(long, requires = "at", allow_hyphen_values = true)]
    pub angle: Option<f64>,
    /// Named exam site: cfv, sfj, fv-proximal, fv-mid, fv-distal, popliteal.
    #[arg(long)]
    pub site: Option<String>,
    /// A case (shipped name or case TOML file): its patient, and per vein
    /// its thrombus state at the section (`state` in the JSON). Not with --patient.
    #[arg(long)]
    pub case: Option<String>,
    /// Print JSON (else a table).
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct JsonStructure {
    id: &'static str,
    kind: &'static str,
    depth_mm: f64,
    lateral_mm: f64,
    radii_mm: [f64; 2],
    #[serde(skip_serializing_if = "Option::is_none")]
    state: Option<echothigh_anatomy::LumenState>,
}

#[derive(Serialize)]
struct JsonSection {
    s_mm: f64,
    structures: Vec<JsonStructure>,
}

/// Loads `--patient`: a preset name, else a TOML file.
pub fn load_patient(arg: &str) -> Result<Patient> {
    if PRESETS.contains(&arg) {
        return Ok(Patient::preset(arg)?);
    }
    let path = Path::new(arg);
    if !path.exists() {
        bail!(
            "--patient `{arg}` is neither a preset ({}) nor an existing file",
            PRESETS.join(", ")
        );
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {arg}"))?;
    Patient::from_toml_str(&text).with_context(|| format!("patient file {arg}"))
}

/// Runs `echothigh anatomy`.
pub fn run(args: Args) -> Result<()> {
    let case = match &args.case {
        Some(c) => {
            if args.patient != "lean-male" {
                bail!("--case sets the patient: drop --patient");
            }
            Some(super::cases::load_case(c)?)
        }
        None => None,
    };
    let anatomy = match &case {
        Some(c) => c.anatomy.clone(),
        None => {
            let patient = load_patient(&args.patient)?;
            Anatomy::new(patient).with_context(|| format!("patient {}", args.patient))?
        }
    };
    let pose = match (&args.site, args.at) {
        (Some(name), _) => anatomy.site_pose(name.parse::<Site>()?),
        (None, Some(at_mm)) => {
            let s = at_mm * 1e-3;
            anatomy.check_s("--at (m)", s)?;
            match args.angle {
                Some(deg) if !deg.is_finite() => bail!("--angle {deg} is not a finite angle"),
                Some(deg) => ProbePose::transverse(s, deg.to_radians()),
                None => anatomy.pose_over(s, anatomy.deep_vein_at(s))?,
            }
        }
        (None, None) => bail!("give --at or --site"),
    };
    let section = anatomy.section(&pose)?;
    let out = JsonSection {
        s_mm: pose.s * 1e3,
        structures: section
            .structures
            .iter()
            .map(|x| JsonStructure {
                id: x.id.as_str(),
                kind: x.kind.as_str(),
                depth_mm: x.ellipse.depth * 1e3,
                lateral_mm: x.ellipse.lateral * 1e3,
                radii_mm: [x.ellipse.radii[0] * 1e3, x.ellipse.radii[1] * 1e3],
                state: case.as_ref().and_then(|c| {
                    matches!(x.kind, Kind::DeepVein | Kind::SuperficialVein)
                        .then(|| c.thrombi.state(x.id, x.s))
                }),
            })
            .collect(),
    };
    if args.json {
        println!("{}", serde_json::to_string(&out)?);
    } else {
        println!(
            "s = {:.1} mm, angle = {:.1}° (patient {}); fascia at {:.1} mm",
            out.s_mm,
            pose.theta.to_degrees(),
            anatomy.patient().name,
            section.fascia_depth * 1e3
        );
        println!(
            "{:<11} {:<17} {:>9} {:>11} {:>15}",
            "id", "kind", "depth_mm", "lateral_mm", "radii_mm"
        );
        for x in &out.structures {
            let state = x.state.map_or(String::new(), |st| {
                format!(
                    "  thrombus {:.0} % (acute {:.2}, chronic {:.2})",
                    st.fill * 100.0,
                    st.acute,
                    st.chronic
                )
            });
            println!(
                "{:<11} {:<17} {:>9.1} {:>11.1} {:>7.1} {:>7.1}{state}",
                x.id, x.kind, x.depth_mm, x.lateral_mm, x.radii_mm[0], x.radii_mm[1]
            );
        }
    }
    Ok(())
}
