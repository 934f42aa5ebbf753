//! The active window's membership (issue 18): who is integrated as the
//! probe moves, with the hysteresis of `integrator.window.margin`, and the
//! state carried over when nodes enter and leave.

use crate::common;

use echothigh_model::{ModelConfig, NoExtraForce, ThighModel, Vec3, WindowParams};

/// 64 × 40 nodes on the cylinder (7.8 mm around, 7.7 mm along), window
/// radius 30 mm, margin 10 mm.
fn windowed() -> ThighModel {
    let mut c = common::small_config(64, 40);
    c.integrator.window = WindowParams {
        enabled: true,
        radius: 0.03,
        margin: 0.01,
    };
    common::model(&c)
}

/// Per-axis grid distance (θ periodic) of nodes `a` and `b`.
fn cells(m: &ThighModel, a: usize, b: usize) -> (usize, usize) {
    let mesh = m.mesh();
    let ((at, az), (bt, bz)) = (mesh.grid_index(a), mesh.grid_index(b));
    let dt = at.abs_diff(bt);
    (dt.min(mesh.n_theta() - dt), az.abs_diff(bz))
}

/// A probe point 2 mm outside node `k` at rest (its nearest node is `k`).
fn above(m: &ThighModel, k: usize) -> Vec3 {
    m.rest_positions()[k] + m.mesh().rest_normals()[k] * 0.002
}

#[test]
fn membership_holds_its_invariants_along_a_path() {
    let mut m = windowed();
    common::press_top(&mut m, 8.0);
    let mesh = m.mesh().clone();
    let (it0, iz0) = mesh.grid_index(common::top_node(&m));
    // Slide along z, then around θ across the seam-free anterior side,
    // then back: one node per step, a step of the model between moves.
    let mut path: Vec<usize> = (0..20)
        .map(|d| mesh.node_index(it0, iz0 - 10 + d))
        .collect();
    path.extend((0..16).map(|d| mesh.node_index(it0 + d, iz0 + 9)));
    path.extend(
        (0..25)
            .rev()
            .map(|d| mesh.node_index(it0 + d / 2, iz0 - 10 + d)),
    );
    let n = m.node_count();
    let mut core_before = vec![false; n];
    let (mut entered, mut left) = (0, 0);
    for (s, &focus) in path.iter().enumerate() {
        let x_before = m.positions().to_vec();
        m.set_focus(&above(&m, focus));
        assert_eq!(m.positions(), &x_before[..], "following moves no node");
        let w = m.window().unwrap();
        let shape = *w.shape();
        let (r, reach) = (shape.radius, shape.reach());
        let centre = w.centre().unwrap();
        let centre = mesh.node_index(centre.0, centre.1);
        let (ct, cz) = cells(&m, centre, focus);
        assert!(
            ct <= shape.margin.0 && cz <= shape.margin.1,
            "centre within the margin"
        );
        let mut count = 0;
        for (k, before) in core_before.iter_mut().enumerate() {
            let core = w.is_core(&mesh, k);
            let (dt, dz) = cells(&m, k, focus);
            count += usize::from(core);
            if dt <= r.0 && dz <= r.1 && !mesh.fixed()[k] {
                assert!(
                    core,
                    "step {s}: node {k} within the radius is not integrated"
                );
            }
            if *before && !core {
                left += 1;
                assert!(
                    dt > reach.0 || dz > reach.1,
                    "step {s}: node {k} left within r + m ({dt}, {dz} cells)"
                );
            }
            if !core {
                assert_eq!(m.velocities()[k], Vec3::zeros(), "held nodes do not move");
            }
            entered += usize::from(core && !*before && s > 0);
            *before = core;
        }
        assert_eq!(count, w.core_count());
        let stats = m.step(0.01, &mut NoExtraForce);
        assert!(stats.finite && stats.converged);
        for k in (0..n).filter(|&k| !m.window().unwrap().is_core(&mesh, k)) {
            assert_eq!(
                m.positions()[k],
                x_before[k],
                "step {s}: held node {k} moved"
            );
        }
    }
    assert!(m.window().unwrap().moves() >= 4 && entered > 0 && left > 0);
}

#[test]
fn the_window_stays_while_the_probe_moves_within_the_margin() {
    let mut m = windowed();
    let mesh = m.mesh().clone();
    let top = common::top_node(&m);
    m.set_focus(&above(&m, top));
    let (moves, centre) = (m.window().unwrap().moves(), m.window().unwrap().centre());
    let margin = m.window().unwrap().shape().margin;
    let (it, iz) = mesh.grid_index(top);
    // Back and forth across the margin's square, corners included.
    for dt in [0, margin.0, mesh.n_theta() - margin.0] {
        for dz in [iz - margin.1, iz, iz + margin.1] {
            m.set_focus(&above(&m, mesh.node_index(it + dt, dz)));
            assert_eq!(m.window().unwrap().moves(), moves);
            assert_eq!(m.window().unwrap().centre(), centre);
        }
    }
    // One cell further along z: the window re-centres on the probe.
    let beyond = mesh.node_index(it, iz + margin.1 + 1);
    m.set_focus(&above(&m, beyond));
    assert_eq!(m.window().unwrap().moves(), moves + 1);
    assert_eq!(m.window().unwrap().centre(), Some(mesh.grid_index(beyond)));
}

#[test]
fn a_window_that_would_wrap_the_mesh_is_a_clear_error() {
    let mut c = ModelConfig::default();
    c.integrator.window.enabled = true;
    c.integrator.window.radius = 0.3;
    let e = ThighModel::new(&c).unwrap_err().to_string();
    assert!(
        e.starts_with("integrator.window.radius") && e.contains("n_theta = 48"),
        "{e}"
    );
    c.integrator.window.radius = 0.0;
    let e = ThighModel::new(&c).unwrap_err().to_string();
    assert!(
        e.starts_with("integrator.window.radius must be in [0.02, 1] m"),
        "{e}"
    );
    c.integrator.window.radius = 0.05;
    c.integrator.window.margin = 0.06;
    let e = ThighModel::new(&c).unwrap_err().to_string();
    assert!(e.starts_with("integrator.window.margin"), "{e}");
    // Off by default; parsed from TOML with its section.
    assert!(!ModelConfig::default().integrator.window.enabled);
    let w: WindowParams = toml::from_str("enabled = true\nradius = 0.05").unwrap();
    assert_eq!((w.enabled, w.radius, w.margin), (true, 0.05, 0.01));
}
