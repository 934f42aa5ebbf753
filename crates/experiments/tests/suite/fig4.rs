//! Issue 6, "What must hold": the default fig4 scenario reproduces the
//! paper's Fig. 4 — without the buffer model the force trembles, with it the
//! force is smooth and close to direct coupling — a damping sweep shows the
//! sampled-data boundary, and the experiment is deterministic.
//!
//! The three-mode run of the default scenario is shared by the tests (one
//! run per test binary).

use echothigh_device::PhaseConfig;
use echothigh_experiments::fig4::{fig4, write_fig4, Fig4Result};
use echothigh_experiments::scenario::{default_fig4, FIG4_TOML};
use echothigh_experiments::stability::{bound, largest_trembling};
use echothigh_experiments::sweep::{sweep, SweepKind};
use echothigh_runtime::live::CouplingMode;
use std::sync::OnceLock;

fn shared() -> &'static Fig4Result {
    static RUN: OnceLock<Fig4Result> = OnceLock::new();
    RUN.get_or_init(|| fig4(&default_fig4().expect("embedded scenario")).expect("fig4 run"))
}

/// The default scenario: a PHANToM-class device, a light grip inside the
/// published human ranges, a press, a hold and a slide; sources written in
/// the file.
#[test]
fn default_scenario_is_plausible_and_documented() {
    let s = default_fig4().unwrap();
    let d = &s.device;
    assert!(
        (0.045..=0.1).contains(&d.mass),
        "device tip mass {} kg",
        d.mass
    );
    assert!(
        (6.0..=8.5).contains(&d.max_force),
        "device peak force {} N",
        d.max_force
    );
    assert!((0.5..=2.0).contains(&d.viscous_friction));
    let h = &s.hand;
    assert!(
        (200.0..=1000.0).contains(&h.stiffness),
        "hand stiffness {} N/m",
        h.stiffness
    );
    assert!(
        (2.0..=10.0).contains(&h.damping),
        "hand damping {} N·s/m",
        h.damping
    );
    assert!(
        (s.coupling.physics_rate - 100.0).abs() < 1e-9
            && (s.coupling.haptic_rate - 1000.0).abs() < 1e-9
    );
    let has = |f: fn(&PhaseConfig) -> bool| s.exam.phases.iter().any(f);
    assert!(has(|p| matches!(p, PhaseConfig::Press { .. })));
    assert!(has(|p| matches!(p, PhaseConfig::Hold { .. })));
    // A clinical slide (10–20 mm at ≤ 20 mm/s) followed by a second hold.
    assert!(has(|p| matches!(
        p,
        PhaseConfig::Slide { distance, speed, .. }
            if (0.01..=0.02).contains(distance) && *speed <= 0.02
    )));
    let slide = s
        .exam
        .phases
        .iter()
        .position(|p| matches!(p, PhaseConfig::Slide { .. }))
        .unwrap();
    assert!(matches!(
        s.exam.phases.get(slide + 1),
        Some(PhaseConfig::Hold { .. })
    ));
    // Mid-thigh: the exam stays well inside the segment z ∈ [−0.15, 0.15] m,
    // away from its held end rings.
    assert!(s.exam.skin_point[2].abs() < 0.05 && s.exam.start[2].abs() < 0.05);
    for source in ["Massie", "Mussa-Ivaldi", "Tsuji", "Colgate"] {
        assert!(
            FIG4_TOML.contains(source),
            "scenarios/fig4.toml does not cite {source}"
        );
    }
}

/// `hold` at 100 Hz trembles as in the paper (contact lost while the hand
/// presses, or a hold oscillation ≥ 20 % of the mean); `buffer` shows
/// neither; direct coupling does not either.
#[test]
fn hold_trembles_and_buffer_does_not() {
    let m = &shared().metrics;
    assert!(
        m.hold.hold_contact_losses > 0 || m.hold.hold_oscillation >= 0.2,
        "hold: {} losses, oscillation {:.3}",
        m.hold.hold_contact_losses,
        m.hold.hold_oscillation
    );
    for x in [&m.buffer, &m.direct] {
        assert_eq!(x.hold_contact_losses, 0);
        assert!(
            x.hold_oscillation < 0.2,
            "oscillation {:.3}",
            x.hold_oscillation
        );
        assert!(!x.trembles);
    }
    assert!(m.hold.trembles);
}

/// `buffer` at 100 Hz: the RMS of its tick-to-tick force change is at most
/// a third of `hold`'s, and it has less energy above 30 Hz.
#[test]
fn buffer_is_smoother_than_hold() {
    let m = &shared().metrics;
    assert!(
        m.buffer.rms_tick_change <= m.hold.rms_tick_change / 3.0,
        "buffer {:.4} N vs hold {:.4} N",
        m.buffer.rms_tick_change,
        m.hold.rms_tick_change
    );
    assert!(m.buffer.energy_above_30hz < m.hold.energy_above_30hz);
    assert!(m.buffer.rms_error < m.hold.rms_error);
}

/// `buffer` at 100 Hz stays within 10 % of the peak force of `direct` (RMS),
/// and never further than 20 % of it at any tick: no phantom contact at
/// lift-off (a parameter blend of successive spheres once rendered 6 N there
/// while `direct` was free). It measures 2.3 % RMS and 0.9 N at worst
/// (`docs/fig4/table.md`).
#[test]
fn buffer_tracks_direct() {
    let m = &shared().metrics;
    assert!(
        m.buffer.rms_error_rel < 0.10,
        "buffer RMS error {:.1} % of the peak",
        100.0 * m.buffer.rms_error_rel
    );
    assert!(
        m.buffer.peak_error < 0.2 * m.direct.peak_force,
        "buffer peak error {:.2} N vs direct peak {:.2} N",
        m.buffer.peak_error,
        m.direct.peak_force
    );
}

/// The same seed gives the same `metrics.json`, byte for byte; the files of
/// the experiment are all written.
#[test]
fn deterministic_and_written() {
    let s = default_fig4().unwrap();
    let a = serde_json::to_string_pretty(&shared().metrics).unwrap();
    let again = fig4(&s).unwrap();
    let b = serde_json::to_string_pretty(&again.metrics).unwrap();
    assert_eq!(a, b);
    let dir = std::env::temp_dir().join(format!("echothigh-fig4-{}", std::process::id()));
    let table = write_fig4(&dir, &s, shared()).unwrap();
    assert!(table.contains("| hold |") && table.contains("| buffer |"));
    assert_eq!(
        std::fs::read_to_string(dir.join("metrics.json")).unwrap(),
        a + "\n"
    );
    let csv = std::fs::read_to_string(dir.join("force.csv")).unwrap();
    assert!(csv.starts_with("t,buffer,hold,direct,"));
    assert_eq!(csv.lines().count(), 1 + shared().traces[0].force.len());
    for f in ["fig4.png", "fig4.svg", "table.md", "scenario.toml"] {
        assert!(std::fs::metadata(dir.join(f)).unwrap().len() > 100, "{f}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Over the human range of hand damping (2 N·s/m to 10 N·s/m), `hold`
/// trembles at the light end and stops above the sampled-data boundary
/// `b_device + b_hand > K (T/2 + τ)` (predicted ~5.4 N·s/m at mid-thigh),
/// which the sweep brackets, while `buffer` (like `direct`) never trembles.
#[test]
fn damping_sweep_shows_the_boundary() {
    let s = default_fig4().unwrap();
    let values = [2.0, 10.0];
    let out = sweep(&s, SweepKind::Damping, &values).unwrap();
    assert_eq!(largest_trembling(&out.rows, CouplingMode::Buffer), None);
    assert_eq!(largest_trembling(&out.rows, CouplingMode::Direct), None);
    let hold_at = |v: f64| {
        out.rows
            .iter()
            .find(|r| r.mode == CouplingMode::Hold && r.value == v)
            .unwrap()
            .metrics
    };
    assert!(hold_at(2.0).trembles);
    assert!(
        !hold_at(10.0).trembles,
        "hold still trembles at 10 N·s/m: {:?}",
        hold_at(10.0)
    );
    let b = bound(&s, &out.directs[0].1);
    assert!(b.local_stiffness > 0.0);
    assert!(
        (2.0..10.0).contains(&b.hold_critical_hand_damping),
        "predicted boundary {:.2} N·s/m outside the observed transition",
        b.hold_critical_hand_damping
    );
    assert!(b.hold_critical_damping > b.buffer_critical_damping * 10.0);
    // The prediction brackets the transition tightly, from both sides:
    // - at the predicted hand damping `hold` must not tremble: the
    //   condition `b > K (T/2 + τ)` is sufficient for passivity (Gil et al.
    //   2009), so a trembling there would falsify the model of the loop;
    // - at 0.35 × the prediction it must still tremble: on the cylinder of
    //   docs/fig4/stability.md the prediction was 5.35 N·s/m and the hold
    //   lost contact 3 times at 2 N·s/m (0.37 ×), the transition sharp
    //   (192 % peak-to-peak at 2 N·s/m, 8 % at 5).
    // A prediction off by more than that factor (the [2, 10) bracket above
    // allows 5×) fails one side or the other.
    let pred = b.hold_critical_hand_damping;
    let tight = sweep(&s, SweepKind::Damping, &[0.35 * pred, pred]).unwrap();
    let hold_tight = |v: f64| {
        tight
            .rows
            .iter()
            .find(|r| r.mode == CouplingMode::Hold && r.value == v)
            .unwrap()
            .metrics
    };
    assert!(
        hold_tight(0.35 * pred).trembles,
        "hold steady at 0.35 × the predicted {pred:.2} N·s/m: {:?}",
        hold_tight(0.35 * pred)
    );
    assert!(
        !hold_tight(pred).trembles,
        "hold trembles at the predicted {pred:.2} N·s/m: {:?}",
        hold_tight(pred)
    );
}
