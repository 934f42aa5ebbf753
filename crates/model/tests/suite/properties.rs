//! Property tests over mesh resolutions, parameters and loads: the state
//! stays finite and no node crosses the normal springs' asymptote.

use crate::common;

use echothigh_model::{NoExtraForce, ThighModel, Vec3};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn no_nan_and_no_node_crosses_the_asymptote(
        n_theta in 8usize..28,
        n_z in 3usize..10,
        normal_b in 0.5e-6f64..4e-6,
        asymptote in 0.010f64..0.035,
        structural in 20.0f64..2000.0,
        density in 2.0f64..30.0,
        lambda in 0.5f64..=1.0,
        load in 0.0f64..80.0,
        kick in 0.0f64..2.0,
        h in 0.002f64..0.03,
        hold_ends in any::<bool>(),
        on_leg in any::<bool>(),
    ) {
        let mut c = common::small_config_on(n_theta, n_z, on_leg);
        c.thigh.hold_ends = hold_ends;
        c.tissue.normal_b = normal_b;
        c.tissue.normal_a = normal_b / asymptote;
        c.tissue.structural_stiffness = structural;
        c.tissue.areal_density = density;
        c.integrator.lambda = lambda;
        let mut m = ThighModel::new(&c).unwrap();
        common::press_top(&mut m, load); // up to 80 N on three nodes: deep into the asymptote
        let x = m.rest_positions().to_vec();
        let n = m.node_count();
        let v: Vec<Vec3> = common::perturbation(n, kick, n as u64);
        m.set_state(&x, &v);
        for _ in 0..15 {
            let s = m.step(h, &mut NoExtraForce);
            prop_assert!(s.finite, "{s:?}");
            prop_assert!(m.positions().iter().chain(m.velocities()).all(|p| p.iter().all(|c| c.is_finite())));
            let ratio = m.max_asymptote_ratio();
            let bound = 1.0 - c.integrator.asymptote_margin + 1e-9;
            prop_assert!(ratio < bound, "compression ratio {ratio}");
        }
    }
}

/// A hammer blow: 150 N on three nodes plus 3 m/s inward. One linear solve
/// per step would throw the nodes past `b/a`; the limiter must act, the
/// compression must stay within `(1 − margin) b/a`, and the skin must still
/// be pushed deep (Newton makes progress against the stiffening springs).
#[test]
fn hammer_blow_is_limited_at_the_margin() {
    let c = common::small_config(24, 9);
    let mut m = ThighModel::new(&c).unwrap();
    common::press_top(&mut m, 150.0);
    let top = common::top_node(&m);
    let mut v = vec![Vec3::zeros(); m.node_count()];
    v[top] = -m.mesh().rest_normals()[top] * 3.0;
    let x = m.rest_positions().to_vec();
    m.set_state(&x, &v);
    let mut limited = 0;
    let mut deepest: f64 = 0.0;
    for _ in 0..30 {
        let s = m.step(0.01, &mut NoExtraForce);
        assert!(s.finite);
        limited += s.limited;
        let ratio = m.max_asymptote_ratio();
        assert!(
            ratio <= 1.0 - c.integrator.asymptote_margin + 1e-9,
            "{ratio}"
        );
        deepest = deepest.max(ratio);
    }
    assert!(limited > 0, "the limiter never acted");
    assert!(deepest > 0.8, "compression ratio only {deepest}");
}
