//! Prints the section at every exam site for every preset, then the wall
//! time of one `Anatomy::section` call at mid-thigh (median of 9 batches of
//! 200 calls; an indication for the imaging thread, not a benchmark)
//! (`cargo run -p echothigh-anatomy --example sites`; the dev profile builds this crate at opt-level 3).

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
    let a = Anatomy::new(Patient::preset("lean-male")?)?;
    let pose = a.site_pose(Site::FvMid);
    let mut batches: Vec<f64> = (0..9)
        .map(|_| {
            let t = std::time::Instant::now();
            for _ in 0..200 {
                std::hint::black_box(a.section(std::hint::black_box(&pose)).unwrap());
            }
            t.elapsed().as_secs_f64() / 200.0
        })
        .collect();
    batches.sort_by(f64::total_cmp);
    println!(
        "section() at fv-mid: median {:.1} µs per call",
        batches[4] * 1e6
    );
    Ok(())
}
