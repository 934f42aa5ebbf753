//! The physics step with contact and the haptic queries allocate nothing
//! after warm-up (a counting global allocator; one test, single-threaded).

use echothigh_contact::{ContactParams, Probe, ProbeContact};
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
