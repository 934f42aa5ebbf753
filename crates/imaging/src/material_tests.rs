//! The material field's contract: same tissue, same scatterers whatever
//! window is built; the plane moves only within the margin.

use crate::{ImagingConfig, MaterialWindow, Renderer, VeinState};

fn cfg() -> ImagingConfig {
    ImagingConfig {
        columns: 64,
        rows: 96,
        pan_range: 1e-3,
        ..ImagingConfig::default()
    }
}

fn window(elevation: f64) -> MaterialWindow {
    MaterialWindow {
        lateral: 0.0,
        elevation,
        margin: 0.5e-3,
    }
}

/// The envelope of a frame at rest.
fn frame(r: &mut Renderer) -> Vec<f32> {
    let rest = crate::SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    r.render(&crate::FrameInput {
        deformation: &rest,
        probe_pressure: 0.0,
        time: 0.0,
        lateral_offset: 0.0,
    })
    .unwrap();
    let (c, n) = r.frame_size();
    (0..c)
        .flat_map(|j| (0..n).map(move |i| (j, i)))
        .map(|(j, i)| r.envelope(j, i))
        .collect()
}

#[test]
fn a_window_moved_within_its_margin_equals_one_built_there() {
    // The plane moved 0.3 mm by set_elevation and a field built at that
    // elevation hold the same scatterers with the same weights, but for
    // those the first window left outside its slab (weights < e^{−H²/2}
    // relative, H = 2.5: ~4 % in amplitude, at the slab's edge only): the
    // envelopes agree within 5 % of the frame's RMS.
    let mut a = Renderer::in_tissue(&cfg(), VeinState::Healthy, window(0.1)).unwrap();
    a.set_elevation(0.1003).unwrap();
    let mut b = Renderer::in_tissue(&cfg(), VeinState::Healthy, window(0.1003)).unwrap();
    let (fa, fb) = (frame(&mut a), frame(&mut b));
    let rms = (fb.iter().map(|v| (*v as f64).powi(2)).sum::<f64>() / fb.len() as f64).sqrt();
    let diff = (fa
        .iter()
        .zip(&fb)
        .map(|(x, y)| ((x - y) as f64).powi(2))
        .sum::<f64>()
        / fb.len() as f64)
        .sqrt();
    assert!(diff < 0.05 * rms, "difference {diff:.3e} vs rms {rms:.3e}");
}

#[test]
fn the_plane_stays_within_the_margin_to_rounding() {
    let w = window(0.2003);
    let mut r = Renderer::in_tissue(&cfg(), VeinState::Healthy, w).unwrap();
    // The edge, as a caller clamps to it (regression: `(e + m) − e`
    // exceeded `m` by a rounding and stopped the live imaging thread).
    let edge = (w.elevation + 1.0).clamp(w.elevation - w.margin, w.elevation + w.margin);
    r.set_elevation(edge).unwrap();
    r.set_elevation(w.elevation - w.margin).unwrap();
    assert!(r.set_elevation(w.elevation + 2.0 * w.margin).is_err());
    assert!(r.set_elevation(f64::NAN).is_err());
    let mut flat = Renderer::new(&cfg(), VeinState::Healthy).unwrap();
    assert!(
        flat.set_elevation(0.0).is_err(),
        "a 2-D field has no elevation"
    );
}
