//! The probe message the direct-coupling tests drive the physics with.

use echothigh_anatomy::Site;
use echothigh_runtime::physics_side::PhysicsSide;
use echothigh_transport::ProbeMsg;

/// The probe message over the fv-mid site of `physics`'s leg, its face
/// `depth` (m) inside the rest skin, moved `slide` (m) along the leg
/// (towards the knee).
pub fn probe(physics: &PhysicsSide, depth: f64, slide: f64) -> ProbeMsg {
    let leg = physics.model().mesh().leg().expect("the whole-leg mesh");
    let site = leg.anatomy().site_pose(Site::FvMid);
    let target = leg
        .hand_target(site.s + slide, site.theta, depth, 0.0)
        .unwrap();
    let q = target.orientation;
    ProbeMsg::new(0.0, target.position.into(), [q.w, q.i, q.j, q.k], 0)
}
