//! The haptic tick and the model manager's update allocate nothing after
//! construction: 100 000 ticks with a model update (fit + handoff publish)
//! every 10 ticks, counted by a global allocator. One test function so that
//! no other thread allocates while counting.

use echothigh_haptics::{
    handoff, FitConfig, HapticRenderer, ModelManager, RenderConfig, Sample, TickTiming, TimingRing,
    Vec3,
};

use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn tick_and_update_do_not_allocate() {
    let (tx, rx) = handoff();
    let cfg = RenderConfig {
        texture_amplitude: 5e-5,
        ..RenderConfig::default()
    };
    let mut manager = ModelManager::new(&FitConfig::default(), tx).unwrap();
    let mut renderer = HapticRenderer::new(&cfg, rx).unwrap();
    let mut ring = TimingRing::new(1024);
    let (c, radius, k) = (Vec3::new(0.0, -0.08, 0.0), 0.08, 500.0);
    let mut checksum = 0.0;

    let ((), n) = count_allocations(|| {
        for i in 0..100_000u32 {
            let t = f64::from(i) * 1e-3;
            // Press 0–8 mm while sliding on a 2 cm circle.
            let lateral = Vec3::new(0.02 * (3.0 * t).cos(), 0.0, 0.02 * (3.0 * t).sin());
            let dir = (Vec3::new(0.0, radius, 0.0) + lateral).normalize();
            let p = c + dir * (radius + 0.002 - 0.005 * (1.0 - (0.9 * t).cos()));
            if i % 10 == 0 {
                let rho = (p - c).norm();
                let report = manager.update(&Sample {
                    time: t,
                    p,
                    distance: rho - radius,
                    gradient: (p - c) / rho,
                    stiffness: k,
                });
                checksum += report.residual;
            }
            if i == 50_000 {
                // A rejected sample and a NaN tick on the way.
                manager.update(&Sample {
                    time: t,
                    p: Vec3::new(f64::NAN, 0.0, 0.0),
                    distance: 0.0,
                    gradient: Vec3::y(),
                    stiffness: k,
                });
                renderer.tick(Vec3::new(f64::NAN, 0.0, 0.0), t);
            }
            let f = renderer.tick(p, t);
            checksum += f.norm();
            ring.push(TickTiming {
                compute_ns: i,
                cpu_ns: 0,
                period_error_ns: 0,
            });
        }
    });

    assert!(checksum.is_finite() && checksum > 0.0);
    assert_eq!(n, 0, "allocations in the hot loop");
}
