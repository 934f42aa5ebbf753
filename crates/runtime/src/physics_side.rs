//! The physics side of Fig. 1: the thigh model (Eq. 1) with the probe's
//! penalty contact (Eq. 2) and the haptic queries (distance, gradient, local
//! stiffness), behind one `step` that turns a probe message into a sample
//! message.

use super::trace::PhysicsRecord;
use crate::scenario::Scenario;
use anyhow::Result;
use echothigh_contact::{HapticSample, Probe, ProbeContact, SurfaceDistance, SurfaceGrid};
use echothigh_model::ThighModel;
use echothigh_transport::{ProbeMsg, SampleMsg};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The physical model and the probe contact.
pub struct PhysicsSide {
    model: ThighModel,
    contact: ProbeContact,
    last: Option<HapticSample>,
    distance: SurfaceDistance,
    grid: SurfaceGrid,
}

/// The probe pose carried by a probe message (position m, unit quaternion);
/// a degenerate quaternion falls back to the identity (the exam pose).
pub fn probe_pose(msg: &ProbeMsg) -> Isometry3<f64> {
    let [w, i, j, k] = msg.orientation;
    let q = Quaternion::new(w, i, j, k);
    let rot = if q.norm() > 1e-9 && q.coords.iter().all(|c| c.is_finite()) {
        UnitQuaternion::from_quaternion(q)
    } else {
        UnitQuaternion::identity()
    };
    Isometry3::from_parts(Translation3::from(Vector3::from(msg.position)), rot)
}

impl PhysicsSide {
    /// Builds the model at rest and the contact for `scenario`.
    pub fn new(scenario: &Scenario) -> Result<Self> {
        let model = ThighModel::new(&scenario.model_config()).map_err(anyhow::Error::msg)?;
        let contact = ProbeContact::new(&model, scenario.probe, scenario.contact)
            .map_err(anyhow::Error::msg)?;
        let mesh = model.mesh();
        let distance =
            SurfaceDistance::new(mesh.rest_positions(), mesh.rest_normals(), mesh.triangles());
        let spacing = std::f64::consts::TAU
            * scenario.thigh.semi_axis_x.max(scenario.thigh.semi_axis_y)
            / scenario.thigh.n_theta as f64;
        let grid = SurfaceGrid::new(model.node_count(), spacing.max(1e-3));
        Ok(Self {
            model,
            contact,
            last: None,
            distance,
            grid,
        })
    }

    /// One physics step of `h` (s) at physics time `t` (s) with the probe
    /// where `probe` says: implicit Euler with contact, then the queries.
    pub fn step(&mut self, probe: &ProbeMsg, h: f64, t: f64) -> (SampleMsg, PhysicsRecord) {
        let pose = probe_pose(probe);
        let step = self.contact.step(&mut self.model, &pose, h);
        let s = step.sample;
        self.last = Some(s);
        // No surface near the probe (D = +∞) goes on the wire as a finite
        // sentinel with its own contact state.
        let (distance, contact) = echothigh_transport::wire_query(s.distance, s.in_contact);
        let msg = SampleMsg {
            t_sample: t + h,
            p: s.p.into(),
            distance,
            gradient: s.gradient.into(),
            stiffness: s.stiffness,
            force: s.force.into(),
            contact,
            newton_iterations: step.physics.newton_iterations,
            cg_iterations: step.physics.cg_iterations,
            limited: step.physics.limited,
            physics_rate: 1.0 / h,
            ..SampleMsg::default()
        };
        let rec = PhysicsRecord {
            t,
            probe: s.p.into(),
            distance: s.distance,
            gradient: s.gradient.into(),
            stiffness: s.stiffness,
            force: s.force.into(),
            newton_iterations: step.physics.newton_iterations,
            cg_iterations: step.physics.cg_iterations,
            limited: step.physics.limited,
            compute_time: 0.0,
            stages: {
                let mut t = step.physics.timings;
                t.accumulate(&step.query.timings);
                t
            },
        };
        (msg, rec)
    }

    /// One physics step of `h` (s) at physics time `t` (s) with the probe
    /// where `probe` says, *without* the haptic queries: implicit Euler with
    /// contact (the same step as [`Self::step`], which runs these very
    /// stages before its queries), and the contact force at the step's end
    /// ([`ProbeContact::wrench_now`], as the queries evaluate it).
    /// What `direct` coupling renders in real time, where the tick must fit
    /// its 1 ms and the force is all it displays: the stiffness query's
    /// solve alone costs more than the step on the whole-leg mesh (issue 18).
    /// The sample kept for [`Self::last_sample`] has that force and torque;
    /// its `D` is +∞ and its `k` 0 (not computed), and so are the record's.
    /// The force is [`Self::step`]'s to the bit (the queries only read the
    /// model; `tests/suite/direct_force_only.rs`).
    /// Returns the force on the probe (N) and the step's record.
    /// Allocation-free.
    pub fn step_force(
        &mut self,
        probe: &ProbeMsg,
        h: f64,
        t: f64,
    ) -> (Vector3<f64>, PhysicsRecord) {
        let pose = probe_pose(probe);
        let (mut physics, _) = self.contact.advance(&mut self.model, &pose, h);
        let clock = std::time::Instant::now();
        let wrench = self.contact.wrench_now(&self.model);
        physics.timings.broad_phase += clock.elapsed().as_secs_f64();
        let p = Probe::reference_point(&pose);
        let gradient = -Probe::contact_direction(&pose);
        self.last = Some(HapticSample {
            p,
            distance: f64::INFINITY,
            gradient,
            stiffness: 0.0,
            force: wrench.force,
            torque: wrench.torque,
            in_contact: wrench.samples > 0,
        });
        let rec = PhysicsRecord {
            t,
            probe: p.into(),
            distance: f64::INFINITY,
            gradient: gradient.into(),
            stiffness: 0.0,
            force: wrench.force.into(),
            newton_iterations: physics.newton_iterations,
            cg_iterations: physics.cg_iterations,
            limited: physics.limited,
            compute_time: 0.0,
            stages: physics.timings,
        };
        (wrench.force, rec)
    }

    /// The state checkpoint after a step: an error naming the node and the
    /// time if the model diverged (non-finite or runaway state), so that the
    /// caller stops and reports instead of rendering from it.
    pub fn check(&self) -> Result<()> {
        self.model.check_state().map_err(anyhow::Error::new)
    }

    /// The thigh model (deformed state).
    pub fn model(&self) -> &ThighModel {
        &self.model
    }

    /// The probe contact.
    pub fn contact(&self) -> &ProbeContact {
        &self.contact
    }

    /// The last sample computed.
    pub fn last_sample(&self) -> Option<HapticSample> {
        self.last
    }

    /// Signed distance (m, > 0 outside) from `x` to the deformed surface.
    pub fn signed_distance(&mut self, x: &Vector3<f64>) -> Option<f64> {
        self.grid.rebuild(self.model.positions());
        self.distance
            .query(&self.grid, self.model.positions(), x)
            .map(|s| s.distance)
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        self.model.reset();
        self.contact.reset();
        self.last = None;
    }
}
