//! The active window (issue 18) against the full model, probe in contact.

use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, ThighModel, Vec3};

const H: f64 = 0.01;

/// The lean-male leg (the Fig. 4 scenario's patient) at 10 112 nodes in a
/// release build; 48 × 40 in a debug build (the full model's 10k step
/// takes ~0.1 s unoptimised).
fn config(window: bool) -> ModelConfig {
    let mut c = ModelConfig::default();
    c.thigh.patient = "lean-male".into();
    c.thigh.centre_s = 0.20;
    (c.thigh.n_theta, c.thigh.n_z) = if cfg!(debug_assertions) { (48, 40) } else { (128, 79) };
    c.integrator.window.enabled = window;
    c.integrator.window.radius = 0.06;
    c.integrator.window.margin = 0.01;
    c
}

/// Skin height (m) on the anterior line at `z`: the highest rest node near it.
fn skin_y(model: &ThighModel, z: f64) -> f64 {
    model
        .rest_positions()
        .iter()
        .filter(|p| p.x.abs() < 0.01 && (p.z - z).abs() < 0.006)
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max)
}

struct Run {
    model: ThighModel,
    contact: ProbeContact,
}

impl Run {
    fn new(window: bool) -> Run {
        let model = ThighModel::new(&config(window)).unwrap();
        let contact = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
        Run { model, contact }
    }

    fn step(&mut self, p: Vec3) -> Vec3 {
        let (stats, wrench) = self
            .contact
            .advance(&mut self.model, &Probe::exam_pose(p), H);
        assert!(stats.finite);
        wrench.force
    }
}

#[derive(Default, Debug)]
struct Errors {
    peak_force: f64,
    force: f64,
    displacement: f64,
    peak_displacement: f64,
    moves: u64,
    jump: f64,
    step_change: f64,
}

/// Steps both models along `path` (probe points), comparing each step.
fn compare(path: &[Vec3]) -> Errors {
    let (mut full, mut win) = (Run::new(false), Run::new(true));
    let mut e = Errors::default();
    let (mut f_prev_w, mut f_prev_f) = (Vec3::zeros(), Vec3::zeros());
    for (i, p) in path.iter().enumerate() {
        let moves = win.model.window().unwrap().moves();
        let (ff, fw) = (full.step(*p), win.step(*p));
        let peak_u = full
            .model
            .positions()
            .iter()
            .zip(full.model.rest_positions())
            .map(|(x, r)| (x - r).norm())
            .fold(0.0, f64::max);
        let du = full
            .model
            .positions()
            .iter()
            .zip(win.model.positions())
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        e.peak_force = e.peak_force.max(ff.norm());
        e.peak_displacement = e.peak_displacement.max(peak_u);
        let rel_f = (fw - ff).norm() / ff.norm().max(1.0);
        let rel_u = du / peak_u.max(1e-3);
        e.force = e.force.max(rel_f);
        e.displacement = e.displacement.max(rel_u);
        let moved = win.model.window().unwrap().moves() > moves;
        let change = ((fw - f_prev_w) - (ff - f_prev_f)).norm();
        if moved && i > 0 {
            e.moves += 1;
            e.jump = e.jump.max(change);
        } else if i > 0 {
            e.step_change = e.step_change.max(change);
        }
        (f_prev_w, f_prev_f) = (fw, ff);
        if i % 25 == 0 {
            println!(
                "{i:4} p=({:.3},{:.4},{:.3}) F={:.3} Fw={:.3} relF={:.4} peak_u={:.4} du={:.2e} relU={:.4} core={}",
                p.x,
                p.y,
                p.z,
                ff.norm(),
                fw.norm(),
                rel_f,
                peak_u,
                du,
                rel_u,
                win.model.window().unwrap().core_count()
            );
        }
    }
    println!("{e:?}");
    e
}

/// A probe path: from `above` the skin down to `depth` at `rate`, hold,
/// slide `distance` along z at `speed`, hold, release.
fn exam(z0: f64, depth: f64, hold: f64, distance: f64, speed: f64) -> Vec<Vec3> {
    let probe = Run::new(false);
    let top = skin_y(&probe.model, z0);
    let mut path = Vec::new();
    let mut y = top + 0.005;
    let push_to = |path: &mut Vec<Vec3>, target: Vec3, v: f64| {
        let from = *path.last().unwrap_or(&target);
        let n = (((target - from).norm() / (v * H)).ceil() as usize).max(1);
        for k in 1..=n {
            path.push(from + (target - from) * (k as f64 / n as f64));
        }
    };
    path.push(Vec3::new(0.0, y, z0));
    y = top - depth;
    push_to(&mut path, Vec3::new(0.0, y, z0), 0.02);
    let hold_at = |path: &mut Vec<Vec3>, t: f64| {
        let last = *path.last().unwrap();
        path.extend(std::iter::repeat(last).take((t / H).round() as usize));
    };
    hold_at(&mut path, hold);
    push_to(&mut path, Vec3::new(0.0, y, z0 + distance), speed);
    hold_at(&mut path, 0.5);
    push_to(&mut path, Vec3::new(0.0, top + 0.005, z0 + distance), 0.02);
    hold_at(&mut path, 0.3);
    path
}

#[test]
fn fig4_exam_matches_the_full_model() {
    let e = compare(&exam(-0.01, 0.02, 1.0, 0.02, 0.01));
    assert!(e.force < 0.02, "{e:?}");
}

#[test]
fn slide_along_the_leg_matches_the_full_model() {
    let e = compare(&exam(-0.05, 0.02, 0.3, 0.10, 0.02));
    assert!(e.force < 0.02, "{e:?}");
}
