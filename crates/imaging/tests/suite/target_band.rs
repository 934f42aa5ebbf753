//! The gauge's target band (issue 19): the forces it names are those at
//! which the image's own force chain coapts a healthy vein and makes the
//! artery clearly oval, whatever the vein's disease.

use echothigh_imaging::*;

/// Issue 13's coaptation criterion (lumen < 10 % of rest), as the runtime's
/// `COAPTED_RATIO`.
const COAPTED: f64 = 0.10;

fn renderer(state: VeinState) -> Renderer {
    let cfg = ImagingConfig {
        columns: 64,
        rows: 96,
        ..Default::default()
    };
    Renderer::new(&cfg, state).unwrap()
}

fn frame(def: &SectionDeformation, force: f64, area: f64) -> FrameInput<'_> {
    FrameInput {
        deformation: def,
        probe_pressure: force / area,
        time: 0.0,
        lateral_offset: 0.0,
    }
}

/// At rest and pressed 6 mm: pressing with the band's lower force leaves the
/// healthy vein's lumen at the coaptation ratio, and with its upper force
/// puts 120 mmHg at the artery's centre. The bisection stops within 1e-3 Pa
/// of the law's crossing, and the law's slope there is below 1 / (27 mmHg)
/// (8 → 35 mmHg collapse), so the ratio is within 1e-6 of 0.10; the
/// artery's stress is the forward formula of the inverse, to 1e-9 relative.
/// The band is ordered (the vein closes first: issue 12's forces test) and
/// grows when the vessels are farther from the face.
#[test]
fn band_ends_reproduce_coaptation_and_the_clear_oval() {
    let r = renderer(VeinState::Healthy);
    let a = r.anatomy().unwrap();
    let area = r.config().probe_area();
    let mut bands = Vec::new();
    for press in [0.0, 0.006] {
        let def = SectionDeformation::flat_press(press, 0.04, 0.003, a.femur_top()).unwrap();
        let band = r
            .target_band(&frame(&def, 1.0, area), COAPTED)
            .unwrap()
            .unwrap();
        assert!(
            band.walls_meet > 0.0 && band.walls_meet < band.artery_clearly_oval,
            "{band:?}"
        );
        let lumens = r
            .lumens(&frame(&def, band.walls_meet, area))
            .unwrap()
            .unwrap();
        let ratio = lumens.vein.area / lumens.vein.rest_area;
        assert!(
            (ratio - COAPTED).abs() < 1e-6,
            "vein ratio {ratio} at {band:?}"
        );
        let lumens = r
            .lumens(&frame(&def, band.artery_clearly_oval, area))
            .unwrap()
            .unwrap();
        let p = lumens.artery.tissue_pressure;
        assert!(
            (p / ARTERY_CLEARLY_OVAL - 1.0).abs() < 1e-9,
            "artery {p} Pa"
        );
        bands.push(band);
    }
    assert!(bands[1].walls_meet < bands[0].walls_meet, "{bands:?}");
}

/// The band does not give the diagnosis away: a thrombosed vein's section
/// shows the same band as a healthy one's. Both ends are the same
/// arithmetic on the same vessel centres, so they agree to rounding
/// (1e-9 relative).
#[test]
fn band_is_the_same_for_a_thrombosed_vein() {
    let h = renderer(VeinState::Healthy);
    let area = h.config().probe_area();
    let def = SectionDeformation::rest(h.anatomy().unwrap().femur_top());
    let band = |r: &Renderer| {
        r.target_band(&frame(&def, 2.0, area), COAPTED)
            .unwrap()
            .unwrap()
    };
    let hb = band(&h);
    for state in [VeinState::Acute, VeinState::Chronic] {
        let b = band(&renderer(state));
        assert!(
            (b.walls_meet / hb.walls_meet - 1.0).abs() < 1e-9,
            "{state:?}: {b:?} vs {hb:?}"
        );
        assert!(
            (b.artery_clearly_oval / hb.artery_clearly_oval - 1.0).abs() < 1e-9,
            "{state:?}"
        );
    }
}

/// Bad requests give no band rather than a wrong one, and a NaN frame is an error.
#[test]
fn no_band_for_a_bad_ratio_or_a_phantom_and_an_error_for_nan() {
    let r = renderer(VeinState::Healthy);
    let area = r.config().probe_area();
    let def = SectionDeformation::rest(r.anatomy().unwrap().femur_top());
    for bad in [0.0, 1.0, -0.1, f64::NAN] {
        assert!(
            r.target_band(&frame(&def, 1.0, area), bad)
                .unwrap()
                .is_none(),
            "{bad}"
        );
    }
    assert!(r
        .target_band(&frame(&def, f64::NAN, area), COAPTED)
        .is_err());
    let cfg = ImagingConfig {
        columns: 64,
        rows: 96,
        ..Default::default()
    };
    let p = Renderer::phantom(
        &cfg,
        &Phantom::Uniform {
            density: 1e8,
            seed: 1,
        },
    )
    .unwrap();
    assert!(p
        .target_band(&frame(&def, 1.0, area), COAPTED)
        .unwrap()
        .is_none());
}
