//! End-to-end tests of the running system (issue 5) on the deterministic
//! virtual clock: each coupling mode completes a press of the default exam
//! with a bounded force, makes contact, and keeps the proxy outside the
//! tissue; a hostile link does not break the buffer mode; bad scenarios are
//! refused with the key named.

use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::trace::force_magnitudes;
use echothigh_runtime::virtual_clock::VirtualRun;

fn scenario(mode: CouplingMode, duration: f64) -> Scenario {
    let mut s = Scenario::default();
    s.coupling.mode = mode;
    s.run.duration = duration;
    s.validate().unwrap();
    s
}

/// Runs 2 s of the default exam (approach and press) and checks the force
/// limit, the contact, and how far the proxy goes inside the deformed
/// surface (`tolerance`, m). In `hold` and `direct` there is no proxy: the
/// "proxy" is the device itself, inside the surface by the penalty
/// contact's penetration.
fn exam_runs(mode: CouplingMode, tolerance: f64) {
    let s = scenario(mode, 2.0);
    let mut run = VirtualRun::new(&s).unwrap();
    let mut worst_inside: f64 = 0.0;
    for _ in 0..2000 {
        run.step_tick().unwrap();
        let last = run.ticks().last().unwrap();
        let proxy = nalgebra::Vector3::from(last.proxy);
        if let Some(d) = run.physics_mut().signed_distance(&proxy) {
            worst_inside = worst_inside.min(d);
        }
    }
    let f = force_magnitudes(run.ticks());
    assert!(
        f.iter().all(|x| x.is_finite()),
        "{mode:?}: non-finite force"
    );
    let limit = s.haptics.render.max_force + 1e-9;
    assert!(
        f.iter().all(|&x| x <= limit),
        "{mode:?}: force above {limit} N"
    );
    let peak = f.iter().copied().fold(0.0, f64::max);
    assert!(peak > 5.0, "{mode:?}: no press (peak {peak:.2} N)");
    let device_limit = s.device.max_force + 1e-9;
    for r in run.ticks() {
        let n = (r.device_force[0].powi(2) + r.device_force[1].powi(2) + r.device_force[2].powi(2))
            .sqrt();
        assert!(
            n <= device_limit,
            "{mode:?}: device force {n} above the device limit"
        );
    }
    assert!(
        worst_inside > -tolerance,
        "{mode:?}: proxy {:.2} mm inside the tissue (tolerance {:.1} mm)",
        -worst_inside * 1e3,
        tolerance * 1e3
    );
    assert_eq!(run.faults(), 0);
}

/// The depths (m) that bound how far a probe point may sit inside the
/// deformed surface, from the default scenario's physics:
/// - `face`: the penalty contact's penetration at the largest force the
///   renderer may send, `max_force / (λ_c · face area)` = 20 N /
///   (5e7 N/m³ · 40 × 10 mm²) = 20 N / 20 N/mm = 1 mm (Eq. 2: the face
///   pushes the nodes back only as far as it is inside them);
/// - `travel(T)`: how far the press moves the probe in while the surface it
///   is measured against is `T` old, `rate · T` with the exam's press rate
///   (40 mm/s).
fn bounds(s: &Scenario) -> (f64, impl Fn(f64) -> f64) {
    let face = s.haptics.render.max_force / (s.contact.stiffness * s.probe.face_area());
    let rate = s
        .exam
        .phases
        .iter()
        .find_map(|p| match p {
            echothigh_device::PhaseConfig::Press { rate, .. } => Some(*rate),
            _ => None,
        })
        .expect("the default exam presses");
    (face, move |t: f64| rate * t)
}

#[test]
fn buffer_mode_exam() {
    // The proxy sits on the local model's surface, outside the tissue as
    // the last sample saw it; the surface under the probe moves at most by
    // the press's travel in one physics period (40 mm/s · 10 ms = 0.4 mm).
    let s = scenario(CouplingMode::Buffer, 2.0);
    let (_, travel) = bounds(&s);
    exam_runs(CouplingMode::Buffer, travel(1.0 / s.coupling.physics_rate));
}

#[test]
fn hold_mode_exam() {
    // No proxy: the device itself, inside the surface by the face's
    // penetration (≤ 1 mm) plus the press's travel while the held force is
    // one physics period old (0.4 mm): 1.4 mm, where the slide test holds
    // the face to 2 mm.
    let s = scenario(CouplingMode::Hold, 2.0);
    let (face, travel) = bounds(&s);
    exam_runs(
        CouplingMode::Hold,
        face + travel(1.0 / s.coupling.physics_rate),
    );
}

#[test]
fn direct_mode_exam() {
    // One physics step per tick: the face's penetration (≤ 1 mm) plus one
    // tick's travel (0.04 mm).
    let s = scenario(CouplingMode::Direct, 2.0);
    let (face, travel) = bounds(&s);
    exam_runs(
        CouplingMode::Direct,
        face + travel(1.0 / s.coupling.haptic_rate),
    );
}

/// Under 20 % loss, 5 ms of jitter and 10 % duplication the buffer mode
/// still completes the press: no NaN, no force above the device limit, and
/// the link dropped what it should.
#[test]
fn buffer_mode_survives_a_hostile_link() {
    let mut s = scenario(CouplingMode::Buffer, 2.0);
    s.link.loss = 0.2;
    s.link.jitter = 0.005;
    s.link.duplicate = 0.1;
    s.validate().unwrap();
    let mut run = VirtualRun::new(&s).unwrap();
    run.run_for(2.0).unwrap();
    let f = force_magnitudes(run.ticks());
    assert!(f.iter().all(|x| x.is_finite()));
    let peak = f.iter().copied().fold(0.0, f64::max);
    assert!(
        peak > 5.0 && peak <= s.haptics.render.max_force + 1e-9,
        "peak {peak}"
    );
    for r in run.ticks() {
        let n = (r.device_force[0].powi(2) + r.device_force[1].powi(2) + r.device_force[2].powi(2))
            .sqrt();
        assert!(n <= s.device.max_force + 1e-9);
    }
    let (up, down) = run.link_stats();
    assert!(
        up.fault_lost > 100 && down.fault_lost > 10,
        "loss not injected: {up:?} {down:?}"
    );
    assert!(
        up.duplicate + up.stale + down.duplicate + down.stale > 0,
        "nothing filtered"
    );
}

/// Two runs of the same scenario give identical traces (virtual clock).
#[test]
fn virtual_clock_is_deterministic() {
    let s = scenario(CouplingMode::Buffer, 1.0);
    let trace = |s: &Scenario| {
        let mut run = VirtualRun::new(s).unwrap();
        run.run_for(1.0).unwrap();
        force_magnitudes(run.ticks())
    };
    assert_eq!(trace(&s), trace(&s));
}

#[test]
fn scenario_errors_name_the_key() {
    let err = |text: &str| {
        format!(
            "{:#}",
            Scenario::from_toml_str(text, "test.toml").unwrap_err()
        )
    };
    let e = err("[coupling]\nmode = \"buffer\"\nbogus = 1\n");
    assert!(e.contains("bogus"), "{e}");
    let e = err("[tissue]\nareal_density = -1.0\n");
    assert!(e.contains("tissue.areal_density"), "{e}");
    let e = err("[coupling]\nphysics_rate = nan\n");
    assert!(e.contains("coupling.physics_rate"), "{e}");
    let e = err("[integrator]\nlambda = 1.5\n");
    assert!(e.contains("integrator.lambda"), "{e}");
    let e = err("[[exam.phases]]\nkind = \"hold\"\n");
    assert!(e.contains("duration"), "{e}");
    let e = err("[patient]\nvein = \"sclerotic\"\n");
    assert!(e.contains("sclerotic") || e.contains("vein"), "{e}");
}
