//! The surface mesh: geometry, areas, normals, topology, grid lookups.

use crate::common;

use echothigh_model::{EdgeKind, SurfaceMesh, ThighGeometry};
use std::f64::consts::{FRAC_PI_2, TAU};

#[test]
fn nodes_lie_on_the_ellipse_with_outward_normals_and_anchors_inside() {
    let g = ThighGeometry::default();
    let mesh = SurfaceMesh::new(&g).unwrap();
    for k in 0..mesh.node_count() {
        let p = mesh.rest_positions()[k];
        let e = (p.x / g.semi_axis_x).powi(2) + (p.y / g.semi_axis_y).powi(2);
        assert!((e - 1.0).abs() < 1e-12);
        let n = mesh.rest_normals()[k];
        assert!((n.norm() - 1.0).abs() < 1e-12 && n.z == 0.0);
        // Outward: the gradient of the ellipse equation points along n.
        let grad = nalgebra::Vector3::new(
            p.x / g.semi_axis_x.powi(2),
            p.y / g.semi_axis_y.powi(2),
            0.0,
        );
        assert!((grad.normalize() - n).norm() < 1e-12);
        let a = mesh.anchors()[k];
        assert!(((p - a).norm() - g.tissue_thickness).abs() < 1e-12);
        let fem = nalgebra::Vector2::new(a.x - g.femur_offset[0], a.y - g.femur_offset[1]);
        assert!(fem.norm() > g.femur_radius);
    }
}

#[test]
fn areas_sum_to_the_lateral_surface_and_do_not_depend_on_resolution() {
    let areas = |nt: usize, nz: usize| {
        let mesh = SurfaceMesh::new(&common::small_config(nt, nz).thigh).unwrap();
        mesh.areas().iter().sum::<f64>()
    };
    // Ramanujan's perimeter of the default ellipse × length.
    let (a, b) = (0.080f64, 0.072f64);
    let perim = std::f64::consts::PI * (3.0 * (a + b) - ((3.0 * a + b) * (a + 3.0 * b)).sqrt());
    let exact = perim * 0.30;
    let fine = areas(256, 41);
    assert!((fine - exact).abs() < 1e-3 * exact, "{fine} vs {exact}");
    assert!((areas(48, 21) - exact).abs() < 5e-3 * exact);
}

#[test]
fn topology_counts_and_triangle_orientation() {
    let g = common::small_config(12, 5).thigh;
    let mesh = SurfaceMesh::new(&g).unwrap();
    let (nt, nz) = (12, 5);
    let count = |kind| mesh.edges().iter().filter(|e| e.kind == kind).count();
    assert_eq!(count(EdgeKind::Structural), nt * nz + nt * (nz - 1));
    assert_eq!(count(EdgeKind::Shear), 2 * nt * (nz - 1));
    assert_eq!(count(EdgeKind::Bending), nt * nz + nt * (nz - 2));
    assert_eq!(mesh.triangles().len(), 2 * nt * (nz - 1));
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|k| mesh.rest_positions()[k]);
        let n = (b - a).cross(&(c - a));
        let centre = (a + b + c) / 3.0;
        assert!(
            n.dot(&nalgebra::Vector3::new(centre.x, centre.y, 0.0)) > 0.0,
            "inward triangle"
        );
    }
    assert_eq!(mesh.fixed().iter().filter(|&&f| f).count(), 2 * nt);
}

#[test]
fn grid_lookup_round_trips() {
    let mesh = SurfaceMesh::new(&ThighGeometry::default()).unwrap();
    for k in [0, 1, 47, 48, 500, mesh.node_count() - 1] {
        let (it, iz) = mesh.grid_index(k);
        assert_eq!(mesh.node_index(it, iz), k);
        let (theta, z) = mesh.theta_z(k);
        assert_eq!(mesh.node_at(theta, z), k);
        assert_eq!(mesh.node_at(theta + TAU, z + 0.001), k);
    }
    let top = mesh.node_at(FRAC_PI_2, 0.0);
    let p = mesh.rest_positions()[top];
    assert!((p.y - 0.072).abs() < 1e-12 && p.x.abs() < 1e-12 && p.z.abs() < 1e-12);
    // Out of range z clamps, NaN does not panic.
    assert_eq!(mesh.grid_index(mesh.node_at(0.0, 10.0)).1, mesh.n_z() - 1);
    let _ = mesh.node_at(f64::NAN, f64::NAN);
}
