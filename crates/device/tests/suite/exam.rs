//! The exam script's phases, against a synthetic linear tissue `F = k·depth`.

use echothigh_device::{
    DeviceConfig, ExamConfig, ExamInput, ExamPhase, ExamScript, HandConfig, HapticDevice,
    PhaseConfig, SimulatedDevice, SimulatedHand, Vec3,
};

const SKIN_Y: f64 = 0.072;

/// Synthetic tissue: a linear spring of stiffness `k` (N/m) below the skin
/// plane `y = SKIN_Y`, pushing the probe back along +y (tissue force, N).
fn tissue_force(k: f64, p: Vec3) -> Vec3 {
    let depth = SKIN_Y - p.y;
    Vec3::new(0.0, k * depth.max(0.0), 0.0)
}

/// An ideal (kinematic) hand: the probe is exactly at the setpoint.
#[test]
fn press_stops_at_target_force_with_an_ideal_hand() {
    let k = 800.0;
    let dt = 1e-3;
    let mut script = ExamScript::new(ExamConfig::default()).unwrap();
    let mut force = 0.0;
    let mut transitions = Vec::new();
    let mut last = script.status().phase;
    for _ in 0..20_000 {
        let p = script.advance(
            dt,
            ExamInput {
                position: script.setpoint(),
                felt_tissue_force: force,
            },
        );
        force = tissue_force(k, p).y;
        let status = script.status();
        if status.phase != last {
            // Exact transition time: the new phase has run `phase_time` of this step.
            transitions.push((last, status.phase, status.time - status.phase_time, p));
            last = status.phase;
        }
    }
    use ExamPhase::*;
    let phases: Vec<_> = transitions.iter().map(|t| t.1).collect();
    assert_eq!(
        phases,
        [Press, Hold, Slide, Hold, Release, Approach, Press, Hold, Slide, Hold, Release, Done]
    );
    // Approach: 15 mm at 50 mm/s = 0.3 s.
    assert!((transitions[0].2 - 0.3).abs() < 1e-9);
    // (the setpoint is sampled at the step's end: the press moved it for the rest of the step)
    let y0 = transitions[0].3.y;
    assert!(
        y0 <= 0.077 + 1e-12 && y0 >= 0.077 - 0.04 * dt - 1e-12,
        "{y0}"
    );
    // Press ends at the first step where F ≥ 10 N: depth 12.5 mm, within one step's travel.
    let (_, _, t_press_end, p_press_end) = transitions[1];
    let depth = SKIN_Y - p_press_end.y;
    assert!(
        depth >= 10.0 / k - 1e-12 && depth <= 10.0 / k + 0.04 * dt + 1e-12,
        "{depth}"
    );
    // Hold 1 s exactly (the hold starts inside a step, keeps the rest).
    assert!((transitions[2].2 - t_press_end - 1.0).abs() < 1e-9);
    // Slide 20 mm along z at 10 mm/s at constant depth.
    let (_, _, t_slide_end, p_slide_end) = transitions[3];
    assert!((t_slide_end - transitions[2].2 - 2.0).abs() < 1e-9);
    assert!((p_slide_end - p_press_end - Vec3::new(0.0, 0.0, 0.02)).norm() < 1e-12);
    // Release ends 5 mm above the skin; the second approach goes back 20 mm
    // along z to mid-thigh at 50 mm/s.
    assert!((transitions[5].3.y - (SKIN_Y + 0.005)).abs() < 1e-12);
    assert!((transitions[6].2 - transitions[5].2 - 0.4).abs() < 1e-9);
    assert!((transitions[6].3.z - (-0.01)).abs() < 1e-12);
    assert_eq!(script.status().phase, Done);
    // Done after the second slide's release: the setpoint stays there.
    assert!((script.setpoint() - Vec3::new(0.0, SKIN_Y + 0.005, 0.01)).norm() < 1e-12);
    assert!(script.is_done());
    assert_eq!(script.status().repetition, 2);
    // The release rises from the held depth to 5 mm above the skin at 80 mm/s.
    let last = transitions.len() - 1;
    let rise = transitions[last - 1].3.y - SKIN_Y;
    let expected = (0.005 - rise) / 0.08;
    let err = transitions[last].2 - transitions[last - 1].2 - expected;
    // `rise` is read from the setpoint sampled at the end of the step in
    // which the release began; allow the two steps that sampling spans.
    assert!(err.abs() < 2.0 * dt + 1e-9, "release duration off by {err}");
}

#[test]
fn press_stops_at_max_depth_without_force() {
    let config = ExamConfig {
        repeat: 1,
        ..ExamConfig::default()
    };
    let mut script = ExamScript::new(config).unwrap();
    let mut deepest: f64 = 0.0;
    for _ in 0..8000 {
        let p = script.setpoint();
        script.advance(
            1e-3,
            ExamInput {
                position: p,
                felt_tissue_force: 0.0,
            },
        );
        if script.status().phase == ExamPhase::Press || script.status().phase == ExamPhase::Hold {
            deepest = deepest.max(script.depth(p));
        }
    }
    assert!(script.is_done());
    assert!(
        (0.025..=0.025 + 0.04e-3 + 1e-12).contains(&deepest),
        "{deepest}"
    );
}

#[test]
fn phase_timing_does_not_depend_on_step_size() {
    // Without a force-triggered phase the script is a pure function of time.
    let config = ExamConfig {
        repeat: 1,
        phases: vec![
            PhaseConfig::Approach {
                point: [0.0, 0.08, -0.01],
                speed: 0.03,
            },
            PhaseConfig::Hold { duration: 0.37 },
            PhaseConfig::Slide {
                direction: [1.0, -0.5, 0.0],
                distance: 0.013,
                speed: 0.011,
            },
            PhaseConfig::Release {
                speed: 0.07,
                clearance: 0.02,
            },
        ],
        ..ExamConfig::default()
    };
    let run = |dt: f64| {
        let mut s = ExamScript::new(config.clone()).unwrap();
        let input = ExamInput {
            position: Vec3::zeros(),
            felt_tissue_force: 0.0,
        };
        let mut trace = Vec::new();
        for i in 1..=(2.5 / dt).round() as usize {
            s.advance(dt, input);
            if i % (0.01 / dt).round() as usize == 0 {
                trace.push((s.setpoint(), s.status().phase));
            }
        }
        trace
    };
    let coarse = run(1e-3);
    let fine = run(1e-4);
    assert_eq!(coarse.len(), fine.len());
    for ((a, pa), (b, pb)) in coarse.iter().zip(&fine) {
        assert!((a - b).norm() < 1e-12, "{a:?} vs {b:?}");
        assert_eq!(pa, pb);
    }
    // The slide direction lost its press component: depth kept, 13 mm along x.
    let end = coarse.last().unwrap().0;
    assert!((end.x - 0.013).abs() < 1e-12);
    assert!((end.y - (0.072 + 0.02)).abs() < 1e-12);
}

/// The full chain: scripted hand, simulated device, synthetic tissue rendered
/// through the force scale at 1 kHz.
#[test]
fn default_exam_on_simulated_device_against_linear_tissue() {
    let k = 800.0;
    let config = DeviceConfig::default();
    let scale = config.force_scale();
    let script = ExamScript::new(ExamConfig::default()).unwrap();
    let hand = SimulatedHand::scripted(HandConfig::default(), script).unwrap();
    let mut device = SimulatedDevice::with_hand(config, hand).unwrap();
    let mut last = device.exam_status().unwrap().phase;
    let mut press_end_force = Vec::new();
    let mut hold_forces: Vec<f64> = Vec::new();
    let mut slide_start_z = 0.0;
    let mut slide_travel = Vec::new();
    let mut max_device_force: f64 = 0.0;
    let mut end_time = None;
    for tick in 0..15_000 {
        let tissue = tissue_force(k, device.position());
        device.set_force(scale.tissue_to_device(tissue));
        max_device_force = max_device_force.max(device.force().norm());
        device.advance(1e-3);
        let status = device.exam_status().unwrap();
        if status.phase != last {
            match (last, status.phase) {
                (ExamPhase::Press, ExamPhase::Hold) => {
                    press_end_force.push(device.felt_tissue_force());
                }
                (ExamPhase::Hold, ExamPhase::Slide) => slide_start_z = device.position().z,
                (ExamPhase::Slide, _) => slide_travel.push(device.position().z - slide_start_z),
                (_, ExamPhase::Done) => end_time = Some((tick + 1) as f64 * 1e-3),
                _ => {}
            }
            last = status.phase;
        }
        if status.phase == ExamPhase::Hold && status.phase_index == 2 && status.phase_time > 0.3 {
            hold_forces.push(tissue.y);
        }
    }
    assert_eq!(press_end_force.len(), 2);
    for f in &press_end_force {
        // Ends on the first tick at ≥ 10 N; one tick of ramp adds < 0.1 N.
        assert!((10.0..10.1).contains(f), "press ended at {f} N");
    }
    // After the transient, the hold keeps the press near 10 N (the setpoint
    // is frozen where the hand's spring balanced ~10 N of tissue force).
    let mean = hold_forces.iter().sum::<f64>() / hold_forces.len() as f64;
    assert!((mean - 10.0).abs() < 1.0, "mean hold force {mean}");
    assert!(hold_forces.iter().all(|f| (f - 10.0).abs() < 2.0));
    // The probe follows the 20 mm slide (within the hand's tracking error).
    for d in &slide_travel {
        assert!((d - 0.02).abs() < 1e-3, "slide travel {d}");
    }
    assert!(max_device_force <= config.max_force + 1e-12);
    let t = end_time.expect("exam finished");
    assert!((7.0..11.0).contains(&t), "exam took {t} s");
    println!("exam took {t} s, press ends {press_end_force:?} N, hold mean {mean} N");
}

/// A user script of instant phases (slides of 0 m) at the largest list and
/// repeat count the config accepts (1000 × 1000 = 10⁶ transitions) is run one
/// pass per advance, not all at once: after one 1 ms step the script has
/// finished exactly one pass of its 1000 phases, and it is done after
/// exactly `repeat` = 1000 steps. Without the bound the first step ends it.
#[test]
fn instant_phases_run_one_pass_per_advance() {
    let slide = PhaseConfig::Slide {
        direction: [0.0, 0.0, 1.0],
        distance: 0.0,
        speed: 0.01,
    };
    let config = ExamConfig {
        repeat: 1000,
        phases: vec![slide; echothigh_device::MAX_PHASES],
        ..ExamConfig::default()
    };
    let mut script = ExamScript::new(config).unwrap();
    let input = ExamInput {
        position: script.setpoint(),
        felt_tissue_force: 0.0,
    };
    script.advance(1e-3, input);
    let s = script.status();
    assert_eq!(
        (s.phase, s.phase_index, s.repetition),
        (ExamPhase::Slide, 0, 1)
    );
    for _ in 1..999 {
        script.advance(1e-3, input);
    }
    assert!(!script.is_done());
    script.advance(1e-3, input);
    assert!(script.is_done());
    assert_eq!(script.status().repetition, 1000);
}
