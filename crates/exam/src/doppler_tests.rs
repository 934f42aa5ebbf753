//! Doppler truth on shipped cases (each expectation follows from the flow
//! model's rules in the module docs and the case's thrombus segments), and
//! its scoring.

use super::*;
use echothigh_cases::builtin;
use FlowPattern::*;

fn at(case: &Case) -> (DopplerFinding, DopplerFinding, Vec<ProtocolSite>) {
    let sites = doppler_sites(&case.anatomy);
    let names: Vec<&str> = sites.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(names, ["cfv", "popliteal"]);
    (
        doppler_truth(case, sites[0].s),
        doppler_truth(case, sites[1].s),
        sites,
    )
}

fn d(flow: FlowPattern, augments: bool) -> DopplerFinding {
    DopplerFinding { flow, augments }
}

/// A normal leg: phasic and augmenting at both sites.
#[test]
fn normal_leg_is_phasic_and_augments() {
    let (cfv, pop, _) = at(&builtin("normal-average").unwrap());
    assert_eq!((cfv, pop), (d(Phasic, true), d(Phasic, true)));
}

/// The same leg with an iliac obstruction (`[doppler]
/// proximal_obstruction`): continuous at both sites, still augmenting
/// (nothing is occluded below either).
#[test]
fn proximal_obstruction_makes_it_continuous() {
    let mut c = builtin("normal-average").unwrap();
    c.file.doppler.proximal_obstruction = true;
    let (cfv, pop, _) = at(&c);
    assert_eq!((cfv, pop), (d(Continuous, true), d(Continuous, true)));
}

/// Occluded segments: the iliofemoral case (CFV and FV occluded over
/// 0–220 mm) has no CFV flow and a continuous popliteal signal (occlusion
/// above), which augments (nothing occluded below); the popliteal case (PV
/// occluded over 300–400 mm) has no popliteal flow, and a phasic CFV that
/// does not augment (the calf's flow is blocked below it).
#[test]
fn occluded_segments_have_no_flow_and_block_augmentation() {
    let c = builtin("iliofemoral-extensive").unwrap();
    let (cfv, pop, sites) = at(&c);
    assert!(sites[0].s < 0.06 && sites[1].s > 0.22, "{sites:?}");
    assert_eq!((cfv, pop), (d(Absent, false), d(Continuous, true)));
    let c = builtin("popliteal-acute").unwrap();
    let (cfv, pop, sites) = at(&c);
    assert!((0.3..=0.4).contains(&sites[1].s), "{sites:?}");
    assert_eq!((cfv, pop), (d(Phasic, false), d(Absent, false)));
}

/// A non-occlusive CFV thrombus (half filled, 10–50 mm) leaves flow: the
/// CFV stays phasic and augments.
#[test]
fn non_occlusive_thrombus_keeps_the_flow() {
    let c = builtin("cfv-non-occlusive").unwrap();
    let (cfv, _, sites) = at(&c);
    assert!((0.01..=0.05).contains(&sites[0].s), "{sites:?}");
    assert_eq!(cfv, d(Phasic, true));
}

/// Scoring: the latest call per site counts, right only when both the
/// pattern and the augmentation match; a site without a call is wrong.
#[test]
fn doppler_score_counts_latest_calls_both_parts() {
    let c = builtin("popliteal-acute").unwrap();
    let (cfv_t, pop_t, sites) = at(&c);
    let call = |site: &str, f: DopplerFinding, truth: DopplerFinding| DopplerCall {
        site: site.into(),
        vein: "x".into(),
        s: 0.0,
        finding: f,
        truth,
        t: 0.0,
    };
    // CFV: first right (phasic, no augmentation), then changed to phasic
    // augmenting: wrong on augmentation alone.
    let calls = [
        call("cfv", d(Phasic, false), cfv_t),
        call("cfv", d(Phasic, true), cfv_t),
    ];
    let s = score_doppler(&sites, &[cfv_t, pop_t], &calls);
    assert_eq!((s.correct, s.total), (0, 2));
    assert_eq!(s.sites[0].call, Some(d(Phasic, true)));
    assert_eq!(s.sites[1].call, None);
    assert!(calls[0].is_correct() && !calls[1].is_correct());
    let calls = [
        call("cfv", d(Phasic, false), cfv_t),
        call("popliteal", d(Absent, false), pop_t),
    ];
    let s = score_doppler(&sites, &[cfv_t, pop_t], &calls);
    assert_eq!((s.correct, s.total), (2, 2));
    for f in FlowPattern::ALL {
        assert_eq!(FlowPattern::from_name(f.name()), Some(f));
    }
    assert_eq!(FlowPattern::from_name("monophasic"), None);
}
