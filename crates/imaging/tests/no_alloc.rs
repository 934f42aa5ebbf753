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

/// The same with a section of many structures (the 3D leg's: extra veins
/// and arteries, a muscle outline, a lymph node), pressed hard enough to
/// collapse the veins and deform the arteries, and the veins' slow-flow
/// smoke switched on.
#[test]
fn render_into_with_extra_structures_does_not_allocate() {
    let mut cfg = ImagingConfig {
        columns: 128,
        rows: 192,
        ..Default::default()
    };
    let st = |name: &str, kind, lateral, depth, r: f64| StructureConfig {
        name: name.into(),
        kind,
        lateral,
        depth,
        radii: [r, 0.8 * r],
        angle: 0.3,
        wall: 0.5e-3,
        condition: None,
    };
    cfg.anatomy.structures = vec![
        st("gsv", StructureKind::Vein, 0.012, 0.008, 2e-3),
        st("dfv", StructureKind::Vein, -0.004, 0.040, 3e-3),
        st("dfa", StructureKind::Artery, 0.004, 0.045, 2.5e-3),
        st("sartorius", StructureKind::Muscle, -0.010, 0.016, 8e-3),
        st("lymph_node", StructureKind::LymphNode, 0.015, 0.020, 4e-3),
    ];
    cfg.texture.smoke = true;
    let mut r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    assert_eq!(r.anatomy().unwrap().vessels().len(), 5);
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
        }
    });
    assert_eq!(n, 0, "render_into allocated {n} times");
    assert!(out.iter().any(|&p| p > 0));
}
