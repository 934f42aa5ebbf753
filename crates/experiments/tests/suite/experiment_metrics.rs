//! The Fig. 4 measures on signals whose answers are known by hand.

use echothigh_experiments::metrics::{
    device_energy, errors, hold_losses, hold_oscillation, hold_segments, measure, tick_changes,
    ZERO_FORCE,
};
use echothigh_experiments::trace::ModeTrace;
use echothigh_runtime::live::CouplingMode;

fn trace(force: Vec<f64>, holding: Vec<bool>) -> ModeTrace {
    let n = force.len();
    ModeTrace {
        mode: CouplingMode::Hold,
        period: 1e-3,
        t: (0..n).map(|i| i as f64 * 1e-3).collect(),
        force,
        device_force: vec![[0.0; 3]; n],
        device_position: vec![[0.0; 3]; n],
        final_position: [0.0; 3],
        holding,
        phase: vec![2; n],
        step_stiffness: vec![],
        step_t: vec![],
        faults: 0,
    }
}

/// A ramp of slope 0.01 N per tick changes by exactly 0.01 N each tick; a
/// single 3 N step is the largest change and sets the RMS to 3/√(n−1).
#[test]
fn tick_changes_of_ramp_and_step() {
    let ramp: Vec<f64> = (0..101).map(|i| 0.01 * i as f64).collect();
    let (max, rms) = tick_changes(&ramp);
    assert!((max - 0.01).abs() < 1e-12 && (rms - 0.01).abs() < 1e-12);
    let mut step = vec![1.0; 10];
    step.extend(vec![4.0; 10]);
    let (max, rms) = tick_changes(&step);
    assert!((max - 3.0).abs() < 1e-12);
    assert!((rms - 3.0 / 19f64.sqrt()).abs() < 1e-12);
}

/// RMS and peak error of a constant offset are the offset.
#[test]
fn errors_of_an_offset() {
    let a: Vec<f64> = (0..50).map(|i| i as f64).collect();
    let b: Vec<f64> = a.iter().map(|x| x + 0.5).collect();
    let (rms, peak) = errors(&b, &a);
    assert!((rms - 0.5).abs() < 1e-12 && (peak - 0.5).abs() < 1e-12);
}

/// Two holds; in the first the force drops to zero twice (two losses, five
/// zero ticks); the second starts at zero (never touched: no loss).
#[test]
fn contact_losses_count_drops_after_contact_only() {
    let f = vec![
        5.0, 5.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 5.0, 9.0, 0.0, 0.0, 3.0,
    ];
    let h = vec![
        true, true, true, true, true, true, true, true, true, false, true, true, true,
    ];
    assert_eq!(hold_segments(&h), vec![(0, 9), (10, 13)]);
    assert_eq!(hold_losses(&f, &h), (2, 5));
    // Just above the threshold is contact.
    let g = vec![1.0, ZERO_FORCE * 1.5, 1.0];
    assert_eq!(hold_losses(&g, &[true; 3]), (0, 0));
}

/// A 10 N hold with a ±1 N oscillation after a settling transient: the
/// transient is skipped, the peak-to-peak over the mean is 0.2.
#[test]
fn hold_oscillation_skips_the_settling() {
    let mut f = vec![20.0; 100];
    f.extend((0..1000).map(|i| 10.0 + (i as f64 * 0.3).sin()));
    let h = vec![true; f.len()];
    let osc = hold_oscillation(&f, &h, 100);
    assert!((osc - 0.2).abs() < 2e-3, "{osc}");
    assert!(hold_oscillation(&f, &h, 0) > 1.0);
}

/// Work of a held force: 2 N along +y over three 1 mm steps is 6 mJ into
/// the user; pushing against the motion gives the opposite sign.
#[test]
fn device_energy_sign_and_value() {
    let p = vec![[0.0, 0.0, 0.0], [0.0, 0.001, 0.0], [0.0, 0.002, 0.0]];
    let f = vec![[0.0, 2.0, 0.0]; 3];
    let w = device_energy(&f, &p, [0.0, 0.003, 0.0]);
    assert!((w - 0.006).abs() < 1e-15);
    let g = vec![[0.0, -2.0, 0.0]; 3];
    assert!((device_energy(&g, &p, [0.0, 0.003, 0.0]) + 0.006).abs() < 1e-15);
}

/// A staircase (force held at 100 Hz) against its smooth source: trembles
/// no more than the source in the hold, but has more energy above 30 Hz and
/// a larger tick-to-tick change, and a non-zero error.
#[test]
fn measure_a_held_staircase() {
    let n = 2000;
    let smooth: Vec<f64> = (0..n)
        .map(|i| 5.0 + 4.0 * (std::f64::consts::PI * i as f64 / n as f64).sin())
        .collect();
    let held: Vec<f64> = (0..n).map(|i| smooth[i - i % 10]).collect();
    let hold_flags = vec![false; n];
    let ms = measure(&trace(smooth.clone(), hold_flags.clone()), &smooth);
    let mh = measure(&trace(held, hold_flags), &smooth);
    assert_eq!(ms.rms_error, 0.0);
    assert!(
        mh.rms_error > 0.0 && mh.peak_error <= 10.0 * 4.0 * std::f64::consts::PI / n as f64 + 1e-12
    );
    assert!(mh.energy_above_30hz > 10.0 * ms.energy_above_30hz);
    assert!(mh.max_tick_change > 5.0 * ms.max_tick_change);
    assert!(!ms.trembles && !mh.trembles);
    assert!((ms.peak_force - 9.0).abs() < 1e-3);
}
