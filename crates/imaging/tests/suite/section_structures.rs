//! The section's extra structures (issue 12): elliptic cuts, each vessel
//! by its own lumen law at its own tissue pressure.

use echothigh_imaging::pressure::stress_under_rectangle;
use echothigh_imaging::*;

/// The vertical chords of a rotated ellipse lie on it, and summed over the
/// columns give its area `π a b`. Midpoint sum over 10 µm columns of a
/// 3 × 1.5 mm ellipse: the error, from the chord's √ ends, is below
/// `(Δu / a)^1.5 ≈ 2e-5` relative; asserted 1e-4.
#[test]
fn rotated_ellipse_chords_lie_on_it_and_sum_to_its_area() {
    let v = Vessel {
        lateral: 0.002,
        depth: 0.02,
        radius: 3e-3,
        radius_b: 1.5e-3,
        angle: 0.4,
        wall: 0.0,
    };
    let (sn, cs) = v.angle.sin_cos();
    let on = |u: f64, d: f64| {
        let (du, dd) = (u - v.lateral, d - v.depth);
        let (xi, zeta) = (du * cs + dd * sn, -du * sn + dd * cs);
        (xi / v.radius).powi(2) + (zeta / v.radius_b).powi(2)
    };
    let step = 1e-5;
    let mut area = 0.0;
    for k in -400..400 {
        let u = v.lateral + (k as f64 + 0.5) * step;
        let (c, h) = v.chord(u, 0.0);
        if h > 0.0 {
            assert!((on(u, c - h) - 1.0).abs() < 1e-9 && (on(u, c + h) - 1.0).abs() < 1e-9);
            area += 2.0 * h * step;
        }
    }
    let exact = std::f64::consts::PI * v.radius * v.radius_b;
    assert!((area / exact - 1.0).abs() < 1e-4, "{area} vs {exact}");
}

/// A shallow and a deep extra vein and an extra artery under one press:
/// each lumen ratio is its own law at the Boussinesq pressure at its own
/// centre (to 1e-12), and the shallow vein, under more pressure, is
/// flatter than the deep one.
#[test]
fn each_vessel_follows_its_own_law_at_its_own_pressure() {
    let mut cfg = ImagingConfig {
        columns: 64,
        rows: 96,
        ..Default::default()
    };
    let st = |name: &str, kind, lateral: f64, depth: f64| StructureConfig {
        name: name.into(),
        kind,
        lateral,
        depth,
        radii: [2e-3, 2e-3],
        angle: 0.0,
        wall: 0.4e-3,
        condition: None,
    };
    cfg.anatomy.structures = vec![
        st("gsv", StructureKind::Vein, 0.012, 0.008),
        st("dfv", StructureKind::Vein, -0.004, 0.045),
        st("dfa", StructureKind::Artery, 0.006, 0.050),
    ];
    let r = Renderer::new(&cfg, VeinState::Healthy).unwrap();
    let a = r.anatomy().unwrap();
    let rest = SectionDeformation::rest(a.femur_top());
    // 20 mmHg-ish at depth: 4 kPa under the face.
    let input = FrameInput {
        deformation: &rest,
        probe_pressure: 4000.0,
        time: 0.3,
        lateral_offset: 0.0,
    };
    let mut ratio = Vec::new();
    for i in 0..a.vessels().len() {
        let l = r.vessel_lumen(i, &input).unwrap().unwrap();
        let v = &a.vessels()[i].vessel;
        let p = stress_under_rectangle(
            4000.0,
            cfg.probe_width,
            cfg.probe_elevation,
            v.lateral,
            0.0,
            v.depth,
        );
        let want = a.lumen_ratio(i, p, 0.3);
        assert!((l.area / l.rest_area - want).abs() < 1e-12, "vessel {i}");
        assert!((l.tissue_pressure - p).abs() < 1e-9);
        ratio.push(want);
    }
    assert!(r.vessel_lumen(5, &input).unwrap().is_none());
    // gsv (2) shallower than dfv (3): more pressure, flatter lumen.
    assert!(ratio[2] < ratio[3], "{ratio:?}");
    // The artery (4) follows the artery law, not the vein's.
    let p4 = stress_under_rectangle(
        4000.0,
        cfg.probe_width,
        cfg.probe_elevation,
        0.006,
        0.0,
        0.05,
    );
    assert!((ratio[4] - a.artery_lumen_ratio(p4, 0.3)).abs() < 1e-12);
}
