//! A case's score (issue 14 "Scoring and feedback"; fidelity review §3
//! "Scoring" and §4 item 3): the calls against the truth at each site of
//! the protocol, the protocol's coverage, pressure adequacy (a "not
//! compressible" call without adequate pressure is marked), excessive force
//! over a free-floating thrombus, time, peak and mean force, and the
//! thrombosed segments the exam never examined (where a limited exam missed
//! the disease).
//!
//! The per-trainee aggregates (sensitivity and specificity by site, rates,
//! trends) belong to `echothigh-records`, which owns the sessions.

use crate::coverage::{is_covered, Coverage};
use crate::protocol::{ProtocolSite, WHOLE_LEG_SPACING};
use crate::{Call, CaseScore, CompressionEvent, Finding, MissedSegment, Protocol, SiteScore};
use echothigh_anatomy::VeinTruth;

/// Largest probe force (N) over a free-floating thrombus before the press
/// counts as excessive. No published safe force exists: practice says "do
/// not compress" a free-floating thrombus (review §1, abcvascular.com). The
/// limit is **derived** as the force at which the vein itself begins to
/// deform in the shipped force chain (review § "Force needed in the
/// simulator"): every lumen stays at 1.00 at 1.6 N (5 mmHg at the vein) and
/// the healthy vein is at 0.80 by 4.3 N (16 mmHg); the stress at the vein
/// reaches a supine venous pressure of ~10 mmHg (estimate) at ≈ 2.9 N by
/// linear interpolation, rounded to 3 N. Beyond it the press squeezes the
/// vein around the tail.
pub const SAFE_TAIL_FORCE: f64 = 3.0;

/// What a case's score is computed from.
#[derive(Debug, Clone, Copy)]
pub struct ScoreInput<'a> {
    /// The case's name.
    pub case: &'a str,
    /// The protocol asked for.
    pub protocol: Protocol,
    /// Its sites on the case's anatomy ([`Protocol::sites`]).
    pub sites: &'a [ProtocolSite],
    /// The case's ground truth (`Case::ground_truth()`).
    pub truth: &'a [VeinTruth],
    /// The compression events, in order.
    pub events: &'a [CompressionEvent],
    /// The calls, in order (a later call on a site replaces an earlier one).
    pub calls: &'a [Call],
    /// The coverage strip after the events.
    pub coverage: &'a Coverage,
}

/// The truth on `vein` at `s` (m): the finding of the ground-truth piece
/// there (`Finding::from_truth_kind`), `None` off the vein.
pub fn truth_at(truth: &[VeinTruth], vein: &str, s: f64) -> Option<Finding> {
    let v = truth.iter().find(|v| v.vein == vein)?;
    let last = v.pieces.last()?;
    v.pieces
        .iter()
        .find(|p| s >= p.s_start && (s < p.s_end || (s <= p.s_end && p == &last)))
        .and_then(|p| Finding::from_truth_kind(p.kind))
}

/// Half the probe's elevation (m): the image is a slab 10 mm thick (the
/// contact probe's `half_elevation`, 5 mm), so a site within 5 mm of a
/// thrombus's end shows both the thrombus and the normal vein beyond it.
pub const FOOTPRINT: f64 = 0.005;

/// The truth a call `call` at `s` on `vein` is scored against: the call's
/// own finding when the ground truth shows it anywhere within
/// [`FOOTPRINT`] of `s` (a site on a thrombus's end: either call is
/// right), else the truth at `s` ([`truth_at`], normal off the vein).
pub fn truth_for_call(truth: &[VeinTruth], vein: &str, s: f64, call: Option<Finding>) -> Finding {
    let seen = |f: Finding| {
        truth.iter().filter(|v| v.vein == vein).any(|v| {
            v.pieces.iter().any(|p| {
                p.s_start <= s + FOOTPRINT
                    && p.s_end >= s - FOOTPRINT
                    && Finding::from_truth_kind(p.kind) == Some(f)
            })
        })
    };
    match call {
        Some(f) if seen(f) => f,
        _ => truth_at(truth, vein, s).unwrap_or(Finding::Normal),
    }
}

/// Whether `e` is a press over `vein` within half the site spacing (1 cm)
/// of `s`: the press examined the site there.
fn near(e: &CompressionEvent, vein: &str, s: f64) -> bool {
    e.vein.as_deref() == Some(vein) && (e.s - s).abs() <= 0.5 * WHOLE_LEG_SPACING + 1e-12
}

/// Whether a press reached adequate pressure (the walls met, or the artery
/// began to deform: review §1 "Positive criterion").
pub fn adequate(e: &CompressionEvent) -> bool {
    e.coapted || e.artery_deformed
}

/// Mean force of a press (N): the trapezoidal mean of its force trace over
/// its duration, and that duration (s).
fn trace_integral(e: &CompressionEvent) -> (f64, f64) {
    let tr = &e.force_trace;
    let area: f64 = tr
        .windows(2)
        .map(|w| 0.5 * (w[0][1] + w[1][1]) * (w[1][0] - w[0][0]))
        .sum();
    let span = match (tr.first(), tr.last()) {
        (Some(a), Some(b)) => b[0] - a[0],
        _ => 0.0,
    };
    (area, span)
}

/// Scores a case.
pub fn score_case(x: &ScoreInput) -> CaseScore {
    let sites: Vec<SiteScore> = x
        .sites
        .iter()
        .map(|site| {
            let call = x
                .calls
                .iter()
                .rev()
                .find(|c| c.site == site.name)
                .map(|c| c.finding);
            let truth = truth_for_call(x.truth, &site.vein, site.s, call);
            let pressure_adequate = x
                .events
                .iter()
                .any(|e| near(e, &site.vein, site.s) && adequate(e));
            SiteScore {
                site: site.name.clone(),
                call,
                truth,
                pressure_adequate,
                called_without_adequate_pressure: call == Some(Finding::AcuteDvt)
                    && !pressure_adequate,
            }
        })
        .collect();
    let calls_correct = sites.iter().filter(|s| s.call == Some(s.truth)).count() as u32;
    let n = x.events.len();
    let pressure_adequate = if n == 0 {
        0.0
    } else {
        x.events.iter().filter(|e| adequate(e)).count() as f64 / n as f64
    };
    let excessive_force_on_tail = x
        .events
        .iter()
        .filter(|e| e.peak_force > SAFE_TAIL_FORCE && over_free_floating(x.truth, e))
        .count() as u32;
    let (area, span) = x
        .events
        .iter()
        .map(trace_integral)
        .fold((0.0, 0.0), |(a, s), (da, ds)| (a + da, s + ds));
    let last_call = x.calls.iter().map(|c| c.t).fold(f64::NAN, f64::max);
    let last_event = x.events.iter().map(|e| e.t_end).fold(0.0, f64::max);
    CaseScore {
        case: x.case.to_string(),
        protocol: x.protocol.name().to_string(),
        coverage: x.coverage.share(x.sites),
        calls_correct,
        calls_total: sites.len() as u32,
        pressure_adequate,
        excessive_force_on_tail,
        duration: if last_call.is_nan() {
            last_event
        } else {
            last_call
        },
        peak_force: x.events.iter().map(|e| e.peak_force).fold(0.0, f64::max),
        mean_force: if span > 0.0 { area / span } else { 0.0 },
        sites,
        missed: missed_segments(x),
        // Scored by the caller that holds the Doppler calls (`CaseExam`).
        doppler: Default::default(),
    }
}

/// Whether `e` pressed over a free-floating thrombus of its vein.
fn over_free_floating(truth: &[VeinTruth], e: &CompressionEvent) -> bool {
    let Some(vein) = e.vein.as_deref() else {
        return false;
    };
    truth.iter().filter(|v| v.vein == vein).any(|v| {
        v.pieces
            .iter()
            .any(|p| p.kind == "free_floating" && e.s >= p.s_start && e.s <= p.s_end)
    })
}

/// The diseased stretches of the strip's deep veins that no press examined
/// with adequate pressure and no call named correctly: where the exam
/// missed the disease.
fn missed_segments(x: &ScoreInput) -> Vec<MissedSegment> {
    let bins = x.coverage.bins();
    let mut out = Vec::new();
    for v in x.truth {
        if !bins.iter().any(|b| b.vein == v.vein) {
            continue;
        }
        for p in &v.pieces {
            let Some(truth) = Finding::from_truth_kind(p.kind) else {
                continue;
            };
            if truth == Finding::Normal {
                continue;
            }
            let examined = bins.iter().any(|b| {
                b.vein == v.vein
                    && b.s_start < p.s_end
                    && p.s_start < b.s_end
                    && is_covered(b.state)
            });
            let called = x.calls.iter().any(|c| {
                c.vein == v.vein && c.s >= p.s_start && c.s <= p.s_end && c.finding == truth
            });
            if !examined && !called {
                out.push(MissedSegment {
                    vein: v.vein.to_string(),
                    s_start: p.s_start,
                    s_end: p.s_end,
                    truth,
                });
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "score_tests.rs"]
mod tests;
