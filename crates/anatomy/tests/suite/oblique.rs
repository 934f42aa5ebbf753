//! Oblique planes: a plane cut of a circular tube is an ellipse whose
//! smaller semi-axis is the tube's radius, whatever the tilt and spin.

use echothigh_anatomy::{Anatomy, Patient, ProbePose, Site, StructureId};

#[test]
fn any_plane_cuts_a_vessel_with_minor_semi_axis_equal_to_its_radius() {
    let a = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
    let base = a.site_pose(Site::FvMid);
    for (tilt, spin) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (-0.6, 0.4), (0.9, -0.9)] {
        let pose = ProbePose { tilt, spin, ..base };
        let sec = a.section(&pose).unwrap();
        for id in [StructureId::Fv, StructureId::Fa, StructureId::Gsv] {
            let x = sec
                .get(id)
                .unwrap_or_else(|| panic!("{} missing at tilt {tilt} spin {spin}", id.as_str()));
            let r = a.tube(id).unwrap().radius(x.s);
            let minor = x.ellipse.radii[0].min(x.ellipse.radii[1]);
            // Exact for the linearised tube; the tabulated slope (central
            // difference of the definition, 0.1 mm) and the Catmull–Rom
            // slope (0.5 mm samples) differ by O(h² c''') ≪ 1e-3 relative.
            assert!(
                (minor / r - 1.0).abs() < 1e-3,
                "{} tilt {tilt} spin {spin}: {minor} vs {r}",
                id.as_str()
            );
            // Its centre is the centreline point where the plane crosses it.
            let (lat, dep) = sec.plane.coordinates(&a.tube(id).unwrap().centre(x.s));
            assert!((lat - x.ellipse.lateral).abs() < 1e-9 && (dep - x.ellipse.depth).abs() < 1e-9);
        }
        // A tilted beam reaches the vein along a longer path: the FV's
        // major semi-axis grows at least as 1/cos of the tilt's share.
        if spin == 0.0 && tilt != 0.0 {
            let fv = sec.get(StructureId::Fv).unwrap().ellipse;
            assert!(fv.radii[0].max(fv.radii[1]) > a.tube(StructureId::Fv).unwrap().radius(0.2));
        }
    }
}
