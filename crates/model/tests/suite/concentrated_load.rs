//! A concentrated load (a probe's edge on a few nodes) compresses the
//! tissue column under it and never drives a node round its anchor.
//!
//! With normal springs from node to anchor point, 20 N on three nodes of the
//! cylinder settled the middle node 26 mm *beyond* its anchor (50 N: 130 mm),
//! and 50 N on the lean leg 56 mm beyond: the compressed spring's geometric
//! stiffness pushed the node sideways round the limiter, and the inverted
//! spring then pushed it on. The column along the rest normal (paper §3,
//! "springs orthogonal to the surface") keeps it on its side.

use crate::common;

use common::{model, press_top, small_config_on, top_node};
use echothigh_model::NoExtraForce;

/// Height (m) of the loaded node above its anchor along the rest normal, and
/// the least height its law allows (rest − λ b/a, m), after the press has
/// settled.
fn settled_height(leg: bool, total: f64) -> (f64, f64) {
    let c = small_config_on(48, 21, leg);
    let mut m = model(&c);
    press_top(&mut m, total);
    // 4 s at h = 10 ms: the default layer's slowest mode is damped within
    // ~1 s (normal damping 2000 N·s/m³ against its stiffness); the test
    // asserts the settling below.
    for _ in 0..400 {
        m.step(0.01, &mut NoExtraForce);
    }
    let k = top_node(&m);
    assert!(
        m.velocities()[k].norm() < 1e-6,
        "not settled: {} m/s",
        m.velocities()[k].norm()
    );
    let n0 = m.mesh().rest_normals()[k];
    let a = m.anchors()[k];
    let rest = n0.dot(&(m.rest_positions()[k] - a));
    let asymptote = m.mesh().layer_scales()[k] * c.tissue.asymptote();
    (n0.dot(&(m.positions()[k] - a)), rest - asymptote)
}

#[test]
fn a_concentrated_load_never_passes_the_anchor() {
    for leg in [false, true] {
        let mut last = f64::INFINITY;
        for total in [5.0, 20.0, 50.0, 80.0] {
            let (h, least) = settled_height(leg, total);
            // The law f = x/(ax + b) cannot be compressed past its
            // asymptote, so the column stays above rest − λ b/a (> 0).
            assert!(
                least > 0.0 && h > least,
                "leg {leg}, {total} N: node {:.2} mm above its anchor (least {:.2} mm)",
                h * 1e3,
                least * 1e3
            );
            // More force, more compression.
            assert!(
                h < last,
                "leg {leg}, {total} N: height {:.3} mm not below {:.3} mm",
                h * 1e3,
                last * 1e3
            );
            last = h;
        }
    }
}
