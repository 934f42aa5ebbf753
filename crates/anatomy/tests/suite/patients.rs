//! Patient files: bad input is refused with an error naming the key
//! (issue 12), and the variants and queries behave.

use echothigh_anatomy::{Anatomy, AnatomyError, Patient, ProbePose, StructureId, Vec3};

#[test]
fn unknown_key_is_refused_naming_it() {
    let e = Patient::from_toml_str("preset = \"obese\"\nfat_thicknes_distal = 0.03\n").unwrap_err();
    assert!(matches!(e, AnatomyError::Parse(_)));
    assert!(e.to_string().contains("fat_thicknes_distal"), "{e}");
}

#[test]
fn negative_thickness_is_refused_naming_the_key() {
    let e = Patient::from_toml_str("fat_thickness_distal = -0.002\n").unwrap_err();
    assert!(
        matches!(
            e,
            AnatomyError::InvalidValue {
                key: "fat_thickness_distal",
                ..
            }
        ),
        "{e}"
    );
    let e = Patient::from_toml_str("skin_thickness = -1e-3\n").unwrap_err();
    assert!(e.to_string().contains("patient.skin_thickness"), "{e}");
}

#[test]
fn a_vessel_outside_the_leg_is_refused_naming_what_places_it() {
    // Three times the muscle depth sends the deep vessels through the
    // femur or out of a 0.50 m thigh (the profunda at 3 × 55 mm).
    let p = Patient::from_toml_str("muscle_depth_scale = 3.0\n").unwrap();
    let e = Anatomy::new(p).unwrap_err();
    match &e {
        AnatomyError::StructureOutside { keys, .. } => {
            assert!(keys.contains("muscle_depth_scale"), "{e}")
        }
        other => panic!("expected StructureOutside, got {other}"),
    }
}

#[test]
fn s_beyond_the_leg_is_refused() {
    let a = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
    let e = a
        .section(&ProbePose::transverse(a.length() + 1e-3, 0.0))
        .unwrap_err();
    assert!(
        matches!(e, AnatomyError::OutsideLeg { what: "s", .. }),
        "{e}"
    );
    assert!(a.section(&ProbePose::transverse(-1e-3, 0.0)).is_err());
    assert!(a
        .section(&ProbePose {
            s: 0.2,
            theta: 0.0,
            tilt: 1.2,
            spin: 0.0
        })
        .is_err());
}

#[test]
fn variants_appear_only_when_switched_on() {
    let plain = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
    assert!(plain.tube(StructureId::Fv2).is_none() && plain.lymph_node().is_none());
    let p = Patient::from_toml_str("duplicated_fv = true\nlymph_node = true\n").unwrap();
    let a = Anatomy::new(p).unwrap();
    let mid = a
        .section(&a.site_pose(echothigh_anatomy::Site::FvMid))
        .unwrap();
    assert!(
        mid.get(StructureId::Fv2).is_some(),
        "fv2 missing at mid-thigh"
    );
    let node = a.lymph_node().unwrap();
    let s = echothigh_anatomy::frame::s_of(&node.centre);
    let sec = a
        .section(&a.pose_over(s, StructureId::Cfv).unwrap())
        .unwrap();
    let n = sec
        .get(StructureId::LymphNode)
        .expect("node in the section through its centre");
    // Cut through its centre by a nearly transverse plane: its semi-axes in
    // the plane are the two short ones (5 and 4 mm) to within the plane's
    // tilt from transverse (the skin's slope, < 0.1 rad: cos > 0.995).
    let mut r = n.ellipse.radii;
    r.sort_by(f64::total_cmp);
    assert!(
        (r[0] - 4e-3).abs() < 0.1e-3 && (r[1] - 5e-3).abs() < 0.1e-3,
        "{r:?}"
    );
}

#[test]
fn femur_depth_along_a_ray_through_its_centre_is_centre_distance_minus_radius() {
    let a = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
    let s = 0.2;
    let femur = a.tube(StructureId::Femur).unwrap().cross_section(s);
    let o = a.skin_point(s, -0.3).unwrap();
    let dir = Vec3::new(femur.x - o.x, femur.y - o.y, 0.0);
    let expect = dir.norm() - femur.r1;
    let got = a.femur_depth(s, -0.3, Some(dir)).unwrap().unwrap();
    // Bisection to 1 µm.
    assert!((got - expect).abs() < 2e-6, "{got} vs {expect}");
    // The femur lies lateral: straight down from the anterior line at
    // mid-thigh the ray passes medial to it (reference row 13).
    assert!(a
        .femur_depth(s, 0.0, Some(Vec3::new(0.0, -1.0, 0.0)))
        .unwrap()
        .is_none());
    assert!(a.contains(&(o - 1e-3 * a.skin_normal(s, -0.3).unwrap())));
}
