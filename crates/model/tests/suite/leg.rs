//! The mesh on a patient's leg (issue 12): the skin follows the anatomy's
//! circumference profile, the anchors lie on the oblique femur, and the
//! adductor canal is stiffer.

use echothigh_anatomy::{frame, Anatomy, Patient, StructureId};
use echothigh_model::leg::{leg_theta, CANAL_HALF_ANGLE};
use echothigh_model::{ModelConfig, NoExtraForce, ThighModel};

fn leg_config(patient: &str) -> ModelConfig {
    let mut c = ModelConfig::default();
    c.thigh.patient = patient.into();
    c
}

/// The perimeter of each ring of nodes equals the patient's circumference
/// at its `s`, to within the chord error of the mesh resolution.
#[test]
fn ring_perimeters_follow_the_circumference_profile() {
    for patient in ["lean-male", "average-female", "obese"] {
        let c = leg_config(patient);
        let m = ThighModel::new(&c).unwrap();
        let mesh = m.mesh();
        let leg = mesh.leg().expect("a leg mesh");
        let shape = leg.anatomy().leg();
        let knee = leg.anatomy().levels().knee;
        let mut checked = 0;
        for iz in 0..mesh.n_z() {
            let z = c.thigh.z(iz);
            let s = leg.s_of_z(z);
            if s > 0.74 * knee {
                continue; // the popliteal fossa's hollow: not an ellipse
            }
            let nt = mesh.n_theta();
            let ring: Vec<_> = (0..nt)
                .map(|it| mesh.rest_positions()[mesh.node_index(it, iz)])
                .collect();
            let chords: Vec<f64> = (0..nt)
                .map(|i| (ring[(i + 1) % nt] - ring[i]).norm())
                .collect();
            let perimeter: f64 = chords.iter().sum();
            // The anatomy's circumference at s, from its semi-axes by
            // Ramanujan's second formula (relative error < 1e-9 here; the
            // semi-axes came from the profile by the first, < 1e-4).
            let (a, b) = shape.semi_axes(s);
            let h = ((a - b) / (a + b)).powi(2);
            let circumference =
                std::f64::consts::PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
            // A chord of length l on an arc of curvature κ falls short of the
            // arc by κ² l³ / 24 (+ O(l⁵)); summed, the polygon falls short by
            // at most κ_max² l_max² / 24 of the perimeter, κ_max = a/b² at the
            // end of the ellipse's major axis. The tolerance adds Ramanujan's
            // 1e-4 and the O(l⁵) term (a factor 1.1 on the bound).
            let kappa = a.max(b) / a.min(b).powi(2);
            let l_max = chords.iter().cloned().fold(0.0, f64::max);
            let bound = 1.1 * kappa * kappa * l_max * l_max / 24.0 + 1e-4;
            let shortfall = 1.0 - perimeter / circumference;
            assert!(
                shortfall > -1e-4 && shortfall < bound,
                "{patient} s = {s:.3}: ring perimeter {perimeter:.5} m vs circumference \
                 {circumference:.5} m (shortfall {shortfall:.2e}, bound {bound:.2e})"
            );
            // and the shortfall is not trivially small: the polygon is inscribed.
            assert!(
                shortfall > 0.0,
                "{patient} s = {s:.3}: polygon not inscribed"
            );
            checked += 1;
        }
        assert!(checked >= 10, "{patient}: only {checked} rings checked");
    }
}

/// Every node is on the anatomy's skin, every anchor on its inward normal
/// at the depth of the femur at the node's level, and the rest lengths vary along and around the leg
/// as the femur's position dictates.
#[test]
fn nodes_on_the_skin_and_rest_lengths_from_the_oblique_femur() {
    let c = leg_config("lean-male");
    let m = ThighModel::new(&c).unwrap();
    let mesh = m.mesh();
    let leg = mesh.leg().unwrap();
    let anatomy = Anatomy::new(Patient::preset("lean-male").unwrap()).unwrap();
    let femur = anatomy.tube(StructureId::Femur).unwrap();
    for k in 0..mesh.node_count() {
        let (theta, z) = mesh.theta_z(k);
        let s = leg.s_of_z(z);
        let p = leg.to_leg(&mesh.rest_positions()[k]);
        let skin = anatomy.skin_point(s, leg_theta(theta)).unwrap();
        assert!((p - skin).norm() < 1e-12, "node {k} off the skin");
        let a = leg.to_leg(&mesh.anchors()[k]);
        // The anchor lies on the inward normal at the distance from the
        // node to the femur's surface, measured in the node's plane.
        let cs = femur.cross_section(s);
        let to_bone = (p.x - cs.x).hypot(p.y - cs.y) - femur.radius(s);
        let rest = (p - a).norm();
        assert!(
            (rest - to_bone).abs() < 1e-12,
            "anchor {k}: {rest} vs {to_bone}"
        );
        let inward = (a - p) / rest;
        assert!(
            (inward + mesh.rest_normals()[k]).norm() < 1e-12,
            "anchor {k} off the normal"
        );
        // Rest length over the reference layer is what the mesh reports.
        let lambda = mesh.layer_scales()[k];
        assert!((lambda * c.thigh.tissue_thickness - rest).abs() < 1e-12);
    }
    // Around: the femur lies lateral of the axis, so at every ring the
    // medial layer (θ = π) is thicker than the lateral one (θ = 0), the
    // skin radii there being equal (the ellipse's symmetry). Along: the
    // femur comes towards the axis distally, so that difference shrinks.
    let nt = mesh.n_theta();
    let rest = |it: usize, iz: usize| {
        let k = mesh.node_index(it, iz);
        (mesh.rest_positions()[k] - mesh.anchors()[k]).norm()
    };
    let diff: Vec<f64> = (0..mesh.n_z())
        .map(|iz| rest(nt / 2, iz) - rest(0, iz))
        .collect();
    assert!(diff.iter().all(|&d| d > 0.0), "{diff:?}");
    // Ring 0 is the distal end (z = −L/2, s = centre_s + L/2).
    assert!(diff[mesh.n_z() - 1] > diff[0] + 0.02, "{diff:?}");
    // Femur centre x at the two end rings (obliquity 6°: x = tan 6° (k − s)).
    let (z0, z1) = (c.thigh.z(0), c.thigh.z(mesh.n_z() - 1));
    let dx = femur.cross_section(leg.s_of_z(z1)).x - femur.cross_section(leg.s_of_z(z0)).x;
    // Along: the femur runs from lateral (groin) to central (knee):
    // Δx = tan 6° × 0.30 m from the distal (z0) to the proximal (z1) end.
    let expect = 6f64.to_radians().tan() * c.thigh.length;
    assert!(
        (dx - expect).abs() < 1e-3,
        "femur obliquity {dx} vs {expect}"
    );
}

/// The adductor canal's band is stiffer: its factor peaks at
/// `canal_stiffness` over the femoral vein mid-canal and is 1 at the groin
/// and opposite the vessels; and under the same load a node over the canal
/// sinks less with `canal_stiffness = 1.5` than with 1.
#[test]
fn adductor_canal_is_stiffer_than_the_groin() {
    let c = leg_config("lean-male");
    let m = ThighModel::new(&c).unwrap();
    let leg = m.mesh().leg().unwrap();
    let a = leg.anatomy();
    let lv = a.levels();
    let s_mid = 0.5 * (lv.apex + lv.hiatus);
    let fv = a.tube(StructureId::Fv).unwrap();
    let th = frame::theta_of(&fv.centre(s_mid));
    assert!((leg.stiffness_factor(s_mid, th) - 1.5).abs() < 1e-12);
    assert_eq!(leg.stiffness_factor(0.5 * lv.sfj, th), 1.0);
    assert_eq!(
        leg.stiffness_factor(s_mid, th + CANAL_HALF_ANGLE + 0.01),
        1.0
    );
    assert_eq!(leg.stiffness_factor(lv.hiatus, th), 1.0);

    // The node nearest the femoral vein's angle at mid-canal.
    let z = leg.s_of_z(0.0) - s_mid; // z = centre_s − s
    let node = m.mesh().node_at(echothigh_model::leg::model_theta(th), z);
    let sink = |canal: f64| {
        let mut c = c.clone();
        c.thigh.canal_stiffness = canal;
        let mut m = ThighModel::new(&c).unwrap();
        let n = m.mesh().rest_normals()[node];
        m.external_forces_mut()[node] = -n * 2.0;
        for _ in 0..60 {
            m.step(0.05, &mut NoExtraForce);
        }
        (m.rest_positions()[node] - m.positions()[node]).dot(&n)
    };
    let (soft, hard) = (sink(1.0), sink(1.5));
    assert!(
        m.mesh().stiffness_factors()[node] > 1.2,
        "node not in the band"
    );
    // The membrane and the neighbours carry part of the load, so the ratio
    // lies between 1/1.5 (the spring alone) and 1.
    assert!(hard < soft && hard > soft / 1.5, "{hard} vs {soft}");
}

/// Errors name the key: an unknown preset, a segment off the femur.
#[test]
fn bad_leg_keys_are_named() {
    let mut c = leg_config("skinny");
    let e = ThighModel::new(&c).unwrap_err().to_string();
    assert!(e.contains("thigh.patient") && e.contains("skinny"), "{e}");
    c.thigh.patient = "lean-male".into();
    c.thigh.centre_s = 0.30; // 0.30 + 0.15 > knee_s 0.40
    let e = ThighModel::new(&c).unwrap_err().to_string();
    assert!(e.contains("thigh.centre_s"), "{e}");
}

/// The hand target sits on the skin along the normal, faces it, is the
/// identity at the anterior line of the straight mid-thigh, and refuses
/// a position beyond the leg naming it.
#[test]
fn hand_target_faces_the_skin() {
    let c = leg_config("lean-male");
    let m = ThighModel::new(&c).unwrap();
    let leg = m.mesh().leg().unwrap();
    let a = leg.anatomy();
    for &(s, th) in &[
        (0.05, 0.0),
        (0.2, 0.6),
        (0.3, -1.0),
        (0.36, std::f64::consts::PI),
    ] {
        let t = leg.hand_target(s, th, 0.004, 0.0).unwrap();
        let n = a.skin_normal(s, th).unwrap();
        let skin = leg.to_model(&a.skin_point(s, th).unwrap());
        assert!((t.position - (skin - n * 0.004)).norm() < 1e-12);
        // The tool's +y is the outward normal; its x is transverse (⊥ z).
        let y = t.orientation * nalgebra::Vector3::y();
        let x = t.orientation * nalgebra::Vector3::x();
        assert!((y - n).norm() < 1e-12 && x.z.abs() < 1e-12);
    }
    // Anterior line at mid-thigh: the normal is +y up to the leg's taper,
    // dr/ds = (dC/ds)/2π with the circumference falling 0.50 → 0.41 m over
    // s = 0.20 → 0.33 m (lean-male): a slope of ≈ 0.1 rad at most.
    let t = leg.hand_target(0.2, 0.0, 0.0, 0.0).unwrap();
    assert!(t.orientation.angle() < 0.1, "{}", t.orientation.angle());
    let e = leg.hand_target(0.9, 0.0, 0.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("outside the leg"), "{e}");
    assert!(leg.hand_target(0.2, f64::NAN, 0.0, 0.0).is_err());
}
