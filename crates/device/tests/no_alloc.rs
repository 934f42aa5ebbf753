//! `advance` and `set_force` allocate nothing: a counting global allocator
//! (this test binary only; one test function, so single-threaded).

use echothigh_device::{
    DeviceConfig, ExamConfig, ExamScript, HandConfig, HapticDevice, ReplayDevice, SimulatedDevice,
    SimulatedHand, Vec3,
};
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn advance_does_not_allocate() {
    let config = DeviceConfig::default();
    let scale = config.force_scale();
    let script = ExamScript::new(ExamConfig::default()).unwrap();
    let hand = SimulatedHand::scripted(HandConfig::default(), script).unwrap();
    let mut device = SimulatedDevice::with_hand(config, hand).unwrap();
    let mut replay = ReplayDevice::from_reader(
        "t,x,y,z\n0,0,0.1,0.15\n1,0,0.06,0.15\n2,0,0.06,0.17\n".as_bytes(),
        config,
    )
    .unwrap();
    let mut devices: [&mut dyn HapticDevice; 2] = [&mut device, &mut replay];

    // The whole default exam (~10 s at 1 kHz) against a linear tissue, through
    // the trait object as the haptic loop will call it, with NaN and
    // over-limit forces thrown in.
    let ((), n) = count_allocations(|| {
        for tick in 0..11_000u32 {
            for d in devices.iter_mut() {
                let depth = (0.072 - d.position().y).max(0.0);
                let mut f = scale.tissue_to_device(Vec3::new(0.0, 800.0 * depth, 0.0));
                if tick % 1000 == 7 {
                    f.x = f64::NAN;
                }
                if tick % 1000 == 11 {
                    f.y = 1e3;
                }
                d.set_force(f);
                d.advance(1e-3);
            }
        }
    });
    assert_eq!(n, 0, "advance allocated {n} times");
    assert!(device.exam_status().unwrap().phase == echothigh_device::ExamPhase::Done);
    assert_eq!(device.faults().non_finite, 11);
    assert!(replay.finished());
}
