//! The physics step with contact and the haptic queries allocate nothing
//! after warm-up (a global allocator counting per thread).

use echothigh_contact::{ContactParams, Probe, ProbeContact, QueryPath};
use echothigh_model::{ModelConfig, ThighModel, Vec3};
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn contact_step_and_queries_do_not_allocate() {
    let config = ModelConfig::default();
    let top = config.thigh.semi_axis_y;
    let mut model = ThighModel::new(&config).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    let pose = |d: f64| Probe::exam_pose(Vec3::new(0.001 * d.sin(), top - d, 0.0));
    // Warm-up: out of contact, then pressing.
    for i in 0..10 {
        pc.step(&mut model, &pose(0.004 - 0.001 * i as f64), 0.01);
    }
    let (touched, n) = count_allocations(|| {
        let mut touched = 0;
        for i in 0..40 {
            // Approach from 3 mm above to 8 mm deep and back: both query paths.
            let d = -0.003 + 0.011 * (1.0 - ((i as f64 - 20.0) / 20.0).abs());
            let s = pc.step(&mut model, &pose(d), 0.01);
            touched += s.sample.in_contact as usize;
        }
        touched
    });
    assert!(
        touched > 10 && touched < 40,
        "both paths exercised: {touched}"
    );
    assert_eq!(n, 0, "allocations during 40 contact steps");
}

/// Issue 18's paths: the grid kept in place (unchanged and rebinned; the
/// full rebuild runs in the warm-up and on the reference path), the
/// stiffness product reused from a solve that ran no iteration and computed
/// after one that did, the distance skipped in contact; and the previous
/// implementation ([`QueryPath::Reference`]).
#[test]
fn fast_and_reference_query_paths_do_not_allocate() {
    let config = ModelConfig::default();
    let top = config.thigh.semi_axis_y;
    for path in [QueryPath::Fast, QueryPath::Reference] {
        let mut model = ThighModel::new(&config).unwrap();
        let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
        pc.set_query_path(path);
        // Press 8 mm (40 steps), hold (60), slide 20 mm along the thigh (40).
        let pose = |i: usize| {
            let i = i as f64;
            let d = 0.008 * (i / 40.0).min(1.0);
            let z = 0.020 * ((i - 100.0) / 40.0).clamp(0.0, 1.0);
            Probe::exam_pose(Vec3::new(0.0, top - d, z))
        };
        pc.step(&mut model, &pose(0), 0.01); // warm-up
                                             // rebuilt, rebinned, unchanged, 0 it, > 0 it, unassembled
        let mut seen = [0usize; 6];
        let ((), n) = count_allocations(|| {
            for i in 1..140 {
                let s = pc.step(&mut model, &pose(i), 0.01);
                seen[pc.contact().grid().last_update() as usize] += 1;
                seen[3 + usize::from(s.query.stiffness_solve.iterations > 0)] += 1;
                seen[5] += usize::from(s.query.stiffness_unassembled);
            }
        });
        assert_eq!(n, 0, "allocations during 139 contact steps ({path:?})");
        // The warm-up built the grid; the reference rebuilds it every time.
        let grid_paths = match path {
            // The fast path's warm start also passes the stop test
            // matrix-free (no assembly) on some steps.
            QueryPath::Fast => seen[1] > 0 && seen[2] > 0 && seen[5] > 0,
            QueryPath::Reference => seen[0] == 139 && seen[5] == 0,
        };
        assert!(
            grid_paths && seen[3] > 0 && seen[4] > 0,
            "{path:?}: {seen:?}"
        );
    }
}

/// The active window (issue 18) under a sliding probe: the windowed step
/// (the contact through the patch's index translation) and its
/// re-centring allocate nothing, nor do the queries beside it.
#[test]
fn windowed_contact_steps_do_not_allocate() {
    let mut config = ModelConfig::default();
    config.integrator.window.enabled = true;
    config.integrator.window.radius = 0.03;
    let top = config.thigh.semi_axis_y;
    let mut model = ThighModel::new(&config).unwrap();
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default()).unwrap();
    // Press 8 mm (20 steps), then slide 60 mm along the thigh (60 steps).
    let pose = |i: usize| {
        let i = i as f64;
        let d = 0.008 * (i / 20.0).min(1.0);
        let z = -0.03 + 0.060 * ((i - 20.0) / 60.0).clamp(0.0, 1.0);
        Probe::exam_pose(Vec3::new(0.0, top - d, z))
    };
    pc.step(&mut model, &pose(0), 0.01); // warm-up: places the window
    let (touched, n) = count_allocations(|| {
        let mut touched = 0;
        for i in 1..80 {
            let s = pc.step(&mut model, &pose(i), 0.01);
            touched += usize::from(s.sample.in_contact);
        }
        touched
    });
    assert!(touched > 60, "in contact: {touched}");
    assert!(model.window().unwrap().moves() >= 3, "the window must move");
    assert_eq!(n, 0, "allocations during 79 windowed contact steps");
}
