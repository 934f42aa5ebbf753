//! The image coupled to the physics (issue 7): pressing the physical model
//! to the default exam force collapses a healthy vein in the image's model
//! and leaves a thrombosed one open; the press reaches the asked force.

use echothigh_imaging::{FrameInput, Renderer, VeinState};
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::section::press_to_force;

#[test]
fn physics_press_collapses_only_the_healthy_vein() {
    let s = Scenario::default();
    let cfg = s.imaging_config();
    let bone = Renderer::new(&cfg, VeinState::Healthy)
        .unwrap()
        .anatomy()
        .unwrap()
        .femur_top();
    let mut physics = PhysicsSide::new(&s).unwrap();
    let press = press_to_force(&mut physics, &s, 10.0, bone).unwrap();
    assert!(
        (press.force - 10.0).abs() < 0.3,
        "force reached {}",
        press.force
    );
    assert!(
        (0.005..0.025).contains(&press.indentation),
        "indentation {}",
        press.indentation
    );
    // The skin under the face centre moved by about the indentation.
    let mid = press.deformation.surface_at(0.0);
    assert!(
        (mid - press.indentation).abs() < 2e-3,
        "skin {mid} vs probe {}",
        press.indentation
    );
    let input = FrameInput {
        deformation: &press.deformation,
        probe_pressure: press.force / cfg.probe_area(),
        time: 0.0,
        lateral_offset: 0.0,
    };
    let ratio = |state| {
        let r = Renderer::new(&cfg, state).unwrap();
        let l = r.lumens(&input).unwrap().unwrap();
        (
            l.vein.area / l.vein.rest_area,
            l.artery.area / l.artery.rest_area,
        )
    };
    let (healthy, artery) = ratio(VeinState::Healthy);
    assert!(healthy < 0.1, "healthy vein at {healthy}");
    assert!(artery > 0.8, "artery at {artery}");
    assert!(ratio(VeinState::Acute).0 > 0.6);
    assert!(ratio(VeinState::Chronic).0 > 0.6);
}
