//! The live system's haptic loop when a real device drives the probe
//! (issue 15): the same one tick as every deployment
//! ([`crate::tick::HapticTick`]), reading the device instead of following
//! the page's probe commands.
//!
//! Per tick, besides the tick itself: a device that senses no orientation
//! gets the probe normal to the skin under it ([`SkinNormal`]); the device's
//! clutch, force and health go to the page through a lock-free single-slot
//! handoff. Nothing here allocates, locks or waits (`tests/suite/live_device.rs`
//! counts the allocations of [`DeviceLoop::step`]). A device that stops
//! answering ([`HapticDevice::lost`]) ends the loop: the force is released,
//! the page told, the session's threads stop.

use super::session::{Driver, LiveObserver};
use super::shared::Shared;
use crate::live_device::{ellipse_normal, lost_message, DeviceTick};
use crate::physics_loop::Clock;
use crate::physics_side::PhysicsSide;
use crate::scenario::Scenario;
use crate::tick::{HapticTick, TickObserver};
use anyhow::{Context, Result};
use echothigh_device::HapticDevice;
use echothigh_haptics::{LoopRunner, Vec3};
use echothigh_model::LegSurface;
use nalgebra::UnitQuaternion;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A device chosen at run time.
pub(crate) type BoxedDevice = Box<dyn HapticDevice + Send>;

/// The probe's orientation normal to the skin under a point, for a device
/// that senses none (DESIGN: a 3-DoF device keeps the probe normal to the
/// skin): on a patient's leg the skin's own frame
/// ([`LegSurface::hand_target`], the page's convention), on the elliptic
/// cylinder a rotation about the thigh's axis bringing the probe's `+y` onto
/// the outward normal ([`ellipse_normal`]).
pub enum SkinNormal {
    /// A patient's leg, with the model segment's half-length (m).
    Leg(Box<LegSurface>, f64),
    /// The elliptic cylinder's semi-axes (m).
    Cylinder(f64, f64),
}

impl SkinNormal {
    /// The skin of `scenario`'s thigh.
    pub fn of(scenario: &Scenario) -> Result<Self> {
        let t = &scenario.thigh;
        Ok(match LegSurface::new(t, "thigh")? {
            Some(leg) => SkinNormal::Leg(Box::new(leg), 0.5 * t.length),
            None => SkinNormal::Cylinder(t.semi_axis_x, t.semi_axis_y),
        })
    }

    /// The orientation (w, x, y, z; thigh ← probe) normal to the skin
    /// nearest `p` (m, thigh frame) around the axis, at `p`'s height
    /// (clamped to the segment); `fallback` where the leg has no skin there.
    pub fn orientation_at(&self, p: Vec3, fallback: [f64; 4]) -> [f64; 4] {
        match self {
            SkinNormal::Leg(leg, half) => {
                let z = p.z.clamp(-half, *half);
                let theta_leg = (-p.x).atan2(p.y);
                match leg.hand_target(leg.s_of_z(z), theta_leg, 0.0, 0.0) {
                    Ok(t) => {
                        let q = t.orientation;
                        [q.w, q.i, q.j, q.k]
                    }
                    Err(_) => fallback,
                }
            }
            SkinNormal::Cylinder(a, b) => {
                let n = ellipse_normal(*a, *b, &p);
                let q = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), (-n.x).atan2(n.y));
                [q.w, q.i, q.j, q.k]
            }
        }
    }
}

/// The per-tick work of the live loop with a real device.
pub struct DeviceLoop<O> {
    /// The one haptic tick, on the device.
    pub tick: HapticTick<BoxedDevice>,
    /// The tick's observer (the live system's: pose to the link, status to the page).
    pub observer: O,
    /// The skin, for devices without orientation.
    pub skin: SkinNormal,
    /// The device's state for the page.
    pub status: triple_buffer::Input<DeviceTick>,
    orientation: [f64; 4],
}

impl<O: TickObserver> DeviceLoop<O> {
    /// The loop's state; `orientation` is the probe's until the device or
    /// the skin sets one.
    pub fn new(
        tick: HapticTick<BoxedDevice>,
        observer: O,
        skin: SkinNormal,
        status: triple_buffer::Input<DeviceTick>,
        orientation: [f64; 4],
    ) -> Self {
        DeviceLoop {
            tick,
            observer,
            skin,
            status,
            orientation,
        }
    }

    /// One tick at loop time `now` (s). Returns `Ok(Some(code))` when the
    /// device has stopped (its SDK code): the caller ends the loop.
    pub fn step(&mut self, now: f64) -> Result<Option<u32>> {
        let device = self.tick.device();
        if let Some(code) = device.lost() {
            self.status.write(DeviceTick {
                clutched: false,
                force: [0.0; 3],
                lost: Some(code),
            });
            return Ok(Some(code));
        }
        if device.orientation().is_none() {
            self.orientation = self
                .skin
                .orientation_at(device.position(), self.orientation);
            self.tick.set_orientation(self.orientation);
        }
        self.tick.tick(now, &mut self.observer)?;
        let device = self.tick.device();
        self.status.write(DeviceTick {
            clutched: device.clutched(),
            force: device.force().into(),
            lost: None,
        });
        Ok(None)
    }
}

/// Spawns the live haptic loop on `device_loop` until `stop`; the thread
/// returns the `direct` physics and the device (handed to the next session).
/// A stopped device or a tick error is reported to the page
/// ([`Shared::report_fault`], after the loop, off the real-time path) and
/// stops the session. `realtime`: the loop runner asks for real-time
/// priority (`[haptics.runner] realtime_priority`).
pub(super) fn spawn(
    mut device_loop: DeviceLoop<LiveObserver>,
    mut runner: LoopRunner,
    clock: Clock,
    stop: Arc<AtomicBool>,
    shared: Arc<Shared>,
    name: String,
    realtime: bool,
) -> Result<JoinHandle<(Option<PhysicsSide>, Driver)>> {
    std::thread::Builder::new()
        .name("haptic-loop".into())
        .spawn(move || {
            super::session::raise_priority(&shared, realtime);
            let mut ended: Option<Result<u32>> = None;
            runner.run(&stop, None, |_, _| {
                if ended.is_some() {
                    return;
                }
                match device_loop.step(clock.now()) {
                    Ok(None) => {}
                    Ok(Some(code)) => ended = Some(Ok(code)),
                    Err(e) => ended = Some(Err(e)),
                }
                if ended.is_some() {
                    stop.store(true, Ordering::Relaxed);
                }
            });
            device_loop.tick.release();
            match ended {
                Some(Ok(code)) => shared.report(lost_message(&name, code)),
                Some(Err(e)) => shared.report_fault("haptic", &e),
                None => {}
            }
            let (device, direct) = device_loop.tick.into_parts();
            (direct, Driver::Hardware(device))
        })
        .context("starting the haptic loop")
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Quaternion;

    fn probe_axis(q: [f64; 4]) -> Vec3 {
        let q = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
        q * Vec3::y()
    }

    /// On a patient's leg, a 3-DoF device's probe looks down the skin's
    /// inward normal: its `+y` is the anatomy's outward skin normal at the
    /// point's level and angle (exact on the skin, 1e-9: rounding).
    #[test]
    fn a_three_dof_probe_is_normal_to_the_patients_skin() {
        let mut s = Scenario::default();
        s.thigh.patient = "average-female".into();
        let skin = SkinNormal::of(&s).unwrap();
        let SkinNormal::Leg(leg, _) = &skin else {
            panic!("a patient's leg")
        };
        for (z, theta_leg) in [(0.0, 0.0), (0.05, 0.7), (-0.1, -1.2), (0.12, 2.0)] {
            let sl = leg.s_of_z(z);
            let p = leg.to_model(&leg.anatomy().skin_point(sl, theta_leg).unwrap());
            let n = leg.anatomy().skin_normal(sl, theta_leg).unwrap();
            let axis = probe_axis(skin.orientation_at(p, [1.0, 0.0, 0.0, 0.0]));
            assert!(
                (axis - n).norm() < 1e-9,
                "z {z} θ {theta_leg}: {axis:?} vs {n:?}"
            );
        }
    }

    /// On the elliptic cylinder, the probe's `+y` is the ellipse's outward
    /// normal, and its `z` stays the thigh's axis (a rotation about it).
    #[test]
    fn a_three_dof_probe_is_normal_to_the_cylinder() {
        let s = Scenario::default();
        let (a, b) = (s.thigh.semi_axis_x, s.thigh.semi_axis_y);
        let skin = SkinNormal::of(&s).unwrap();
        for t in [0.3f64, 1.57, 2.4, -0.8] {
            let p = Vec3::new(a * t.cos(), b * t.sin(), 0.02);
            let q = skin.orientation_at(p, [1.0, 0.0, 0.0, 0.0]);
            let n = ellipse_normal(a, b, &p);
            assert!((probe_axis(q) - n).norm() < 1e-12);
            let rq = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
            assert!((rq * Vec3::z() - Vec3::z()).norm() < 1e-12);
        }
    }
}
