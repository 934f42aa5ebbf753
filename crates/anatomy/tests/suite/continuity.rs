//! Continuity along the leg (issue 12): no structure's section jumps by more
//! than its radius over 1 mm of probe travel.

use echothigh_anatomy::{Anatomy, Patient, ProbePose, PRESETS};

#[test]
fn centrelines_move_less_than_their_radius_per_mm() {
    for p in PRESETS {
        let a = Anatomy::new(Patient::preset(p).unwrap()).unwrap();
        for t in a.tubes() {
            let (s0, s1) = t.s_range();
            let mut s = s0;
            while s + 1e-3 <= s1 {
                let jump = (t.centre(s + 1e-3) - t.centre(s)).xy().norm();
                let r = t.cross_section(s).r1.min(t.cross_section(s).r2);
                assert!(
                    jump < r,
                    "{p}: {} jumps {jump} m at s = {s} (radius {r})",
                    t.id().as_str()
                );
                s += 1e-3;
            }
        }
    }
}

#[test]
fn sections_change_continuously_as_the_probe_slides() {
    // A probe held at a fixed angle, slid 1 mm at a time from the groin to
    // the end of the leg, from the front (θ = 0.6, anteromedial) and from
    // behind (θ = π): every structure present in both frames moves less
    // than its smaller radius in the image.
    for p in PRESETS {
        let a = Anatomy::new(Patient::preset(p).unwrap()).unwrap();
        for theta in [0.6, std::f64::consts::PI] {
            let mut prev = a.section(&ProbePose::transverse(0.0, theta)).unwrap();
            let mut s = 1e-3;
            while s <= a.length() {
                let cur = a.section(&ProbePose::transverse(s, theta)).unwrap();
                for x in &cur.structures {
                    if let Some(y) = prev.get(x.id) {
                        let d = ((x.ellipse.lateral - y.ellipse.lateral).powi(2)
                            + (x.ellipse.depth - y.ellipse.depth).powi(2))
                        .sqrt();
                        let r = x.ellipse.radii[0].min(x.ellipse.radii[1]);
                        assert!(
                            d < r,
                            "{p} θ={theta}: {} jumps {d} m at s = {s}",
                            x.id.as_str()
                        );
                    }
                }
                prev = cur;
                s += 1e-3;
            }
        }
    }
}
