//! `direct` coupling integrates the active window around the probe by
//! default (`coupling.direct_window`, issue 18): at the haptic rate the
//! whole-leg step costs ≈ 350 µs of the 1 ms tick, the window's ≈ 115 µs.
//! The window must render the full model's force: on the built-in scenario's
//! whole-leg mesh (lean-male, 48 × 27 nodes), through a press, a hold and a
//! 40 mm slide along the leg (the window re-centres), the windowed physics'
//! force stays within 2 % of the full model's peak and its displacement field
//! within 5 % of the full model's peak displacement: the issue's own
//! acceptance bounds for the window. Radius 20 mm (the smallest allowed)
//! once panicked when the contact's face samples outnumbered the patch's
//! nodes (its rank-one terms overflowed into the side matrix).

use crate::site_probe::probe;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;

/// Largest node distance between two position sets (m).
fn largest_gap(a: &[echothigh_model::Vec3], b: &[echothigh_model::Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}

fn windowed_force_follows_the_full_model(radius: f64) {
    let mut s = Scenario::builtin().unwrap();
    s.coupling.mode = CouplingMode::Direct;
    s.coupling.direct_window = false;
    let mut full = PhysicsSide::new(&s).unwrap();
    s.coupling.direct_window = true;
    s.integrator.window.radius = radius;
    s.integrator.window.margin = 0.01;
    s.validate().unwrap();
    let mut fast = PhysicsSide::new(&s).unwrap();
    assert!(full.model().window().is_none());
    let rest = full.model().positions().to_vec();
    let h = 1e-3;
    // 0.5 s from 3 mm above the skin to 12 mm in, 0.2 s held, 0.8 s
    // sliding 40 mm towards the knee (beyond the 10 mm hysteresis).
    let n = 1500;
    let (mut peak_force, mut force_gap) = (0.0f64, 0.0f64);
    let (mut peak_disp, mut disp_gap) = (0.0f64, 0.0f64);
    for i in 0..n {
        let t = i as f64 * h;
        let depth = -0.003 + 0.015 * (t / 0.5).min(1.0);
        let slide = 0.040 * ((t - 0.7) / 0.8).clamp(0.0, 1.0);
        let msg = probe(&full, depth, slide);
        let (f_full, _) = full.step_force(&msg, h, t);
        let (f_fast, _) = fast.step_force(&msg, h, t);
        peak_force = peak_force.max(f_full.norm());
        force_gap = force_gap.max((f_full - f_fast).norm());
        if i % 50 == 49 {
            let x = full.model().positions();
            peak_disp = peak_disp.max(largest_gap(x, &rest));
            disp_gap = disp_gap.max(largest_gap(x, fast.model().positions()));
        }
    }
    let window = fast
        .model()
        .window()
        .expect("direct mode integrates the window");
    let nodes = fast.model().node_count();
    assert!(
        window.patch_nodes().len() < nodes / 2,
        "radius {radius}: the window holds {} of {nodes} nodes",
        window.patch_nodes().len()
    );
    assert!(
        window.moves() >= 1,
        "radius {radius}: the window never followed the slide"
    );
    // A 12 mm press on the thigh is several newtons and mm.
    assert!(
        peak_force > 2.0 && peak_disp > 5e-3,
        "{peak_force} N, {peak_disp} m"
    );
    assert!(
        force_gap <= 0.02 * peak_force,
        "radius {radius}: force gap {force_gap} N against the full model's peak {peak_force} N"
    );
    assert!(
        disp_gap <= 0.05 * peak_disp,
        "radius {radius}: displacement gap {disp_gap} m against the full model's peak {peak_disp} m"
    );
}

#[test]
fn the_direct_window_renders_the_full_models_force_at_50_mm() {
    windowed_force_follows_the_full_model(0.05);
}

#[test]
fn the_direct_window_renders_the_full_models_force_at_20_mm() {
    windowed_force_follows_the_full_model(0.02);
}

/// `run --mode direct` integrates the window by default, and only there:
/// the buffer and hold modes' physics (100 Hz, off the haptic thread) and a
/// scenario that asks for the whole mesh step every node.
#[test]
fn direct_mode_integrates_the_window_by_default() {
    let mut s = Scenario::builtin().unwrap();
    assert!(s.coupling.direct_window, "the default is the window");
    assert!(
        !s.integrator.window.enabled,
        "the window is off for the other modes"
    );
    for (mode, whole_mesh, windowed) in [
        (CouplingMode::Buffer, false, false),
        (CouplingMode::Hold, false, false),
        (CouplingMode::Direct, false, true),
        (CouplingMode::Direct, true, false),
    ] {
        s.coupling.mode = mode;
        s.coupling.direct_window = !whole_mesh;
        assert_eq!(
            s.model_config().integrator.window.enabled,
            windowed,
            "{mode:?}, direct_window {}",
            s.coupling.direct_window
        );
    }
    s.coupling.mode = CouplingMode::Direct;
    s.coupling.direct_window = true;
    let physics = PhysicsSide::new(&s).unwrap();
    assert!(
        physics.model().window().is_some(),
        "the physics side builds the window"
    );
}
