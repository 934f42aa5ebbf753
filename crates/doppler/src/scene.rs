//! The flow seen in one frame: each vessel's lumen in the image (from the
//! B-mode renderer, after the probe's deformation) with its centreline
//! velocity along the colour beam, and the probe's own motion (the flash
//! source). Fixed capacity: filling it allocates nothing.

use crate::flow::SegmentFlow;
use crate::maneuver::Maneuvers;
use crate::physiology::FlowConfig;
use crate::profile::Profile;
use echothigh_anatomy::Thrombi;
use echothigh_anatomy::{Anatomy, ImagePlane, Kind, ProbePose, Section, StructureId, Vec3};
use echothigh_imaging::{AnatomyConfig, FrameInput, ImagingError, Renderer};

/// Largest number of vessels a scene holds (the studied pair plus
/// `echothigh_imaging::MAX_STRUCTURES`).
pub const MAX_FLOW_VESSELS: usize = 14;

/// One vessel's lumen and flow in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlowVessel {
    /// Lateral position of the lumen's centre (m, image frame).
    pub lateral: f64,
    /// Depth of the centre below the probe face (m).
    pub depth: f64,
    /// Half width of the lumen (m).
    pub half_width: f64,
    /// Half height of the lumen (m).
    pub half_height: f64,
    /// Centreline velocity component towards the probe along the colour
    /// beam (m/s): the flow's centreline velocity times the cosine of its
    /// angle to the beam.
    pub axial_velocity: f64,
    /// Profile across the lumen.
    pub profile: Profile,
    /// Fraction of the lumen that is thrombus (no flow there).
    pub fill: f64,
    /// Whether the content is central (free-floating) rather than mural.
    pub central: bool,
}

impl FlowVessel {
    /// The normalized radius `ρ` of `(lateral, depth)` (m) in the lumen
    /// ellipse, and whether that point holds flowing blood (inside, not in
    /// the content: the deepest `fill` of the chord when mural, its
    /// central `fill` when central, as the B-mode draws it).
    pub fn blood_at(&self, lateral: f64, depth: f64) -> Option<f64> {
        let u = (lateral - self.lateral) / self.half_width;
        let d = (depth - self.depth) / self.half_height;
        let rho2 = u * u + d * d;
        if rho2 >= 1.0 {
            return None;
        }
        let h = (1.0 - u * u).sqrt();
        let eta = d / h;
        let content = self.fill > 0.0
            && if self.central {
                eta.abs() < self.fill
            } else {
                eta > 1.0 - 2.0 * self.fill
            };
        (!content).then(|| rho2.sqrt())
    }
}

/// The vessels of one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlowScene {
    vessels: [FlowVessel; MAX_FLOW_VESSELS],
    /// Each vessel's index in the renderer's anatomy (its order of push
    /// when pushed without one).
    ids: [usize; MAX_FLOW_VESSELS],
    n: usize,
    /// Velocity of the tissue relative to the probe along the beam (m/s,
    /// towards the probe positive): the probe's motion, the flash source.
    pub tissue_velocity: f64,
}

impl FlowScene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Removes every vessel.
    pub fn clear(&mut self) {
        self.n = 0;
    }

    /// Adds a vessel (ignored beyond [`MAX_FLOW_VESSELS`]).
    pub fn push(&mut self, v: FlowVessel) {
        self.push_indexed(self.n, v);
    }

    /// Adds vessel `index` of the renderer's anatomy (ignored beyond
    /// [`MAX_FLOW_VESSELS`]).
    pub fn push_indexed(&mut self, index: usize, v: FlowVessel) {
        if self.n < MAX_FLOW_VESSELS {
            self.vessels[self.n] = v;
            self.ids[self.n] = index;
            self.n += 1;
        }
    }

    /// The vessels.
    pub fn vessels(&self) -> &[FlowVessel] {
        &self.vessels[..self.n]
    }

    /// The blood at `(lateral, depth)`: the vessel and `ρ`, if any.
    pub fn blood_at(&self, lateral: f64, depth: f64) -> Option<(&FlowVessel, f64)> {
        self.vessels()
            .iter()
            .find_map(|v| v.blood_at(lateral, depth).map(|r| (v, r)))
    }

    /// As [`FlowScene::blood_at`], with the vessel's index in the
    /// renderer's anatomy (the index of [`SectionFlows::flow`]).
    pub fn blood_at_indexed(&self, lateral: f64, depth: f64) -> Option<(usize, &FlowVessel, f64)> {
        self.vessels()
            .iter()
            .zip(&self.ids)
            .find_map(|(v, &i)| v.blood_at(lateral, depth).map(|r| (i, v, r)))
    }
}

/// What a section's vessels carry, built once per section: for each vessel
/// of the renderer's anatomy (studied vein, its artery, then the veins and
/// arteries of `structures` in order) its flow, direction and content.
#[derive(Debug, Clone)]
pub struct SectionFlows {
    items: Vec<(SegmentFlow, Vec3, Profile, f64, bool)>,
    plane: ImagePlane,
    pose: ProbePose,
}

impl SectionFlows {
    /// The flows of the section `section` of `anatomy` drawn as `cfg` (the
    /// renderer's anatomy, from `runtime::section_image`), in a case with
    /// `thrombi` and the iliac `proximal_obstruction` flag.
    pub fn new(
        flow: &FlowConfig,
        anatomy: &Anatomy,
        thrombi: &Thrombi,
        proximal_obstruction: bool,
        section: &Section,
        cfg: &AnatomyConfig,
    ) -> Result<SectionFlows, echothigh_anatomy::AnatomyError> {
        let plane = anatomy.image_plane(&section.pose)?;
        let vein = anatomy.deep_vein_at(section.pose.s);
        let artery = match vein {
            StructureId::Cfv => StructureId::Cfa,
            StructureId::Fv => StructureId::Fa,
            _ => StructureId::Pa,
        };
        let mut ids = vec![vein, artery];
        for st in &cfg.structures {
            if let Some(x) = section.structures.iter().find(|x| x.id.as_str() == st.name) {
                if matches!(
                    x.kind,
                    Kind::DeepVein | Kind::SuperficialVein | Kind::Artery
                ) {
                    ids.push(x.id);
                }
            }
        }
        let mut items = Vec::with_capacity(ids.len());
        for id in ids {
            let s = section.get(id).map_or(section.pose.s, |x| x.s);
            let sf = SegmentFlow::of(flow, anatomy, thrombi, id, s, proximal_obstruction);
            let tube = anatomy.tube(id);
            let axis = tube.map_or(Vec3::new(0.0, 0.0, -1.0), |t| t.axis_derivative(s));
            let axis = axis / axis.norm().max(1e-12);
            let artery = sf.kind == crate::flow::FlowKind::Artery;
            // Veins flow towards the heart (s decreasing), arteries away.
            let dir = if artery { axis } else { -axis };
            let st = thrombi.state(id, s);
            let profile = if artery {
                Profile::Plug
            } else {
                Profile::Parabolic
            };
            let central = st.layout == echothigh_anatomy::Layout::Central;
            items.push((
                sf,
                dir,
                profile,
                if artery { 0.0 } else { st.fill },
                central,
            ));
        }
        Ok(SectionFlows {
            items,
            plane,
            pose: section.pose,
        })
    }

    /// The same flows seen by a beam rocked `tilt` (rad, + aims distally)
    /// out of the drawn section's plane: the heel-toe angling a sonographer
    /// gives the probe to see flow in a transverse view. Only the beam's
    /// direction changes (the vessels and their flows are the drawn
    /// section's).
    pub fn beam_tilted(
        mut self,
        anatomy: &Anatomy,
        tilt: f64,
    ) -> Result<SectionFlows, echothigh_anatomy::AnatomyError> {
        self.plane = anatomy.image_plane(&ProbePose { tilt, ..self.pose })?;
        Ok(self)
    }

    /// The segment flow of vessel `i` of the renderer's anatomy.
    pub fn flow(&self, i: usize) -> Option<&SegmentFlow> {
        self.items.get(i).map(|x| &x.0)
    }

    /// Cosine of the angle between vessel `i`'s flow and the direction
    /// from the tissue towards the probe, for a beam steered `steer` (rad)
    /// in the image plane.
    pub fn cos_to_probe(&self, i: usize, steer: f64) -> f64 {
        let beam = steer.cos() * self.plane.depth + steer.sin() * self.plane.lateral;
        self.items.get(i).map_or(0.0, |x| -(beam.dot(&x.1)))
    }

    /// Fills `scene` for one frame at time `t` (s): each vessel's lumen
    /// from `renderer` for `input`, its velocity under the manoeuvres `m`
    /// and the lumen ratio under the probe. Allocates nothing.
    #[allow(clippy::too_many_arguments)]
    pub fn fill(
        &self,
        flow: &FlowConfig,
        m: &Maneuvers,
        renderer: &Renderer,
        input: &FrameInput,
        steer: f64,
        tissue_velocity: f64,
        scene: &mut FlowScene,
    ) -> Result<(), ImagingError> {
        scene.clear();
        scene.tissue_velocity = tissue_velocity;
        for (i, (sf, _, profile, fill, central)) in self.items.iter().enumerate() {
            let Some(l) = renderer.vessel_lumen(i, input)? else {
                break;
            };
            let ratio = l.area / l.rest_area.max(1e-12);
            let v = sf.velocity(flow, m, input.time, ratio);
            let half_height = l.half_height.max(0.0);
            if half_height <= 0.0 || l.half_width <= 0.0 {
                continue;
            }
            scene.push_indexed(
                i,
                FlowVessel {
                    lateral: l.lateral,
                    depth: l.depth,
                    half_width: l.half_width,
                    half_height,
                    axial_velocity: v * self.cos_to_probe(i, steer),
                    profile: *profile,
                    fill: *fill,
                    central: *central,
                },
            );
        }
        Ok(())
    }
}
