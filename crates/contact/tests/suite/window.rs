//! The active window (issue 18) against the full model, the probe in
//! contact: a Fig. 4-style exam (press, hold, a short slide, hold, release)
//! and a 100 mm slide along the leg, both models stepped side by side on
//! the same probe path.
//!
//! **Bounds** (issue 18): the contact force on the probe within 2 % of the
//! full model's, the displacement field within 5 % of its peak, and no jump
//! in force when the window moves.
//! - The force is judged relative to `max(|F(t)|, 5 % of the exam's peak)`:
//!   at first touch and last release the force goes to zero, and a relative
//!   error of a vanishing force measures nothing (the Newton tolerance alone
//!   leaves a relative residual of 2 %, `IntegratorParams::newton_tol`).
//! - The displacement error is the largest node distance between the two
//!   models over the whole mesh, relative to `max(peak(t), 10 % of the
//!   exam's peak)`, `peak(t)` the full model's largest displacement from
//!   rest: out of contact the peak goes to zero while the far field the
//!   window held keeps what it had (see `echothigh_model::window`).
//! - A jump: at a step where the window moved, the windowed force's change
//!   over the step minus the full model's must be no larger than twice the
//!   largest such difference over the steps without a move (the two
//!   models' solver tolerance; a re-centring must look like any other step)
//!   and below 0.5 % of the exam's peak force, a quarter of the accuracy bound.
//!
//! Measured at 10 112 nodes, radius 50 mm: force within 0.008 % (exam) and
//! 0.048 % (slide), displacement within 0.057 % and 0.060 % of the peak;
//! at a move the force's step change is off by 6e-6 N (exam) and 3.9e-3 N
//! (slide) against 1.1e-3 N and 3.5e-3 N at the other steps. (At radius
//! 40 mm, measured with an earlier form of these checks — a 20 mm press in
//! the exam, errors relative to `max(|F|, 1 N)` and `max(peak, 1 mm)` —
//! force 0.009 % and 0.09 %, displacement 0.6 % and 0.4 %.)

use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, ThighModel, Vec3};

const H: f64 = 0.01;

/// The lean-male leg (the Fig. 4 scenario's patient, mid-thigh) at
/// 128 × 79 = 10 112 nodes (3.7 mm around, 3.8 mm along: the window's
/// goal size) in a release build; 48 × 40 in a debug build, to keep the
/// unoptimised full model's steps short (the window then still leaves a
/// far field). Window radius 50 mm, margin 10 mm.
fn config(window: bool) -> ModelConfig {
    let mut c = ModelConfig::default();
    c.thigh.patient = "lean-male".into();
    c.thigh.centre_s = 0.20;
    (c.thigh.n_theta, c.thigh.n_z) = if cfg!(debug_assertions) {
        (48, 40)
    } else {
        (128, 79)
    };
    c.integrator.window.enabled = window;
    c.integrator.window.radius = 0.05;
    c.integrator.window.margin = 0.01;
    c
}

/// Skin height (m) on the anterior line at `z`: the highest rest node near it.
fn skin_y(model: &ThighModel, z: f64) -> f64 {
    model
        .rest_positions()
        .iter()
        .filter(|p| p.x.abs() < 0.01 && (p.z - z).abs() < 0.012)
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
        let contact =
            ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
        Run { model, contact }
    }

    /// One step with the probe's face centre at `p`: the contact force on the probe.
    fn step(&mut self, p: Vec3) -> Vec3 {
        let (stats, wrench) = self
            .contact
            .advance(&mut self.model, &Probe::exam_pose(p), H);
        assert!(stats.finite);
        wrench.force
    }
}

/// One step of both models.
struct Sample {
    full: Vec3,
    window: Vec3,
    /// Largest node distance between the models (m).
    gap: f64,
    /// The full model's largest displacement from rest (m).
    peak: f64,
    moved: bool,
}

/// Steps both models along `path` (probe points).
fn run(path: &[Vec3]) -> Vec<Sample> {
    let (mut full, mut win) = (Run::new(false), Run::new(true));
    let mut out = Vec::with_capacity(path.len());
    for p in path {
        let moves = win.model.window().unwrap().moves();
        let (ff, fw) = (full.step(*p), win.step(*p));
        let (xf, xw, x0) = (
            full.model.positions(),
            win.model.positions(),
            full.model.rest_positions(),
        );
        let max = |it: &mut dyn Iterator<Item = f64>| it.fold(0.0, f64::max);
        out.push(Sample {
            full: ff,
            window: fw,
            gap: max(&mut xf.iter().zip(xw).map(|(a, b)| (a - b).norm())),
            peak: max(&mut xf.iter().zip(x0).map(|(a, b)| (a - b).norm())),
            moved: win.model.window().unwrap().moves() > moves,
        });
    }
    out
}

/// Worst errors of a run against the bounds of the module docs.
#[derive(Debug)]
struct Errors {
    peak_force: f64,
    force: f64,
    displacement: f64,
    moves: usize,
    jump: f64,
    step_noise: f64,
}

fn errors(s: &[Sample]) -> Errors {
    let peak_force = s.iter().map(|s| s.full.norm()).fold(0.0, f64::max);
    let peak_u = s.iter().map(|s| s.peak).fold(0.0, f64::max);
    let mut e = Errors {
        peak_force,
        force: 0.0,
        displacement: 0.0,
        moves: 0,
        jump: 0.0,
        step_noise: 0.0,
    };
    for (k, x) in s.iter().enumerate() {
        let scale = x.full.norm().max(0.05 * peak_force);
        e.force = e.force.max((x.window - x.full).norm() / scale);
        e.displacement = e.displacement.max(x.gap / x.peak.max(0.1 * peak_u));
        if k > 0 {
            let d = ((x.window - s[k - 1].window) - (x.full - s[k - 1].full)).norm();
            if x.moved {
                e.moves += 1;
                e.jump = e.jump.max(d);
            } else {
                e.step_noise = e.step_noise.max(d);
            }
        }
    }
    e
}

fn assert_within_bounds(e: &Errors, min_moves: usize) {
    println!("{e:?}");
    assert!(e.peak_force > 8.0, "the exam must press: {e:?}");
    assert!(
        e.force <= 0.02,
        "force off by {:.3} %: {e:?}",
        100.0 * e.force
    );
    assert!(e.displacement <= 0.05, "displacement off: {e:?}");
    assert!(e.moves >= min_moves, "the window must move: {e:?}");
    assert!(
        e.jump <= 2.0 * e.step_noise && e.jump <= 0.005 * e.peak_force,
        "a jump in force when the window moved: {e:?}"
    );
}

/// A probe path at `x = 0` (the anterior line): from 5 mm above the skin at
/// `z0` down to `depth` at 20 mm/s, hold `hold` s, slide `distance` along
/// +z at `speed` (m/s), hold 0.5 s, release at 20 mm/s to 5 mm above the
/// skin, 0.3 s out of contact.
fn exam(z0: f64, depth: f64, hold: f64, distance: f64, speed: f64) -> Vec<Vec3> {
    let top = skin_y(&Run::new(false).model, z0);
    let mut path = vec![Vec3::new(0.0, top + 0.005, z0)];
    let go = |path: &mut Vec<Vec3>, to: Vec3, v: f64| {
        let from = *path.last().unwrap();
        let n = (((to - from).norm() / (v * H)).ceil() as usize).max(1);
        path.extend((1..=n).map(|k| from + (to - from) * (k as f64 / n as f64)));
    };
    let stay = |path: &mut Vec<Vec3>, t: f64| {
        let last = *path.last().unwrap();
        path.extend(std::iter::repeat_n(last, (t / H).round() as usize));
    };
    go(&mut path, Vec3::new(0.0, top - depth, z0), 0.02);
    stay(&mut path, hold);
    go(&mut path, Vec3::new(0.0, top - depth, z0 + distance), speed);
    stay(&mut path, 0.5);
    go(&mut path, Vec3::new(0.0, top + 0.005, z0 + distance), 0.02);
    stay(&mut path, 0.3);
    path
}

/// Fig. 4's exam (`scenarios/fig4.toml`): at z = −10 mm, a 25 mm press
/// (its `max_depth`; ≈ 11 N on this mesh, fig4's target is 12 N), 1 s
/// hold, 20 mm slide at 10 mm/s.
#[test]
fn fig4_exam_matches_the_full_model() {
    let e = errors(&run(&exam(-0.01, 0.025, 1.0, 0.02, 0.01)));
    assert_within_bounds(&e, 1);
}

/// A slide along the leg: from z = −50 mm, 100 mm at 20 mm/s pressing
/// 20 mm (the window re-centres every ~10 mm).
#[test]
fn slide_along_the_leg_matches_the_full_model() {
    let e = errors(&run(&exam(-0.05, 0.02, 0.3, 0.10, 0.02)));
    assert_within_bounds(&e, 5);
}
