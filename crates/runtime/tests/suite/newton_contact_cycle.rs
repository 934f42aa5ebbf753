//! Regression test of issue 18's Newton 2-cycle: in `direct` coupling (the
//! physics stepped inside the 1 kHz tick, h = 1 ms) on the built-in
//! scenario's whole-leg mesh (lean-male, 48 × 27 nodes), four steps of the
//! built-in exam ran Newton to its 8-iteration cap, one face sample of the
//! penalty contact entering and leaving penetration on alternate iterates,
//! and each cost 2–3 ms: three ticks' worth.
//!
//! The test plays the exam `echothigh run --mode direct` plays (the
//! scripted device through the real-time tick, on the tick's own clock,
//! unpaced) and asserts that every physics step stopped on a convergence
//! test, in few Newton iterations.

use echothigh_runtime::deploy::scripted_device;
use echothigh_runtime::haptic_side::haptic_side_for;
use echothigh_runtime::live::CouplingMode;
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_runtime::scenario::Scenario;
use echothigh_runtime::tick::{HapticTick, TickObserver};
use echothigh_runtime::trace::PhysicsRecord;
use echothigh_transport::ProbeMsg;

/// Newton iterations of every physics step, in order.
#[derive(Default)]
struct Iterations(Vec<u32>);

impl TickObserver for Iterations {
    fn on_physics_step(&mut self, _: &PhysicsSide, _: &ProbeMsg, step: &PhysicsRecord) {
        self.0.push(step.newton_iterations);
    }
}

#[test]
fn direct_exam_steps_converge_without_cycling_the_contact_set() {
    let mut s = Scenario::builtin().unwrap();
    s.coupling.mode = CouplingMode::Direct;
    // The whole mesh at the haptic rate, where the cycle was found.
    s.coupling.direct_window = false;
    s.validate().unwrap();
    let period = s.coupling.haptic_period();
    assert_eq!(period, 1e-3, "the direct tick steps h = 1 ms");
    let (_, source) = haptic_side_for(CouplingMode::Direct, &s).unwrap();
    let physics = PhysicsSide::new(&s).unwrap();
    assert_eq!(physics.model().node_count(), 48 * 27);
    let scale = s.device().force_scale();
    let mut tick = HapticTick::new(
        scripted_device(&s).unwrap(),
        source,
        scale,
        Some(physics),
        period,
    );
    tick.set_orientation(s.probe_orientation().unwrap());
    tick.set_direct_queries(false);
    // The whole exam `run --mode direct` plays: its duration in ticks.
    let ticks = (s.run.duration / period).round() as usize;
    let mut seen = Iterations::default();
    for i in 0..ticks {
        tick.tick(i as f64 * period, &mut seen).unwrap();
    }
    let steps = &seen.0;
    assert_eq!(steps.len(), ticks, "one physics step per direct tick");
    let cap = s.integrator.newton_max_iterations;
    // The bound: a converging step needs one solve for the step's load and
    // one more per change of the contact's active set that its first solve
    // makes (a sample entering or leaving: a kink of the force, after which
    // Newton is on one linear piece), then the relative test (newton_tol,
    // 2e-2) holds after the next solve, since on a linear piece one solve
    // leaves the PCG's own residual (cg_tol, 1e-2; the springs are nearly
    // linear over a 1 ms step's motion): 1 + 1 + 1 = 3. A step at
    // the cap (8) did not converge; a cycle between two sets never does.
    let bound = 3;
    let worst: Vec<(usize, u32)> = steps
        .iter()
        .copied()
        .enumerate()
        .filter(|&(_, n)| n > bound)
        .collect();
    let capped = steps.iter().filter(|&&n| n >= cap).count();
    let mut histogram = vec![0usize; cap as usize + 1];
    for &n in steps {
        histogram[n.min(cap) as usize] += 1;
    }
    let over_one: Vec<(usize, u32)> = steps
        .iter()
        .copied()
        .enumerate()
        .filter(|&(_, n)| n > 1)
        .collect();
    println!("steps per Newton iteration count (0..={cap}): {histogram:?}");
    println!("steps of more than one iteration (tick, iterations): {over_one:?}");
    assert!(
        worst.is_empty(),
        "{} of {} steps took more than {bound} Newton iterations ({capped} at the cap of \
         {cap}): {:?}; steps per iteration count {:?}",
        worst.len(),
        steps.len(),
        &worst[..worst.len().min(20)],
        histogram
    );
}
