//! Force–indentation of the probe over the mid-thigh femoral vein of each
//! patient preset (issue 12): monotonic, and inside the band the leg's
//! per-node law implies relative to the calibrated cylinder.
//!
//! **Band.** On the leg a node's normal spring is the calibrated law at the
//! same strain on a layer `λ` times the reference and `φ` times stiffer
//! (`echothigh_model::leg`): `f_leg(x) = φ f(x/λ)`. The law `f` stiffens
//! with compression (convex, `f(0) = 0`), so for `λ ≥ 1`
//! `f(x)/λ ≤ f(x/λ) ≤ f(x)`: at the same indentation a node pushes back
//! between `φ/λ` and `φ` times its cylinder value. The membrane and the
//! shear ties respond to the same indentation as on the cylinder (ties ×φ),
//! factors 1 and φ, inside the same range since `φ ≥ 1`. So the probe's
//! force at the same indentation on the leg lies within `[min φ/λ, max φ]`
//! (over the nodes the face loads) times the cylinder's, measured in the
//! same run on the same mesh resolution.

use echothigh_anatomy::{Site, PRESETS};
use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use nalgebra::{Isometry3, Translation3};

/// Quasi-static force (N, along the probe's axis) at indentations 1..=10 mm
/// of the probe placed by `pose_at(depth)`: 20 steps of 10 ms per mm
/// (200 ms, ≥ 7 time constants of the slowest normal damper: `c/k` ≤ 10 ms
/// on the cylinder, ×2.8 for the thickest layer).
fn curve(model: &mut ThighModel, pose_at: impl Fn(f64) -> Isometry3<f64>) -> Vec<f64> {
    let mut pc = ProbeContact::new(model, Probe::default(), ContactParams::default()).unwrap();
    let h = 0.01;
    (1..=10)
        .map(|mm| {
            let pose = pose_at(mm as f64 * 1e-3);
            for _ in 0..20 {
                pc.step(model, &pose, h);
            }
            let (s, _) = pc.sample(model);
            assert!(s.in_contact, "no contact at {mm} mm");
            let axis = pose.rotation * Vec3::y();
            s.force.dot(&axis)
        })
        .collect()
}

fn config() -> ModelConfig {
    let mut c = ModelConfig::default();
    c.thigh.n_theta = 32; // the fig4 mesh: ~15 mm around, ~21 mm along
    c.thigh.n_z = 15;
    c
}

#[test]
fn force_indentation_per_patient_is_monotonic_and_in_band() {
    let mut cyl = ThighModel::new(&config()).unwrap();
    let top = config().thigh.semi_axis_y;
    let reference = curve(&mut cyl, |d| Probe::exam_pose(Vec3::new(0.0, top - d, 0.0)));
    for preset in PRESETS {
        let mut c = config();
        c.thigh.patient = preset.to_string();
        let knee = echothigh_anatomy::Patient::preset(preset).unwrap().knee_s;
        c.thigh.centre_s = 0.5 * knee; // mid-thigh at z = 0
        let mut m = ThighModel::new(&c).unwrap();
        let leg = m.mesh().leg().unwrap().clone();
        let site = leg.anatomy().site_pose(Site::FvMid);
        let target = |d: f64| leg.hand_target(site.s, site.theta, d, 0.0).unwrap();
        // φ/λ and φ over the nodes within one mesh spacing of the face.
        let face = target(0.0);
        let inv = face.orientation.inverse();
        let probe = Probe::default();
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for k in 0..m.node_count() {
            let p = inv * (m.rest_positions()[k] - face.position);
            if p.x.abs() <= probe.half_width + 0.015 && p.z.abs() <= probe.half_elevation + 0.021 {
                let (lam, phi) = (m.mesh().layer_scales()[k], m.mesh().stiffness_factors()[k]);
                assert!(
                    lam >= 1.0,
                    "{preset}: layer thinner than the reference under the face"
                );
                lo = lo.min(phi / lam);
                hi = hi.max(phi);
            }
        }
        let forces = curve(&mut m, |d| {
            let t = target(d);
            Isometry3::from_parts(Translation3::from(t.position), t.orientation)
        });
        for w in forces.windows(2) {
            assert!(w[1] > w[0], "{preset}: not monotonic {forces:?}");
        }
        for (i, (f, r)) in forces.iter().zip(&reference).enumerate() {
            let ratio = f / r;
            assert!(
                ratio >= lo && ratio <= hi,
                "{preset} at {} mm: {f:.2} N vs cylinder {r:.2} N, ratio {ratio:.3} outside [{lo:.3}, {hi:.3}]",
                i + 1
            );
        }
        eprintln!("{preset}: F(5 mm) = {:.2} N, F(10 mm) = {:.2} N (cylinder {:.2}, {:.2}); band [{lo:.3}, {hi:.3}]", forces[4], forces[9], reference[4], reference[9]);
    }
}
