//! The bridge from the physical model to the echographic image (`DESIGN.md`
//! §5): the skin's inward displacement along the image section under the
//! probe, read off the deformed mesh, and the probe pressure.
//!
//! For each lateral position `u` along the probe's width, a ray is cast from
//! above the face along the contact direction `k̂`; the skin displacement is
//! the distance between where it meets the deformed surface and where it
//! meets the rest surface (positive inward). The imaging crate carries it
//! into depth towards the femur, as the normal springs do.

use echothigh_imaging::SectionDeformation;
use echothigh_model::{ThighGeometry, ThighModel, Vec3};
use nalgebra::Isometry3;

/// Distance from `o` along unit `d` to triangle `(a, b, c)` (Möller–Trumbore),
/// if the ray hits it.
fn ray_triangle(o: &Vec3, d: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = d.cross(&e2);
    let det = e1.dot(&pv);
    if det.abs() < 1e-18 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - a;
    let u = tv.dot(&pv) * inv;
    if !(-1e-9..=1.0 + 1e-9).contains(&u) {
        return None;
    }
    let qv = tv.cross(&e1);
    let v = d.dot(&qv) * inv;
    if v < -1e-9 || u + v > 1.0 + 1e-9 {
        return None;
    }
    let t = e2.dot(&qv) * inv;
    (t >= 0.0).then_some(t)
}

/// First hit of the ray `o + t d` (t ≥ 0) with the surface at positions `x`,
/// considering only the triangles listed in `near`.
fn first_hit(x: &[Vec3], tris: &[[usize; 3]], near: &[usize], o: &Vec3, d: &Vec3) -> Option<f64> {
    let mut best: Option<f64> = None;
    for &t in near {
        let [a, b, c] = tris[t];
        if let Some(s) = ray_triangle(o, d, &x[a], &x[b], &x[c]) {
            best = Some(best.map_or(s, |b: f64| b.min(s)));
        }
    }
    best
}

/// Reusable scratch for [`section_deformation`].
#[derive(Debug, Clone, Default)]
pub struct SectionScratch {
    near: Vec<usize>,
}

/// Fills `out` with the skin displacement (m, inward) at `samples` lateral
/// positions spread over `width` (m) centred on the probe at `pose`, from the
/// model's deformed and rest surfaces. `bone_depth` (m) is copied into
/// `out`. Allocation-free once `out` and `scratch` have grown.
pub fn section_deformation(
    model: &ThighModel,
    pose: &Isometry3<f64>,
    width: f64,
    samples: usize,
    bone_depth: f64,
    scratch: &mut SectionScratch,
    out: &mut SectionDeformation,
) {
    let mesh = model.mesh();
    let tris = mesh.triangles();
    let (x, rest) = (model.positions(), mesh.rest_positions());
    let lateral = pose.rotation * Vec3::x();
    let elevation = pose.rotation * Vec3::z();
    let k = pose.rotation * -Vec3::y();
    let p = pose.translation.vector;
    let lift = 0.05;
    // Triangles that the section's rays can meet: near the section plane and
    // within the section's lateral span, on either surface.
    scratch.near.clear();
    let half = 0.5 * width + 0.01;
    for (t, tri) in tris.iter().enumerate() {
        let near = |pos: &[Vec3]| {
            let (mut emin, mut emax, mut lmin, mut lmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for &i in tri {
                let r = pos[i] - p;
                let (e, l) = (r.dot(&elevation), r.dot(&lateral));
                emin = emin.min(e);
                emax = emax.max(e);
                lmin = lmin.min(l);
                lmax = lmax.max(l);
            }
            emin <= 1e-9 && emax >= -1e-9 && lmax >= -half && lmin <= half
        };
        if near(x) || near(rest) {
            scratch.near.push(t);
        }
    }
    let n = samples.max(2);
    out.lateral.clear();
    out.surface_displacement.clear();
    out.bone_depth = bone_depth;
    for j in 0..n {
        let u = -0.5 * width + width * j as f64 / (n - 1) as f64;
        let o = p + lateral * u - k * lift;
        let s = match (
            first_hit(rest, tris, &scratch.near, &o, &k),
            first_hit(x, tris, &scratch.near, &o, &k),
        ) {
            (Some(r), Some(d)) => (d - r).max(0.0),
            _ => 0.0,
        };
        out.lateral.push(u);
        out.surface_displacement.push(s);
    }
}

/// The image's lateral offset in the anatomy's frame (m,
/// [`echothigh_imaging::FrameInput::lateral_offset`]) for the probe at
/// `pose`: the signed arc length along the skin's cross-section (the
/// ellipse of `thigh`) from the vessels' line at angle `vessel_angle` (rad)
/// to the skin point nearest the probe's face centre (so that pressing
/// deeper does not pan the image), positive along the image's lateral axis
/// (the probe's local `x`, which at the exam pose is the thigh's `x`). The
/// vessels run along the thigh's axis, so the probe's `z` does not matter.
pub fn lateral_offset(thigh: &ThighGeometry, pose: &Isometry3<f64>, vessel_angle: f64) -> f64 {
    let (a, b) = (thigh.semi_axis_x, thigh.semi_axis_y);
    let p = pose.translation.vector;
    // Nearest point of the ellipse: Newton on (P(t) − p)·P'(t) = 0 from the
    // point's own elliptic angle (a few steps; the face centre is never
    // near the ellipse's evolute, ~50 mm deep on the anterior line).
    let mut theta = (p.y / b).atan2(p.x / a);
    for _ in 0..8 {
        let (s, c) = theta.sin_cos();
        let (dx, dy) = (a * c - p.x, b * s - p.y);
        let f = -dx * a * s + dy * b * c;
        let df = (a * s).powi(2) + (b * c).powi(2) - dx * a * c - dy * b * s;
        if df <= 0.0 {
            break;
        }
        let step = f / df;
        theta -= step;
        if step.abs() < 1e-14 {
            break;
        }
    }
    // Shortest way round from the vessels' line, in (−π, π].
    let tau = std::f64::consts::TAU;
    let dtheta =
        (theta - vessel_angle + std::f64::consts::PI).rem_euclid(tau) - std::f64::consts::PI;
    // Arc length ∫ |dP/dθ| dθ by Simpson's rule (the speed is smooth).
    let speed = |t: f64| (a * t.sin()).hypot(b * t.cos());
    let n = 64;
    let h = dtheta / n as f64;
    let arc = (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * speed(vessel_angle + i as f64 * h)
        })
        .sum::<f64>()
        * h
        / 3.0;
    // Increasing θ moves along dP/dθ; the image's lateral axis may point
    // either way along it.
    let tangent = Vec3::new(-a * theta.sin(), b * theta.cos(), 0.0);
    let lateral = pose.rotation * Vec3::x();
    if lateral.dot(&tangent) >= 0.0 {
        arc
    } else {
        -arc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn pose_at(g: &ThighGeometry, theta: f64) -> Isometry3<f64> {
        let s = g.surface_point(theta, 0.02);
        // The exam pose rotated about the thigh's axis to face the skin at θ.
        let rot =
            UnitQuaternion::from_axis_angle(&Vec3::z_axis(), theta - std::f64::consts::FRAC_PI_2);
        Isometry3::from_parts(Translation3::new(s[0], s[1], s[2]), rot)
    }

    /// At the vessels' line the offset is 0; a small slide by `Δθ` at the
    /// anterior line moves the image centre by `a Δθ` (the ellipse's speed
    /// there is the x semi-axis), towards −x for increasing θ; a quarter turn
    /// matches the ellipse's quarter perimeter (Ramanujan's formula).
    #[test]
    fn offset_is_the_arc_length_from_the_vessels() {
        let g = ThighGeometry::default();
        let top = std::f64::consts::FRAC_PI_2;
        assert!(lateral_offset(&g, &pose_at(&g, top), top).abs() < 1e-12);
        let d = 1e-3;
        let s = lateral_offset(&g, &pose_at(&g, top + d), top);
        assert!((s - (-g.semi_axis_x * d)).abs() < 1e-8, "{s}");
        let s = lateral_offset(&g, &pose_at(&g, top - d), top);
        assert!((s - g.semi_axis_x * d).abs() < 1e-8, "{s}");
        let (a, b) = (g.semi_axis_x, g.semi_axis_y);
        let h = ((a - b) / (a + b)).powi(2);
        let quarter = 0.25
            * std::f64::consts::PI
            * (a + b)
            * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
        let s = lateral_offset(&g, &pose_at(&g, 0.0), top);
        assert!((s - quarter).abs() < 1e-6, "{s} vs {quarter}");
        // Pressing along the skin's normal does not pan the image.
        for theta in [top + 0.05, top - 0.3, 0.4] {
            let skin = pose_at(&g, theta);
            let n = g.surface_normal(theta);
            let mut pressed = skin;
            pressed.translation.vector -= 0.014 * Vec3::new(n[0], n[1], n[2]);
            let (o, q) = (
                lateral_offset(&g, &skin, top),
                lateral_offset(&g, &pressed, top),
            );
            assert!((o - q).abs() < 1e-9, "θ {theta}: {o} vs pressed {q}");
        }
        // A probe turned end for end sees the thigh mirrored: the sign flips.
        let flipped = pose_at(&g, top + 0.2)
            * UnitQuaternion::from_axis_angle(&Vec3::y_axis(), std::f64::consts::PI);
        let s = lateral_offset(&g, &pose_at(&g, top + 0.2), top);
        assert!((lateral_offset(&g, &flipped, top) + s).abs() < 1e-12);
    }

    /// A ray straight down onto a horizontal triangle meets it at the height
    /// difference; a ray beside it misses.
    #[test]
    fn ray_meets_triangle_at_its_height() {
        let (a, b, c) = (
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        );
        let d = -Vec3::y();
        let t = ray_triangle(&Vec3::new(0.1, 2.5, 0.0), &d, &a, &b, &c).unwrap();
        assert!((t - 2.5).abs() < 1e-12);
        assert!(ray_triangle(&Vec3::new(5.0, 2.5, 0.0), &d, &a, &b, &c).is_none());
    }
}

/// A static press of the probe on the physical model.
#[derive(Debug, Clone)]
pub struct StaticPress {
    /// Skin displacement along the image section.
    pub deformation: SectionDeformation,
    /// Depth of the probe face below the rest skin (m).
    pub indentation: f64,
    /// Contact force reached (N).
    pub force: f64,
}

/// Presses the probe, face down at the top of mid-thigh (the exam pose),
/// into the physical model until the quasi-static contact force reaches
/// `target` (N): the depth is increased in steps of 0.25 mm, the tissue
/// settled at each (implicit steps of 10 ms until the force changes by less
/// than 0.1 %), and the last step bisected. Returns the section under the
/// probe for the image, with `bone_depth` (m) copied in.
pub fn press_to_force(
    physics: &mut super::physics_side::PhysicsSide,
    scenario: &crate::scenario::Scenario,
    target: f64,
    bone_depth: f64,
) -> anyhow::Result<StaticPress> {
    use echothigh_transport::ProbeMsg;
    anyhow::ensure!(
        target.is_finite() && target >= 0.0,
        "force must be finite and >= 0 N, got {target}"
    );
    let top = scenario.thigh.semi_axis_y;
    let h = 0.01;
    let settle = |physics: &mut super::physics_side::PhysicsSide, depth: f64| -> f64 {
        let probe = ProbeMsg::new(0.0, [0.0, top - depth, 0.0], [1.0, 0.0, 0.0, 0.0], 0);
        let mut last = f64::NAN;
        for i in 0..200 {
            let (s, _) = physics.step(&probe, h, i as f64 * h);
            let f = Vec3::from(s.force).norm();
            if (f - last).abs() <= 1e-3 * f.max(1e-3) {
                return f;
            }
            last = f;
        }
        last
    };
    let step = 0.25e-3;
    let max_depth = 0.9 * scenario.tissue.asymptote();
    let (mut lo, mut f_lo) = (0.0, 0.0);
    let mut depth = 0.0;
    let mut f = 0.0;
    while f < target {
        depth += step;
        anyhow::ensure!(
            depth <= max_depth,
            "{target} N is beyond what the tissue bears before its asymptote ({f_lo:.1} N at {:.1} mm)",
            lo * 1e3
        );
        f = settle(physics, depth);
        if f < target {
            lo = depth;
            f_lo = f;
        }
    }
    if target > 0.0 && f > f_lo {
        // One secant refinement between the last two depths.
        let d = lo + (depth - lo) * (target - f_lo) / (f - f_lo);
        f = settle(physics, d);
        depth = d;
    } else if target == 0.0 {
        depth = 0.0;
        f = settle(physics, 0.0);
    }
    let pose = super::physics_side::probe_pose(&ProbeMsg::new(
        0.0,
        [0.0, top - depth, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        0,
    ));
    let img = scenario.imaging_config();
    let mut out = SectionDeformation::rest(bone_depth);
    section_deformation(
        physics.model(),
        &pose,
        img.width,
        81,
        bone_depth,
        &mut SectionScratch::default(),
        &mut out,
    );
    Ok(StaticPress {
        deformation: out,
        indentation: depth,
        force: f,
    })
}
