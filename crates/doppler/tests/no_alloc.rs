//! The per-frame and per-line paths allocate nothing after warm-up
//! (counting allocator of echothigh-testkit).

use echothigh_doppler::{
    AudioSynth, ColorConfig, ColorFlow, ColorMode, FlowConfig, FlowKind, FlowScene, FlowVessel,
    Maneuver, Maneuvers, Profile, PwConfig, PwDoppler, SegmentFlow, SpectralDisplay,
};
use echothigh_testkit::{count_allocations, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn spectral_line_audio_and_colour_frame_do_not_allocate() {
    let fc = FlowConfig::default();
    let flow = SegmentFlow::healthy(FlowKind::Vein, 0.2);
    let mut m = Maneuvers::scripted(Maneuver::Augment, 0.5, 0.0);
    let c = PwConfig::default();
    let mut pw = PwDoppler::new(&c, 5e-3, Profile::Parabolic, 0.0, 0.1).unwrap();
    let mut synth = AudioSynth::new(c.fft_size, c.hop(), 1);
    let mut audio = vec![[0.0f32; 2]; c.hop()];
    let mut column = vec![0u8; 256];
    let cols: Vec<f64> = (0..256).map(|j| (j as f64 - 128.0) * 1.5e-4).collect();
    let cc = ColorConfig::default();
    let mut cf = ColorFlow::new(&cc, ColorMode::Velocity, &cols, 384, 1.5e-4).unwrap();
    let bmode = vec![40u8; 256 * 384];
    let mut rgb = vec![0u8; 3 * 256 * 384];
    let mut scene = FlowScene::new();
    let display = SpectralDisplay::default();
    // Warm-up: one of each.
    let line = pw.line(|t| flow.velocity(&fc, &m, t, 1.0));
    synth.push(line, &mut audio);
    let ((), n) = count_allocations(|| {
        for k in 0..50 {
            m.release(1.0 + k as f64 * 0.1);
            let line = pw.line(|t| flow.velocity(&fc, &m, t, 1.0));
            display.column(line, c.prf, 1.0, &mut column);
            synth.push(line, &mut audio);
        }
        for k in 0..3 {
            scene.clear();
            scene.tissue_velocity = 0.001 * k as f64;
            scene.push(FlowVessel {
                lateral: 0.0,
                depth: 0.02,
                half_width: 0.005,
                half_height: 0.004,
                axial_velocity: 0.05,
                profile: Profile::Parabolic,
                fill: 0.3,
                central: false,
            });
            cf.frame(&bmode, &scene, &mut rgb).unwrap();
        }
    });
    assert_eq!(n, 0, "allocations in the per-line / per-frame path");
}
