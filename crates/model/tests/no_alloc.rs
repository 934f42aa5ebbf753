//! A physics step and a stiffness solve allocate nothing (counting global
//! allocator; one test function so no other thread allocates meanwhile).

mod common;

use echothigh_model::{NoExtraForce, Vec3};
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn steps_and_stiffness_solves_allocate_nothing() {
    // On the elliptic cylinder and on the patient's leg (issue 12).
    for leg in [false, true] {
        check(leg);
        check_windowed(leg);
    }
}

/// The active window (issue 18): following a moving probe (re-centring
/// included) and stepping allocate nothing either.
fn check_windowed(leg: bool) {
    let mut config = common::small_config_on(48, 21, leg);
    config.integrator.window.enabled = true;
    config.integrator.window.radius = 0.03;
    let mut m = common::model(&config);
    common::press_top(&mut m, 12.0);
    let mesh = m.mesh().clone();
    let (it, iz) = mesh.grid_index(common::top_node(&m));
    let focus = |d: usize| mesh.rest_positions()[mesh.node_index(it, iz - 5 + d % 11)];
    m.set_focus(&focus(0));
    m.step(0.01, &mut NoExtraForce); // warm-up: places the window
    let (moves, n) = count_allocations(|| {
        for s in 0..30 {
            m.set_focus(&focus(s));
            m.step(0.01, &mut NoExtraForce);
        }
        m.window().unwrap().moves()
    });
    assert!(moves >= 3, "the window must move: {moves}");
    assert_eq!(n, 0, "allocations during windowed steps (leg: {leg})");
}

fn check(leg: bool) {
    let mut config = common::small_config_on(24, 11, leg);
    config.tissue.gravity = [0.0, -9.81, 0.0];
    let mut m = common::model(&config);
    common::press_top(&mut m, 12.0); // strong load: Newton iterates, limiter may act
    let n = m.node_count();
    let mut rhs = vec![Vec3::zeros(); n];
    rhs[common::top_node(&m)] = Vec3::new(0.0, -1.0, 0.0);
    let mut out = vec![Vec3::zeros(); n];
    m.step(0.01, &mut NoExtraForce); // warm-up
    m.solve_stiffness(&mut NoExtraForce, &rhs, &mut out);

    let ((work, s), n) = count_allocations(|| {
        let mut work = 0;
        for _ in 0..20 {
            let s = m.step(0.01, &mut NoExtraForce);
            work += s.cg_iterations;
        }
        (work, m.solve_stiffness(&mut NoExtraForce, &rhs, &mut out))
    });
    assert!(work > 0 && s.iterations > 0, "the steps must do real work");
    assert_eq!(n, 0, "allocations during steps (leg: {leg})");
}
