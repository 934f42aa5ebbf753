//! The scripted trainee's hand (issue 14): travel through the air to a
//! site, approach, press by the script's policy, hold, release — the hand's
//! setpoint driven tick by tick on the virtual clock while the detector
//! reads the live state. See [`crate::exam_run`] for the walk and its
//! approximations.

use crate::exam_probe::{Look, SiteProbe};
use crate::exam_script::{PressPolicy, TraineeScript};
use crate::scenario::Scenario;
use crate::virtual_clock::VirtualRun;
use anyhow::{bail, Context, Result};
use echothigh_anatomy::{ProbePose, StructureId};
use echothigh_cases::Case;
use echothigh_device::{HapticDevice, SimulatedDevice, SimulatedHand};
use echothigh_exam::detector::{ARTERY_CUE, COAPTATION, CONTACT_ON};
use echothigh_exam::{CaseExam, ExamLog, ExamSample, ProtocolSite};
use echothigh_imaging::ImagingConfig;
use echothigh_model::{LegSurface, Vec3};

/// Closest a press gets to the mesh's held end rings (m): a probe's
/// length, as [`crate::exam_site`] asks of a named site.
pub const END_MARGIN: f64 = 0.03;
/// Rate of the lumen looks (Hz), see [`crate::exam_run`].
pub const LOOK_RATE: f64 = 50.0;
/// Pause above each site before the approach (s).
pub const SETTLE: f64 = 0.1;
/// Height above the rest skin of the travel between sites (m).
const CLEARANCE: f64 = 0.02;
/// Height above the rest skin where the approach hands over to the press
/// (m). The approach runs at the press's rate, so the hand (its mass on
/// the 300 N/m grip) meets the skin at that rate and no faster: at the
/// travel speed it would overshoot by v √(m/K) ≈ 5 mm and bump the skin.
const APPROACH_END: f64 = 0.01;
/// Setpoint speed through the air and of the release (m/s): a careful probe
/// placement (`SimulatedHand::slew_towards`'s docs: ~0.2 m/s).
const MOVE_SPEED: f64 = 0.2;
/// Largest step between travel waypoints: along the leg (m) and around it
/// (rad), so that the physics (100 Hz) follows the probe through the air.
const WAYPOINT: (f64, f64) = (0.02, 0.1);
/// Longest a phase may last (s) before the walk stops with an error.
const PHASE_TIMEOUT: f64 = 10.0;
/// How far along its vein the trainee may move to find a drawable window
/// when the site's own section cannot be drawn (m): under half the site
/// spacing, so the window stays in the site's bin.
const SEARCH: f64 = 0.0095;

/// The probe's place on the physics' leg: `s`, θ, tilt.
type Place = (f64, f64, f64);

/// The walk's state: the run, the hand, and the case's bookkeeping (the
/// [`CaseExam`]: detector, coverage, events and calls), whose records go
/// to `log` as they happen.
pub(crate) struct Walker<'a> {
    pub run: VirtualRun,
    leg: LegSurface,
    script: &'a TraineeScript,
    imaging: ImagingConfig,
    pub exam: CaseExam,
    pub log: &'a mut dyn ExamLog,
    segment: (f64, f64),
    max_depth: f64,
    period: f64,
    look_every: u64,
    pub ticks: u64,
    pub looks: u64,
    at: Option<Place>,
}

/// The current site: its probe and where its skin is.
struct Here {
    probe: SiteProbe,
    skin: Vec3,
    inward: Vec3,
    vein: &'static str,
    look: Option<Look>,
}

/// One tick's reading.
struct Now {
    t: f64,
    force: f64,
    depth: f64,
    look: Look,
}

impl<'a> Walker<'a> {
    pub fn new(
        scenario: &Scenario,
        script: &'a TraineeScript,
        case: &Case,
        log: &'a mut dyn ExamLog,
    ) -> Result<Self> {
        let leg = LegSurface::new(&scenario.thigh, "thigh")?
            .context("the exam scenario has a patient's leg")?;
        let start = leg.to_model(&Vec3::new(0.0, 0.2, -scenario.thigh.centre_s));
        let hand = SimulatedHand::new(scenario.hand, start).map_err(anyhow::Error::msg)?;
        let device =
            SimulatedDevice::with_hand(scenario.device(), hand).map_err(anyhow::Error::msg)?;
        let run = VirtualRun::with_device(scenario, device)?;
        let period = scenario.coupling.haptic_period();
        let (c, l) = (scenario.thigh.centre_s, scenario.thigh.length);
        Ok(Walker {
            run,
            leg,
            script,
            imaging: scenario.live_imaging_config(),
            exam: CaseExam::new(case, script.protocol()),
            log,
            segment: (c - 0.5 * l + END_MARGIN, c + 0.5 * l - END_MARGIN),
            max_depth: 0.9 * scenario.tissue.asymptote(),
            period,
            look_every: ((1.0 / LOOK_RATE) / period).round().max(1.0) as u64,
            ticks: 0,
            looks: 0,
            at: None,
        })
    }

    /// The site's probe: the section at the site, or — when the renderer
    /// cannot draw it — the nearest drawable one within [`SEARCH`] along
    /// the vein (0.5 mm steps), as a sonographer moves to find a window.
    /// `Err(reason)` inside `Ok` when no window is drawable there.
    fn site_probe(
        &self,
        site: &ProtocolSite,
        case: &Case,
        vein: StructureId,
    ) -> Result<std::result::Result<(ProbePose, SiteProbe), String>> {
        let mut first_error = None;
        // Nearest first: 0, +0.5, −0.5, +1, … ±9.5 mm; the window stays
        // inside the site's 2 cm bin.
        let steps = (0..39).map(|i| if i % 2 == 1 { (i + 1) / 2 } else { -(i / 2) });
        for k in steps {
            let s = site.s + f64::from(k) * 0.5e-3;
            let Ok(pose) = case.anatomy.pose_over(s, vein) else {
                continue;
            };
            let s_phys = s.clamp(self.segment.0, self.segment.1);
            let q = self
                .leg
                .hand_target(s_phys, pose.theta, 0.0, pose.tilt)?
                .orientation;
            let q = q.quaternion();
            let orientation = [q.w, q.i, q.j, q.k];
            let (a, t) = (&case.anatomy, &case.thrombi);
            match SiteProbe::new(&self.imaging, a, t, pose, s_phys, orientation) {
                Ok(p) => return Ok(Ok((pose, p))),
                Err(e) => {
                    first_error.get_or_insert(format!("{e:#}"));
                }
            }
        }
        Ok(Err(format!(
            "no drawable section within {:.1} mm of the site: {}",
            SEARCH * 1e3,
            first_error.unwrap_or_else(|| "the vein does not exist there".into())
        )))
    }

    /// Travels to `site`, presses by the script's policy, holds, releases.
    /// Returns the physics' press point `s` (m), or why the site cannot be
    /// imaged (then nothing was done).
    pub fn press_site(
        &mut self,
        site: &ProtocolSite,
        case: &Case,
    ) -> Result<std::result::Result<f64, String>> {
        let vein = match site.vein.as_str() {
            "cfv" => StructureId::Cfv,
            "fv" => StructureId::Fv,
            _ => StructureId::Pv,
        };
        let (pose, probe) = match self.site_probe(site, case, vein)? {
            Ok(x) => x,
            Err(why) => return Ok(Err(why)),
        };
        let s_phys = pose.s.clamp(self.segment.0, self.segment.1);
        let place = (s_phys, pose.theta, pose.tilt);
        let skin = self.leg.hand_target(s_phys, pose.theta, 0.0, pose.tilt)?;
        let above = self.leg.hand_target(s_phys, pose.theta, -1e-3, pose.tilt)?;
        let mut here = Here {
            probe,
            skin: skin.position,
            inward: (skin.position - above.position).normalize(),
            vein: vein.as_str(),
            look: None,
        };
        self.travel(place, &mut here)?;
        self.press(&mut here)?;
        self.at = Some(place);
        Ok(Ok(s_phys))
    }

    /// Moves the probe through the air, [`CLEARANCE`] off the skin, from
    /// where it is to above `to`, then waits [`SETTLE`].
    fn travel(&mut self, to: Place, here: &mut Here) -> Result<()> {
        let from = self.at.unwrap_or(to);
        let n = ((to.0 - from.0).abs() / WAYPOINT.0)
            .max((to.1 - from.1).abs() / WAYPOINT.1)
            .ceil()
            .max(1.0) as usize;
        for i in 0..=n {
            let u = i as f64 / n as f64;
            let p = (
                from.0 + u * (to.0 - from.0),
                from.1 + u * (to.1 - from.1),
                from.2 + u * (to.2 - from.2),
            );
            let target = self.leg.hand_target(p.0, p.1, -CLEARANCE, p.2)?;
            let q = target.orientation.quaternion();
            self.run.set_probe_orientation([q.w, q.i, q.j, q.k]);
            if self.at.is_none() {
                // The first site: the probe starts there, at rest.
                let dev = self.run.device_mut();
                dev.set_state(target.position, Vec3::zeros());
                hand(dev)?.set_setpoint(target.position, Vec3::zeros());
            }
            self.until("travel", here, |w, _| {
                let h = hand(w.run.device_mut())?;
                h.slew_towards(target.position, MOVE_SPEED, w.period);
                Ok((h.setpoint() - target.position).norm() < 1e-9)
            })?;
        }
        let t0 = self.run.time();
        self.until("settle", here, |_, now| Ok(now.t - t0 >= SETTLE))
    }

    /// Approach, press, hold, release at the current site.
    fn press(&mut self, here: &mut Here) -> Result<()> {
        let (skin, inward) = (here.skin, here.inward);
        let goal = skin - inward * APPROACH_END;
        let rate = self.script.press.rate;
        self.until("approach", here, |w, _| {
            let h = hand(w.run.device_mut())?;
            h.slew_towards(goal, rate, w.period);
            Ok((h.setpoint() - goal).norm() < 1e-9)
        })?;
        let p = self.script.press.clone();
        let cap = p
            .max_force
            .unwrap_or(self.leg.anatomy().patient().exam_force);
        let max_depth = self.max_depth;
        self.until("press", here, |w, now| {
            let l = now.look;
            let done = match p.policy {
                PressPolicy::Target => now.force >= p.target_force,
                PressPolicy::Adequate => {
                    now.force >= cap
                        || (now.force > CONTACT_ON
                            && (l.vein_ratio < COAPTATION || l.artery_ratio < ARTERY_CUE))
                }
            } || now.depth >= max_depth;
            let h = hand(w.run.device_mut())?;
            let sp = h.setpoint();
            if done {
                h.set_setpoint(sp, Vec3::zeros());
            } else {
                h.set_setpoint(sp + inward * (p.rate * w.period), inward * p.rate);
            }
            Ok(done)
        })?;
        let t0 = self.run.time();
        self.until("hold", here, |_, now| Ok(now.t - t0 >= p.hold))?;
        let lift = skin - inward * CLEARANCE;
        self.until("release", here, |w, now| {
            let h = hand(w.run.device_mut())?;
            h.slew_towards(lift, MOVE_SPEED, w.period);
            Ok((h.setpoint() - lift).norm() < 1e-9
                && now.depth < -APPROACH_END
                && !w.exam.pressing())
        })
    }

    /// Runs ticks until `done` (called after each tick with its reading)
    /// says so; errors after [`PHASE_TIMEOUT`].
    fn until(
        &mut self,
        phase: &str,
        here: &mut Here,
        mut done: impl FnMut(&mut Self, &Now) -> Result<bool>,
    ) -> Result<()> {
        let t0 = self.run.time();
        loop {
            let now = self.step(here)?;
            if done(self, &now)? {
                return Ok(());
            }
            if now.t - t0 > PHASE_TIMEOUT {
                bail!(
                    "the {phase} did not end within {PHASE_TIMEOUT} s (force {:.2} N, depth {:.1} mm)",
                    now.force,
                    now.depth * 1e3
                );
            }
        }
    }

    /// One haptic tick, a look when due, and the detector's sample.
    fn step(&mut self, here: &mut Here) -> Result<Now> {
        self.run.step_tick()?;
        self.ticks += 1;
        let mut rec = None;
        self.run.drain_trace(|t, _| rec = t.last().copied());
        let rec = rec.context("the tick left no record")?;
        let t = rec.t + self.period;
        let force = Vec3::from(rec.force).norm();
        let position = self.run.device().position();
        let depth = (position - here.skin).dot(&here.inward);
        if here.look.is_none() || self.ticks.is_multiple_of(self.look_every) {
            let model = self.run.physics().model();
            here.look = Some(
                here.probe
                    .look(model, &self.leg, position.into(), force, t)?,
            );
            self.looks += 1;
        }
        let look = here.look.expect("looked");
        let sample = ExamSample {
            t,
            force,
            skin: look.skin,
            vein: Some(here.vein),
            s: look.s,
            vein_ratio: look.vein_ratio,
            artery_ratio: look.artery_ratio,
        };
        self.exam
            .observe(&sample, &mut *self.log)
            .context("the exam's bookkeeping")?;
        Ok(Now {
            t,
            force,
            depth,
            look,
        })
    }
}

/// The device's hand.
fn hand(dev: &mut SimulatedDevice) -> Result<&mut SimulatedHand> {
    dev.hand_mut().context("the walk's device has a hand")
}
