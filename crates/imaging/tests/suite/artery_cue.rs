//! The artery's deformation cue (issue 12, cus-exam-fidelity §4 item 5):
//! trainees press "until the artery just begins to deform". The artery must
//! ovalise visibly from ~60–80 mmHg of tissue pressure at its depth and
//! clearly by ~120 mmHg, inside the force the device can render, and a
//! healthy vein must close before that.

use crate::common;
use common::*;
use echothigh_imaging::*;

/// Tissue force (N) the default device renders: `device.max_force` 6 N at
/// `device.force_scale` 0.3 (scenarios/fig4.toml).
const RENDERABLE_FORCE: f64 = 6.0 / 0.3;

/// A "visible" change of the artery: 10 % of its area. Flattened
/// vertically, its 7 mm height loses 0.7 mm, ≈ 4.5 image rows at the
/// default 60 mm / 384 rows (0.16 mm per row): well above a pixel.
const VISIBLE: f64 = 0.9;

#[test]
fn artery_lumen_law_follows_the_cue() {
    let cfg = AnatomyConfig::default();
    let a = Anatomy::new(&cfg, VeinState::Healthy).unwrap();
    // At diastole (time 0 is the cycle's start: pulse P(0) = 0).
    let at = |mmhg: f64| a.artery_lumen_ratio(mmhg * MMHG, 0.0);
    assert!(at(55.0) == 1.0, "no deformation below 60 mmHg");
    assert!(
        at(80.0) < 0.97 && at(80.0) > VISIBLE,
        "just begins at 80: {}",
        at(80.0)
    );
    assert!(at(90.0) < VISIBLE, "visible by 90 mmHg: {}", at(90.0));
    assert!(at(120.0) < 0.75, "clearly oval at 120 mmHg: {}", at(120.0));
    // The vein is closed (its full-closure pressure) before the artery moves.
    assert!(cfg.healthy.collapse_full < cfg.artery_collapse_onset);
    assert_eq!(a.vein_lumen_ratio(cfg.healthy.collapse_full), 0.0);
}

#[test]
fn vein_closes_then_artery_ovalises_below_the_renderable_force() {
    let cfg = ImagingConfig::default();
    let r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let mut vein_closed = None;
    let mut artery_visible = None;
    // 0.1 N steps up to the renderable force.
    let steps = (RENDERABLE_FORCE * 10.0).round() as usize;
    let mut last_artery = f64::INFINITY;
    for i in 0..=steps {
        let f = i as f64 * 0.1;
        let d = press(&r, indentation(f));
        let input = FrameInput {
            deformation: &d,
            probe_pressure: f / cfg.probe_area(),
            time: 0.0,
            lateral_offset: 0.0,
        };
        let l = r.lumens(&input).unwrap().unwrap();
        let vein = l.vein.area / l.vein.rest_area;
        let artery = l.artery.area / l.artery.rest_area;
        assert!(
            artery <= last_artery + 1e-12,
            "artery grows with force at {f} N"
        );
        last_artery = artery;
        if vein < 0.05 && vein_closed.is_none() {
            vein_closed = Some(f);
        }
        if artery < VISIBLE && artery_visible.is_none() {
            artery_visible = Some(f);
        }
    }
    let closed = vein_closed.expect("the healthy vein closes below the renderable force");
    let visible = artery_visible.expect("the artery ovalises below the renderable force");
    assert!(
        closed < visible,
        "vein closed at {closed} N, artery visible at {visible} N"
    );
}
