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

#[test]
fn buffer_mode_exam() {
    // The proxy sits on the constraint surface, outside the tissue; the
    // tolerance covers the deformation between two physics samples.
    exam_runs(CouplingMode::Buffer, 2e-3);
}

#[test]
fn hold_mode_exam() {
    // The held 100 Hz force trembles (paper Fig. 4): the probe bounces
    // into the tissue, but never through it.
    exam_runs(CouplingMode::Hold, 20e-3);
}

#[test]
fn direct_mode_exam() {
    // The face presses the tissue; the probe's centre stays within the
    // penalty contact's penetration of the deformed surface.
    exam_runs(CouplingMode::Direct, 8e-3);
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
