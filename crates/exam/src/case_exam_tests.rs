//! `CaseExam` on a shipped case with synthetic live samples.

use super::*;
use crate::{BinState, MemoryLog};
use echothigh_cases::builtin;

fn case(name: &str) -> Case {
    builtin(name).unwrap()
}

/// One press at `(vein, s)`: force ramps 0 → `peak` → 0 over 2 s at 50 Hz,
/// the vein's ratio falling linearly with force to `vein_min` at the peak,
/// the artery's to `artery_min`.
#[allow(clippy::too_many_arguments)] // a press is its eight numbers
fn press(
    x: &mut CaseExam,
    log: &mut MemoryLog,
    t0: f64,
    vein: &'static str,
    s: f64,
    peak: f64,
    vein_min: f64,
    artery_min: f64,
) -> f64 {
    let n = 100;
    for k in 0..=n {
        let u = k as f64 / n as f64;
        let f = peak * (1.0 - (2.0 * u - 1.0).abs());
        let w = f / peak;
        let sample = ExamSample {
            t: t0 + 2.0 * u,
            force: f,
            skin: [s, 0.0],
            vein: Some(vein),
            s,
            vein_ratio: 1.0 - w * (1.0 - vein_min),
            artery_ratio: 1.0 - w * (1.0 - artery_min),
        };
        x.observe(&sample, log).unwrap();
    }
    t0 + 2.0
}

#[test]
fn presses_mark_the_checklist_and_calls_score_against_the_truth() {
    let c = case("isolated-fv-mid-acute");
    let mut x = CaseExam::new(&c, Protocol::ThreePoint);
    let mut log = MemoryLog::default();
    let names: Vec<String> = x.sites().iter().map(|s| s.name.clone()).collect();
    assert_eq!(names, ["cfv", "fv-mid", "popliteal"]);
    let site = |x: &CaseExam, n: &str| x.sites().iter().find(|s| s.name == n).unwrap().clone();
    let (cfv, mid, pop) = (site(&x, "cfv"), site(&x, "fv-mid"), site(&x, "popliteal"));
    let vein =
        |v: &str| -> &'static str { ["cfv", "fv", "pv"].into_iter().find(|n| *n == v).unwrap() };
    // CFV closes (0.02 < 0.1), the thrombosed mid-thigh FV stays open with
    // the artery deformed (0.85 < 0.9: adequate), the popliteal is pressed
    // too lightly (neither criterion).
    let mut t = press(
        &mut x,
        &mut log,
        0.0,
        vein(&cfv.vein),
        cfv.s,
        10.0,
        0.02,
        0.95,
    );
    t = press(
        &mut x,
        &mut log,
        t + 1.0,
        vein(&mid.vein),
        mid.s,
        18.0,
        0.9,
        0.85,
    );
    t = press(
        &mut x,
        &mut log,
        t + 1.0,
        vein(&pop.vein),
        pop.s,
        3.0,
        0.7,
        0.99,
    );
    assert_eq!(log.events.len(), 3, "one event per press");
    assert_eq!(
        x.events(),
        &log.events[..],
        "the log saw every event as it ended"
    );
    let done: Vec<bool> = x.sites().iter().map(|s| s.done).collect();
    assert_eq!(done, [true, true, false], "the light press covers nothing");
    let states: Vec<BinState> = log
        .events
        .iter()
        .map(|e| {
            x.coverage().bins()[x
                .coverage()
                .bin_at(e.vein.as_deref().unwrap(), e.s)
                .unwrap()]
            .state
        })
        .collect();
    assert_eq!(
        states,
        [
            BinState::Closed,
            BinState::NotClosed,
            BinState::InadequatePressure
        ]
    );
    // Peak of the three presses (the ramp reaches its peak exactly at u = ½).
    assert!((x.peak_force() - 18.0).abs() < 1e-9, "{}", x.peak_force());

    x.call("cfv", Finding::Normal, t, &mut log).unwrap();
    x.call("fv-mid", Finding::Normal, t, &mut log).unwrap();
    // Changing one's mind: the later call counts.
    x.call("fv-mid", Finding::AcuteDvt, t + 1.0, &mut log)
        .unwrap();
    x.call("popliteal", Finding::Indeterminate, t + 2.0, &mut log)
        .unwrap();
    assert_eq!(
        log.calls.len(),
        4,
        "every call is recorded, the changed one too"
    );
    assert_eq!(
        log.calls[2].truth,
        Finding::AcuteDvt,
        "the truth at mid-thigh FV"
    );
    assert_eq!(x.call_at("fv-mid"), Some(Finding::AcuteDvt));
    let err = x
        .call("fv-distal", Finding::Normal, t, &mut log)
        .unwrap_err();
    assert!(
        err.to_string()
            .contains("no site `fv-distal` in the three-point protocol"),
        "{err}"
    );

    let score = x.finish(t + 3.0, &mut log).unwrap();
    assert_eq!(log.score.as_ref(), Some(&score));
    assert_eq!(log.coverage, x.coverage().bins());
    // cfv normal ✓, fv-mid acute ✓, popliteal indeterminate ✗ (truth normal).
    assert_eq!((score.calls_correct, score.calls_total), (2, 3));
    // Two of the protocol's three bins are covered.
    assert!(
        (score.coverage - 2.0 / 3.0).abs() < 1e-12,
        "{}",
        score.coverage
    );
}

#[test]
fn finishing_mid_press_records_the_press() {
    let c = case("normal-average");
    let mut x = CaseExam::new(&c, Protocol::TwoPoint);
    let mut log = MemoryLog::default();
    let cfv = x.sites()[0].clone();
    for k in 0..10 {
        let s = ExamSample {
            t: 0.1 * k as f64,
            force: 2.0 * k as f64,
            skin: [cfv.s, 0.0],
            vein: Some("cfv"),
            s: cfv.s,
            vein_ratio: 0.05,
            artery_ratio: 1.0,
        };
        x.observe(&s, &mut log).unwrap();
    }
    assert!(x.pressing());
    x.finish(1.0, &mut log).unwrap();
    assert_eq!(
        log.events.len(),
        1,
        "the press under way at the end is kept"
    );
    assert!((log.events[0].peak_force - 18.0).abs() < 1e-12);
    assert!(log.events[0].coapted);
}

#[test]
fn a_malformed_sample_is_refused_naming_the_field() {
    let c = case("normal-average");
    let mut x = CaseExam::new(&c, Protocol::TwoPoint);
    let mut log = MemoryLog::default();
    let s = ExamSample {
        t: 0.0,
        force: f64::NAN,
        skin: [0.0, 0.0],
        vein: None,
        s: 0.0,
        vein_ratio: 1.0,
        artery_ratio: 1.0,
    };
    let err = x.observe(&s, &mut log).unwrap_err().to_string();
    assert!(err.contains("force"), "{err}");
    assert!(log.events.is_empty());
}

/// Doppler calls go to the log as they are made and are scored apart from
/// the compression calls: on the popliteal case (PV occluded 300–400 mm)
/// the CFV is phasic without augmentation and the popliteal absent; one
/// right and one wrong Doppler call leave the compression score (no call:
/// 0 of 2) as it was and give 1 of 2 Doppler calls right.
#[test]
fn doppler_calls_are_logged_and_scored_apart() {
    use crate::{DopplerFinding, FlowPattern};
    let c = case("popliteal-acute");
    let mut x = CaseExam::new(&c, Protocol::ThreePoint);
    let mut log = MemoryLog::default();
    let names: Vec<&str> = x.doppler_sites().iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["cfv", "popliteal"]);
    let f = |flow, augments| DopplerFinding { flow, augments };
    x.call_doppler("cfv", f(FlowPattern::Phasic, false), 1.0, &mut log)
        .unwrap();
    x.call_doppler("popliteal", f(FlowPattern::Phasic, true), 2.0, &mut log)
        .unwrap();
    let err = x
        .call_doppler("fv-mid", f(FlowPattern::Absent, false), 2.0, &mut log)
        .unwrap_err()
        .to_string();
    assert!(err.contains("no Doppler site `fv-mid`"), "{err}");
    assert_eq!(log.doppler.len(), 2);
    assert_eq!(
        x.doppler_at("popliteal"),
        Some(f(FlowPattern::Phasic, true))
    );
    assert_eq!(log.doppler[1].truth, f(FlowPattern::Absent, false));
    let score = x.finish(3.0, &mut log).unwrap();
    assert_eq!((score.calls_correct, score.calls_total), (0, 3));
    assert_eq!((score.doppler.correct, score.doppler.total), (1, 2));
}

/// A log whose sink dies after `ok` writes (a database gone mid-case:
/// disk full, server stopped): every later write fails.
struct DyingLog {
    ok: usize,
    writes: usize,
    taken: MemoryLog,
}

impl DyingLog {
    fn write(&mut self) -> Result<(), LogError> {
        self.writes += 1;
        if self.writes > self.ok {
            return Err(LogError("database gone".into()));
        }
        Ok(())
    }
}

impl ExamLog for DyingLog {
    fn event(&mut self, e: &CompressionEvent) -> Result<(), LogError> {
        self.write()?;
        self.taken.event(e)
    }
    fn call(&mut self, c: &Call) -> Result<(), LogError> {
        self.write()?;
        self.taken.call(c)
    }
    fn doppler(&mut self, c: &DopplerCall) -> Result<(), LogError> {
        self.write()?;
        self.taken.doppler(c)
    }
    fn finish(&mut self, cov: &[crate::CoverageBin], s: &CaseScore) -> Result<(), LogError> {
        self.write()?;
        self.taken.finish(cov, s)
    }
}

/// The same exam (four presses on the CFV and popliteal, two calls, a
/// Doppler call, a press left under way at the end) run against a log that
/// never fails and one that fails from its third write on: the case keeps
/// every record in memory either way — its events, calls, Doppler calls
/// and score equal the healthy log's exactly — and each failed write
/// returns the log's error.
#[test]
fn a_failing_log_loses_no_record_in_memory() {
    use crate::{DopplerFinding, FlowPattern};
    let c = case("normal-average");
    let run = |log: &mut dyn ExamLog| -> (CaseExam, usize) {
        let mut x = CaseExam::new(&c, Protocol::TwoPoint);
        let sites: Vec<_> = x.sites().to_vec();
        let mut errors = 0;
        let mut t = 0.0;
        for k in 0..5 {
            let site = &sites[k % 2];
            let vein = if site.vein == "cfv" { "cfv" } else { "pv" };
            // The last press is cut by the finish at half its length.
            let n = if k == 4 { 50 } else { 100 };
            for j in 0..=n {
                let u = j as f64 / 100.0;
                let f = 12.0 * (1.0 - (2.0 * u - 1.0).abs());
                let sample = ExamSample {
                    t: t + 2.0 * u,
                    force: f,
                    skin: [site.s, 0.0],
                    vein: Some(vein),
                    s: site.s,
                    vein_ratio: 1.0 - f / 12.5,
                    artery_ratio: 1.0,
                };
                match x.observe(&sample, log) {
                    Ok(_) => {}
                    Err(CaseExamError::Log(_)) => errors += 1,
                    Err(e) => panic!("{e}"),
                }
            }
            t += 3.0;
            if k < 2 {
                errors += x.call(&site.name, Finding::Normal, t, log).is_err() as usize;
            }
        }
        let d = DopplerFinding {
            flow: FlowPattern::Phasic,
            augments: true,
        };
        errors += x.call_doppler("cfv", d, t, log).is_err() as usize;
        errors += x.finish(t + 1.0, log).is_err() as usize;
        (x, errors)
    };
    let mut healthy = MemoryLog::default();
    let (good, none) = run(&mut healthy);
    assert_eq!(none, 0);
    let mut dying = DyingLog {
        ok: 2,
        writes: 0,
        taken: MemoryLog::default(),
    };
    let (x, errors) = run(&mut dying);
    // 5 events + 2 calls + 1 Doppler call + the score = 9 writes, 2 taken,
    // 7 failed; the finish returns one error for its two failed writes (the
    // press cut by the finish, then the score): 6 errors returned.
    assert_eq!((healthy.events.len(), healthy.calls.len()), (5, 2));
    assert_eq!((dying.writes, errors), (9, 6));
    assert_eq!(dying.taken.events.len() + dying.taken.calls.len(), 2);
    assert_eq!(x.events(), healthy.events.as_slice());
    assert_eq!(x.calls(), healthy.calls.as_slice());
    assert_eq!(x.doppler_calls(), healthy.doppler.as_slice());
    assert_eq!(x.score(), healthy.score.as_ref());
    assert_eq!(x.score(), good.score());
}

/// A restart mid-case (issue 19): an attempt resumed from its recorded
/// events and calls shows the same checklist, coverage and peak force as
/// the attempt it continues, logs nothing again, and, after the same
/// further press and calls, scores exactly as one uninterrupted attempt.
#[test]
fn a_resumed_attempt_goes_on_as_if_never_interrupted() {
    use crate::{DopplerFinding, FlowPattern};
    let c = case("isolated-fv-mid-acute");
    let site = |x: &CaseExam, n: &str| x.sites().iter().find(|s| s.name == n).unwrap().clone();
    let whole = CaseExam::new(&c, Protocol::ThreePoint);
    let (cfv, mid) = (site(&whole, "cfv"), site(&whole, "fv-mid"));
    // Before the restart: the CFV closes, a call and a Doppler call.
    let before = |x: &mut CaseExam, log: &mut MemoryLog| {
        let t = press(x, log, 0.0, "cfv", cfv.s, 10.0, 0.02, 0.95);
        x.call("cfv", Finding::Normal, t + 0.5, log).unwrap();
        let d = DopplerFinding {
            flow: FlowPattern::Phasic,
            augments: true,
        };
        x.call_doppler("cfv", d, t + 1.0, log).unwrap();
    };
    // After it: the mid-thigh FV stays open with the artery deformed.
    let after = |x: &mut CaseExam, log: &mut MemoryLog, t0: f64| {
        let t = press(x, log, t0, "fv", mid.s, 18.0, 0.9, 0.85);
        x.call("fv-mid", Finding::AcuteDvt, t + 0.5, log).unwrap();
        x.finish(t + 1.0, log).unwrap()
    };
    let mut whole = whole;
    let mut log = MemoryLog::default();
    before(&mut whole, &mut log);
    // The latest record is the Doppler call, after the press's last sample.
    let resumed_at = log.doppler[0].t;
    assert!(resumed_at > whole.last_time());
    let mut resumed = CaseExam::resume(
        &c,
        Protocol::ThreePoint,
        log.events.clone(),
        log.calls.clone(),
        log.doppler.clone(),
    );
    assert_eq!(resumed.last_time(), resumed_at);
    assert_eq!(resumed.sites(), whole.sites());
    assert_eq!(resumed.coverage().bins(), whole.coverage().bins());
    assert_eq!(resumed.peak_force(), whole.peak_force());
    assert_eq!(resumed.call_at("cfv"), Some(Finding::Normal));
    let mut log2 = MemoryLog::default();
    let t0 = resumed_at + 2.0;
    let a = after(&mut whole, &mut log, t0);
    let b = after(&mut resumed, &mut log2, t0);
    assert_eq!(a, b);
    // The resumed attempt logged only what came after the restart.
    assert_eq!(
        (log2.events.len(), log2.calls.len(), log2.doppler.len()),
        (1, 1, 0)
    );
}
