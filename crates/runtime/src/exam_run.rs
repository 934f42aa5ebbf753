//! The scripted trainee (issue 14), headless on the virtual clock: the
//! simulated hand walks the probe site to site over the case patient's
//! leg, normal to the skin over the vein at each site (as
//! [`crate::exam_site`] places it), presses, holds, releases and makes its
//! calls, while the case's [`CaseExam`](echothigh_exam::CaseExam) (the viewer's bookkeeping: event
//! detector, coverage, calls, score) turns the live state into compression
//! events. Every tick is the one haptic tick of `run`
//! ([`crate::virtual_clock::VirtualRun`]: physics, link, buffer model,
//! device and hand on the scenario's rates).
//!
//! **The physics' leg.** The mesh spans the femur of the case's patient
//! preset, `s ∈ [0, knee_s]`, its end rings held. A site closer than
//! [`END_MARGIN`] to a held ring, or beyond it (the popliteal vein below
//! the knee), is pressed on the mesh at the nearest point at least
//! [`END_MARGIN`] inside (as [`crate::exam_site`] refuses sites within a
//! probe's length of the ends) while its image is the case's section at the
//! site itself. The case's own patient options that the mesh does not know
//! (tense muscle, duplicated FV, lymph node) change the image only.
//!
//! **Between sites** the probe is lifted 20 mm off the skin and carried
//! through the air, 20 mm off it, to above the next site (waypoints every
//! 2 cm along the leg and 0.1 rad around it, so that the physics follows),
//! then settles [`SETTLE`] before approaching. Where the renderer cannot
//! draw the site's own section, the trainee slides up to 1 cm along the
//! vein to the nearest drawable one (as a sonographer finds a window).
//!
//! **Sampling.** The detector reads the probe force at every tick (1 kHz)
//! and the lumens at [`LOOK_RATE`]: a press rises at most ~25 N/s (measured,
//! report), so 50 Hz resolves the lumens to ≤ 0.5 N of force, 5 % of the
//! default 10 N press, and matches the trace rate of the events.

use crate::exam_script::{CallPolicy, TraineeScript};
use crate::exam_walk::Walker;
pub use crate::exam_walk::{END_MARGIN, LOOK_RATE, SETTLE};
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use echothigh_anatomy::Patient;
use echothigh_cases::Case;
use echothigh_exam::{CaseScore, ExamLog, Finding, ProtocolSite};

/// What a walk did, besides what went to the log.
#[derive(Debug, Clone, PartialEq)]
pub struct ExamOutcome {
    /// The case's score (also given to the log).
    pub score: CaseScore,
    /// Virtual time of the walk (s).
    pub virtual_time: f64,
    /// Haptic ticks run.
    pub ticks: u64,
    /// Sites pressed, and the physics' press point of each (m): the site's
    /// own `s`, or the nearest point [`END_MARGIN`] inside the mesh.
    pub pressed: Vec<(ProtocolSite, f64)>,
    /// Sites the trainee could not image (the renderer cannot draw any
    /// section within 9.5 mm of them), and why: not pressed, not called.
    pub unexaminable: Vec<(ProtocolSite, String)>,
    /// Lumen looks made.
    pub looks: u64,
}

/// The scenario of a case's walk: the built-in scenario on the case's
/// patient preset, the mesh over the whole femur.
pub fn exam_scenario(case: &Case) -> Result<Scenario> {
    let preset = case
        .file
        .patient
        .get("preset")
        .and_then(|v| v.as_str())
        .unwrap_or("lean-male");
    let knee = Patient::preset(preset)
        .with_context(|| format!("case {}: patient preset {preset:?}", case.name()))?
        .knee_s;
    let mut s = Scenario::builtin()?;
    s.thigh.patient = preset.to_string();
    s.thigh.centre_s = 0.5 * knee;
    s.thigh.length = knee;
    s.site.name.clear();
    // The walk drains the trace every tick: a short buffer suffices.
    s.run.duration = 1.0;
    s.validate()
        .with_context(|| format!("the exam scenario of case {}", case.name()))?;
    Ok(s)
}

/// Runs `script` on `case`, sending events, calls and the score to `log` as
/// they happen (the bookkeeping is the viewer's: one [`CaseExam`](echothigh_exam::CaseExam) fed by
/// the walk). Errors name the script's key, the site, or the physics'
/// failure.
pub fn run_exam(script: &TraineeScript, case: &Case, log: &mut dyn ExamLog) -> Result<ExamOutcome> {
    let scenario = exam_scenario(case)?;
    let sites = script.protocol().sites(&case.anatomy);
    let names: Vec<&str> = sites.iter().map(|x| x.name.as_str()).collect();
    script.check_sites(&names)?;
    let doppler = echothigh_exam::doppler::doppler_sites(&case.anatomy);
    let names: Vec<&str> = doppler.iter().map(|x| x.name.as_str()).collect();
    script.check_doppler_sites(&names)?;
    let mut w = Walker::new(&scenario, script, case, log)?;
    let mut pressed = Vec::new();
    let mut unexaminable = Vec::new();
    for site in sites.iter().filter(|x| !script.skip.contains(&x.name)) {
        let pressed_at = w.press_site(site, case).with_context(|| {
            format!(
                "pressing site {} ({} at {:.0} mm)",
                site.name,
                site.vein,
                site.s * 1e3
            )
        })?;
        let s_phys = match pressed_at {
            Ok(s) => s,
            Err(why) => {
                unexaminable.push((site.clone(), why));
                continue;
            }
        };
        pressed.push((site.clone(), s_phys));
        if script.calls == CallPolicy::Honest {
            if let Some(finding) = w.exam.seen_at(&site.name) {
                let t = w.run.time();
                w.exam.call(&site.name, finding, t, &mut *w.log)?;
            }
        }
    }
    let t = w.run.time();
    if script.calls == CallPolicy::Scripted {
        for c in &script.call {
            let finding = Finding::from_name(&c.finding).expect("validated");
            w.exam.call(&c.site, finding, t, &mut *w.log)?;
        }
    }
    for d in &script.doppler {
        let finding = d.finding().expect("validated");
        w.exam.call_doppler(&d.site, finding, t, &mut *w.log)?;
    }
    let score = w.exam.finish(t, &mut *w.log)?;
    Ok(ExamOutcome {
        score,
        virtual_time: w.run.time(),
        ticks: w.ticks,
        pressed,
        unexaminable,
        looks: w.looks,
    })
}
