//! Acoustic shadow below the femur and anechoic vessel lumens.

use crate::common;
use common::*;
use echothigh_imaging::*;

#[test]
fn shadow_below_the_femur() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, _) = render_force(&mut r, 0.0, 0.0);
    let a = cfg.anatomy.clone();
    let centre = a.femur_top() + a.femur_radius;
    let depths = (centre - 2e-3, centre + 5e-3);
    let below = mean_db(
        &cfg,
        &frame,
        (a.femur_lateral - 6e-3, a.femur_lateral + 6e-3),
        depths,
    );
    let beside = mean_db(&cfg, &frame, (-19e-3, -15e-3), depths);
    assert!(beside - below >= 10.0, "shadow only {} dB", beside - below);
}

#[test]
fn vessel_lumens_are_anechoic() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, lumens) = render_force(&mut r, 0.0, 0.0);
    let muscle = mean_db(&cfg, &frame, (12e-3, 18e-3), (26e-3, 32e-3));
    for l in [lumens.vein, lumens.artery] {
        let h = 0.6 * l.half_width;
        let lumen = mean_db(
            &cfg,
            &frame,
            (l.lateral - h, l.lateral + h),
            (l.depth - 0.6 * l.half_height, l.depth + 0.6 * l.half_height),
        );
        assert!(
            muscle - lumen >= 20.0,
            "lumen contrast only {} dB",
            muscle - lumen
        );
    }
}

#[test]
fn enhancement_below_the_vein() {
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, lumens) = render_force(&mut r, 0.0, 0.0);
    let v = lumens.vein;
    let depths = (
        v.depth + v.half_height + 1.5e-3,
        v.depth + v.half_height + 4.5e-3,
    );
    let below = mean_db(&cfg, &frame, (v.lateral - 2e-3, v.lateral + 2e-3), depths);
    let beside = mean_db(&cfg, &frame, (-19.5e-3, -16e-3), depths);
    assert!(
        below - beside >= 2.0,
        "enhancement only {} dB",
        below - beside
    );
}

#[test]
fn the_femoral_cortex_is_specular() {
    // Issue 21: bright where its normal faces the beam, ≥ 20 dB dimmer where
    // it is parallel to it. Boxes of 0.6 mm just inside the cortex's outer
    // surface (where each beam line meets the bone first), at the polar
    // angle θ of the surface normal from the beam axis: θ = 0 (top) and
    // θ = 70° (the flank, near grazing), each relative to muscle at the same
    // depth away from the vessels, so that the beam's depth dependence
    // (focus, attenuation, TGC) cancels.
    let cfg = ImagingConfig::default();
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let (frame, _) = render_force(&mut r, 0.0, 0.0);
    let a = cfg.anatomy.clone();
    let (fu, rad) = (a.femur_lateral, a.femur_radius);
    let fd = a.femur_top() + rad;
    let relative = |theta: f64| {
        let rho = rad - 0.4e-3;
        let (u, d) = (fu + rho * theta.sin(), fd - rho * theta.cos());
        let h = 0.3e-3;
        let band = (d - h, d + h);
        mean_db(&cfg, &frame, (u - h, u + h), band)
            - mean_db(&cfg, &frame, (-19e-3, -16e-3), (d - 1e-3, d + 1e-3))
    };
    let facing = relative(0.0);
    let parallel = relative(70f64.to_radians());
    assert!(
        facing - parallel >= 20.0,
        "cortex facing the beam {facing:.1} dB, near parallel {parallel:.1} dB (re muscle)"
    );
}
