//! `echothigh report` on a fixed database: the page carries the
//! hand-computed numbers, its plots and its calls table, with no network
//! reference; an unknown trainee is a clear error.
//!
//! The fixed record (trainee "Jo"), sites as site: truth / call:
//! Session 1: case A  cfv: acute/acute (TP), popliteal: normal/normal (TN);
//!                    coverage 1.0, presses 2 of 2 adequate, calls 2/2.
//!            case B  cfv: normal/acute (FP), popliteal: acute/normal (FN);
//!                    coverage 0.5, presses 0 of 2 adequate, calls 0/2.
//! Session 2: case C  cfv: acute/acute (TP), popliteal, fv-mid: normal/normal
//!                    (TN, TN); coverage 0.9, presses 3 of 4, calls 3/3.
//! Overall: sensitivity 2/3 = 66.7 %, specificity 3/4 = 75.0 %, coverage
//! (1 + 0.5 + 0.9)/3 = 80.0 %, calls 5/7 = 71.4 %, pressure 5/8 = 62.5 %.
//! Session 1: 1/2, 1/2, 75.0 %, 2/4, 2/4 → 50.0 % each but coverage.
//! Session 2: 100.0 % everywhere but coverage 90.0 % and pressure 3/4 = 75.0 %.

use echothigh_exam::{
    BinState, Call, CaseScore, CompressionEvent, CoverageBin, ExamLog, Finding, SiteScore,
};
use echothigh_records::{BlockingStore, SessionId, TruthSegment};
use std::process::Command;
use Finding::*;

fn press(k: usize, adequate: bool) -> CompressionEvent {
    let t = k as f64 * 3.0;
    CompressionEvent {
        t_start: t,
        t_end: t + 1.0,
        vein: Some("cfv".into()),
        s: 0.01,
        peak_force: 10.0 + k as f64,
        min_lumen_ratio: if adequate { 0.0 } else { 0.6 },
        artery_deformed: adequate,
        coapted: adequate,
        slide: 0.0,
        force_trace: (0..=50)
            .map(|i| [t + i as f64 * 0.02, (10.0 + k as f64) * (i as f64 / 50.0)])
            .collect(),
    }
}

fn case(
    store: &BlockingStore,
    s: SessionId,
    name: &str,
    sites: &[(&str, Finding, Finding)],
    cov: f64,
    presses: &[bool],
) {
    let truth = vec![
        TruthSegment {
            vein: "cfv".into(),
            s_start: 0.0,
            s_end: 0.03,
            kind: "acute_occlusive".into(),
        },
        TruthSegment {
            vein: "cfv".into(),
            s_start: 0.03,
            s_end: 0.06,
            kind: "normal".into(),
        },
    ];
    let mut rec = store.begin_case(s, name, &truth).unwrap();
    for (k, &a) in presses.iter().enumerate() {
        rec.event(&press(k, a)).unwrap();
    }
    for (i, &(site, truth, call)) in sites.iter().enumerate() {
        rec.call(&Call {
            site: site.into(),
            vein: "cfv".into(),
            s: 0.01,
            finding: call,
            truth,
            t: 5.0 + i as f64,
        })
        .unwrap();
    }
    let bins = [
        BinState::Closed,
        BinState::NotClosed,
        BinState::InadequatePressure,
    ]
    .iter()
    .enumerate()
    .map(|(i, &state)| CoverageBin {
        vein: "cfv".into(),
        s_start: 0.02 * i as f64,
        s_end: 0.02 * (i + 1) as f64,
        state,
    })
    .collect::<Vec<_>>();
    let correct = sites.iter().filter(|(_, t, c)| t == c).count() as u32;
    let score = CaseScore {
        case: name.into(),
        protocol: "two-point".into(),
        coverage: cov,
        calls_correct: correct,
        calls_total: sites.len() as u32,
        pressure_adequate: 0.0,
        excessive_force_on_tail: 0,
        duration: 30.0,
        peak_force: 14.0,
        mean_force: 11.0,
        sites: sites
            .iter()
            .map(|&(site, truth, call)| SiteScore {
                site: site.into(),
                call: Some(call),
                truth,
                pressure_adequate: true,
                called_without_adequate_pressure: false,
            })
            .collect(),
        missed: Vec::new(),
        doppler: Default::default(),
    };
    rec.finish(&bins, &score).unwrap();
}

#[test]
fn the_report_carries_the_hand_computed_numbers_plots_and_calls() {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite://{}", dir.path().join("records.sqlite3").display());
    {
        let store = BlockingStore::open(Some(&url)).unwrap();
        let jo = store.trainee("Jo").unwrap();
        let s1 = store.begin_session(&jo, "two-point").unwrap();
        case(
            &store,
            s1,
            "A",
            &[("cfv", AcuteDvt, AcuteDvt), ("popliteal", Normal, Normal)],
            1.0,
            &[true, true],
        );
        case(
            &store,
            s1,
            "B",
            &[("cfv", Normal, AcuteDvt), ("popliteal", AcuteDvt, Normal)],
            0.5,
            &[false, false],
        );
        let s2 = store.begin_session(&jo, "three-point").unwrap();
        let c = [
            ("cfv", AcuteDvt, AcuteDvt),
            ("popliteal", Normal, Normal),
            ("fv-mid", Normal, Normal),
        ];
        case(&store, s2, "C", &c, 0.9, &[true, true, true, false]);
    }
    let out = dir.path().join("report");
    let run = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(["report", "--trainee", "Jo", "--db", &url, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains(
        "<tr><td>3</td><td>80.0 %</td><td>71.4 %</td><td>62.5 %</td><td>66.7 %</td><td>75.0 %</td><td>0</td></tr>"
    ));
    assert!(html.contains("<td>2</td><td>75.0 %</td><td>50.0 %</td><td>50.0 %</td><td>50.0 %</td><td>50.0 %</td></tr>"));
    assert!(html.contains("<td>1</td><td>90.0 %</td><td>100.0 %</td><td>75.0 %</td><td>100.0 %</td><td>100.0 %</td></tr>"));
    // One trend plot, and per case a coverage strip and a force plot.
    assert_eq!(html.matches("<svg").count(), 1 + 2 * 3);
    // B's two calls are the wrong ones.
    assert_eq!(html.matches("class=\"wrong\"").count(), 2);
    // Self-contained: nothing fetched.
    for fetch in ["<script", "<link", "src=", "url("] {
        assert!(!html.contains(fetch), "{fetch}");
    }
    // The coverage strip's closed bin and the truth's acute piece are drawn
    // in their colours (#2E7D32, #282828).
    let upper = html.to_uppercase();
    assert!(upper.contains("#2E7D32") && upper.contains("#282828"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(
        json["history"]["rates"]["sensitivity"].as_f64(),
        Some(2.0 / 3.0)
    );
    assert_eq!(json["history"]["rates"]["specificity"].as_f64(), Some(0.75));
    assert_eq!(json["cases"].as_array().unwrap().len(), 3);

    let run = Command::new(env!("CARGO_BIN_EXE_echothigh"))
        .args(["report", "--trainee", "Nobody", "--db", &url, "--out"])
        .arg(dir.path().join("nobody"))
        .output()
        .unwrap();
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("no trainee named `Nobody`") && err.contains("records.sqlite3"),
        "{err}"
    );
    assert!(!dir.path().join("nobody").exists());
}
