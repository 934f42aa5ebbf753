//! `Renderer::render_into` allocates nothing after construction.

use echothigh_imaging::*;
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn render_into_does_not_allocate() {
    let cfg = ImagingConfig {
        columns: 128,
        rows: 192,
        ..Default::default()
    };
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let bone = r.anatomy().unwrap().femur_top();
    let presses: Vec<SectionDeformation> = (0..5)
        .map(|k| SectionDeformation::flat_press(k as f64 * 3e-3, 0.04, 1.5e-3, bone).unwrap())
        .collect();
    let mut out = vec![0u8; cfg.columns * cfg.rows];
    let ((), n) = count_allocations(|| {
        for (k, d) in presses.iter().enumerate() {
            let input = FrameInput {
                deformation: d,
                probe_pressure: k as f64 * 5000.0,
                time: k as f64 * 0.1,
                lateral_offset: 0.0,
            };
            r.render_into(&input, &mut out).unwrap();
            r.lumens(&input).unwrap();
        }
    });
    assert_eq!(n, 0, "render_into allocated {n} times");
    assert!(out.iter().any(|&p| p > 0));
}
