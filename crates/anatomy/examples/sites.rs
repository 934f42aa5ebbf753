//! Prints the section at every exam site for every preset
//! (`cargo run -p echothigh-anatomy --example sites`).

use echothigh_anatomy::{Anatomy, Patient, Site, PRESETS};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for name in PRESETS {
        let a = Anatomy::new(Patient::preset(name)?)?;
        for site in Site::ALL {
            let pose = a.site_pose(site);
            let sec = a.section(&pose)?;
            println!(
                "{name} {} s = {:.1} mm θ = {:.1}° fascia {:.1} mm",
                site.name(),
                pose.s * 1e3,
                pose.theta.to_degrees(),
                sec.fascia_depth * 1e3
            );
            for x in &sec.structures {
                let e = x.ellipse;
                println!(
                    "  {:<10} {:<16} depth {:6.1} lateral {:7.1} radii {:5.1} {:5.1}",
                    x.id.as_str(),
                    x.kind.as_str(),
                    e.depth * 1e3,
                    e.lateral * 1e3,
                    e.radii[0] * 1e3,
                    e.radii[1] * 1e3
                );
            }
        }
    }
    Ok(())
}
