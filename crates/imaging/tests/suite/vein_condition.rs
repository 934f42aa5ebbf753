//! Per-vein conditions (issue 13): the two-part lumen law, the content's
//! place in the lumen, and the global VeinState as the one-segment case.

use echothigh_imaging::{
    Anatomy, AnatomyConfig, ContentLayout, StructureConfig, StructureKind, Tissue, VeinCondition,
    VeinState, VeinStateParams, MMHG,
};

fn acute_fill(fill: f64, layout: ContentLayout) -> VeinCondition {
    let a = VeinStateParams::acute();
    VeinCondition {
        fill,
        layout,
        ..VeinCondition::of_state(VeinState::Acute, &a, &VeinStateParams::healthy())
    }
}

#[test]
fn global_states_keep_their_law() {
    // The one-segment case reproduces the old single law `1 − (1 − c_min) S(t)`.
    let cfg = AnatomyConfig::default();
    for state in VeinState::ALL {
        let a = Anatomy::new(&cfg, state).unwrap();
        let v = cfg.vein(state);
        for k in 0..=60 {
            let p = k as f64 * 5.0 * MMHG;
            let t = ((p - v.collapse_onset) / (v.collapse_full - v.collapse_onset)).clamp(0.0, 1.0);
            let old = 1.0 - (1.0 - v.min_lumen_ratio) * t * t * (3.0 - 2.0 * t);
            assert!(
                (a.vein_lumen_ratio(p) - old).abs() < 1e-12,
                "{state:?} at {p} Pa"
            );
        }
    }
}

#[test]
fn two_part_law_between_healthy_and_occlusive() {
    let big = 1e5; // beyond every full pressure
    assert_eq!(VeinCondition::healthy().lumen_ratio(big), 0.0);
    assert!((acute_fill(1.0, ContentLayout::Mural).lumen_ratio(big) - 0.8).abs() < 1e-12);
    // fill · 0.8 + (1 − fill) · 0
    let partial = acute_fill(0.4, ContentLayout::Mural);
    assert!((partial.lumen_ratio(big) - 0.32).abs() < 1e-12);
    assert!((partial.min_lumen_ratio() - 0.32).abs() < 1e-12);
    // Monotone in pressure.
    let mut last = 1.0;
    for k in 0..200 {
        let r = partial.lumen_ratio(k as f64 * MMHG);
        assert!(r <= last + 1e-15);
        last = r;
    }
}

/// The content's area is `fill` of the lumen's in both layouts: counted on a
/// 0.05 mm grid over a 5 mm-radius vein (≈ 31 000 points inside; the
/// boundary's discretisation error is ~ perimeter × step / area = 2 step / r
/// = 2 %, asserted 3 %), and it sits deep (mural) or central.
#[test]
fn content_fills_its_fraction_of_the_lumen() {
    for layout in [ContentLayout::Mural, ContentLayout::Central] {
        let cfg = AnatomyConfig {
            vein_condition: Some(acute_fill(0.4, layout)),
            ..Default::default()
        };
        let a = Anatomy::new(&cfg, VeinState::Healthy).unwrap();
        let v = *a.vein();
        let (mut lumen, mut content, mut deep) = (0usize, 0usize, 0usize);
        let step = 5e-5;
        let n = (v.radius / step) as i64 + 1;
        for i in -n..=n {
            for j in -n..=n {
                let (u, d) = (v.lateral + i as f64 * step, v.depth + j as f64 * step);
                match a.tissue_at(u, d) {
                    Tissue::VeinLumen => lumen += 1,
                    Tissue::Thrombus => {
                        content += 1;
                        if d > v.depth {
                            deep += 1;
                        }
                    }
                    _ => {}
                }
            }
        }
        let f = content as f64 / (lumen + content) as f64;
        assert!((f - 0.4).abs() < 0.4 * 0.03, "{layout:?}: content {f}");
        let deep_share = deep as f64 / content as f64;
        match layout {
            ContentLayout::Mural => assert!(deep_share > 0.99, "mural content deep: {deep_share}"),
            ContentLayout::Central => {
                assert!((deep_share - 0.5).abs() < 0.02, "central: {deep_share}")
            }
        }
        // Echoes: blood at the healthy content's, thrombus at the condition's.
        // (0.9 of the vertical semi-axis: a partly filled vein is oval.)
        let (top, bottom) = (v.depth - 0.9 * v.radius_b, v.depth + 0.9 * v.radius_b);
        let probe = if layout == ContentLayout::Mural {
            bottom
        } else {
            v.depth
        };
        assert_eq!(
            a.echo_at(v.lateral, probe),
            Some(VeinStateParams::acute().content_echo)
        );
        assert_eq!(a.echo_at(v.lateral, top), Some(cfg.healthy.content_echo));
    }
}

#[test]
fn structure_veins_carry_their_own_condition() {
    let mut cfg = AnatomyConfig::default();
    let mut chronic = VeinCondition::of_state(
        VeinState::Chronic,
        &VeinStateParams::chronic(),
        &cfg.healthy,
    );
    chronic.fill = 0.5;
    let st = |condition| StructureConfig {
        name: "gsv".into(),
        kind: StructureKind::Vein,
        lateral: 0.015,
        depth: 0.007,
        radii: [2e-3, 2e-3],
        angle: 0.0,
        wall: 0.4e-3,
        condition,
    };
    cfg.structures = vec![st(Some(chronic)), st(None)];
    cfg.structures[1].lateral = -0.02;
    let a = Anatomy::new(&cfg, VeinState::Healthy).unwrap();
    let big = 1e5;
    // Studied vein healthy, the first GSV chronic (0.5·0.95 + 0.5·0), the second healthy.
    assert_eq!(a.lumen_ratio(0, big, 0.0), 0.0);
    assert!((a.lumen_ratio(2, big, 0.0) - 0.475).abs() < 1e-12);
    assert_eq!(a.lumen_ratio(3, big, 0.0), 0.0);
    // Its radius shrinks by the chronic diameter factor and its wall thickens.
    assert!((a.vessels()[2].vessel.radius - 2e-3 * 0.85).abs() < 1e-15);
    assert_eq!(a.vessels()[2].vessel.wall, 1.5e-3);
    // A condition on an artery is refused, naming the key.
    cfg.structures[1].kind = StructureKind::Artery;
    cfg.structures[1].condition = Some(chronic);
    let e = Anatomy::new(&cfg, VeinState::Healthy)
        .unwrap_err()
        .to_string();
    assert!(e.contains("structures[1].condition"), "{e}");
}
