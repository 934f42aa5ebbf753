//! The WebSocket protocol: state messages round-trip, frames parse, and bad
//! page messages are refused with an error naming the problem, never a panic.

use super::super::protocol::*;
use echothigh_runtime::live::{
    CouplingMode, LiveCommand, LiveMesh, LiveSnapshot, LiveStatus, SectionReading, StructureId,
    VeinState,
};
use proptest::prelude::*;

/// The limits of the test double's thigh (0.3 m long, 1 kHz haptics).
fn limits() -> CommandLimits {
    use echothigh_runtime::live::LiveControl;
    super::super::fake::FakeLive::new().limits()
}

/// [`super::super::protocol::decode_client`] against the test double's limits.
fn decode_client(text: &str) -> Result<ClientMessage, ProtocolError> {
    super::super::protocol::decode_client(text, &limits())
}

/// A state with every field set, an answered exam question and a visible vein.
pub(super) fn sample_state() -> ViewState {
    let status = LiveStatus {
        time: 1.25,
        probe_position: [0.0, 0.07, 0.01],
        probe_orientation: [1.0, 0.0, 0.0, 0.0],
        rendered_force: [0.0, 4.5, 0.0],
        physics_force: [0.0, 4.0, 0.1],
        max_force: 30.0,
        physics_rate: 98.0,
        haptic_rate: 1000.0,
        missed_deadlines: 3,
        model_age: 0.012,
        mode: Some(CouplingMode::Hold),
        physics_rate_setting: 100.0,
        latency_setting: 0.02,
        exam_playing: true,
        level_s: 0.2,
        level: Some(echothigh_runtime::live::LegLevel::FemoralCanal),
        ..Default::default()
    };
    let snap = LiveSnapshot {
        status,
        ..Default::default()
    };
    let exam = ExamStatus {
        rev: 7,
        active: true,
        trainee: Some("ada".into()),
        protocol: "two-point".into(),
        recording: "not recorded (practice)".into(),
        case_number: 2,
        cases_total: 3,
        cases_done: 2,
        calls_correct: 3,
        calls_total: 4,
        last: Some(CaseFeedback {
            case: "popliteal-acute".into(),
            title: "Popliteal thrombus".into(),
            diagnosis: "acute_dvt".into(),
            teaching: None,
            score: echothigh_exam::CaseScore {
                case: "popliteal-acute".into(),
                protocol: "two-point".into(),
                coverage: 1.0,
                calls_correct: 2,
                calls_total: 2,
                pressure_adequate: 1.0,
                excessive_force_on_tail: 0,
                duration: 61.5,
                peak_force: 14.0,
                mean_force: 6.5,
                sites: Vec::new(),
                missed: Vec::new(),
                doppler: Default::default(),
            },
            truth: vec![TruthSegment {
                vein: "pv".into(),
                s_start: 0.33,
                s_end: 0.37,
                kind: "acute_occlusive".into(),
            }],
            coverage: Vec::new(),
        }),
        ..ExamStatus::default()
    };
    ViewState::from_snapshot(&snap, Some(VeinState::Acute), Some(exam))
}

#[test]
fn state_message_is_versioned_typed_and_round_trips() {
    let state = sample_state();
    let text = serde_json::to_string(&Envelope::new(ServerMessage::State(state.clone()))).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(value["v"], 2);
    assert_eq!(value["type"], "state");
    assert_eq!(value["mode"], "hold");
    assert_eq!(value["vein"], "acute");
    assert_eq!(value["exam"]["last"]["truth"][0]["kind"], "acute_occlusive");
    let back: Envelope = serde_json::from_str(&text).unwrap();
    assert_eq!(back.v, PROTOCOL_VERSION);
    match back.body {
        ServerMessage::State(s) => assert_eq!(s, state),
        other => panic!("decoded {other:?}"),
    }
}

#[test]
fn hello_and_error_round_trip() {
    let mesh = LiveMesh {
        rest: vec![[0.0, 0.07, -0.1], [0.01, 0.069, -0.1], [0.0, 0.07, 0.1]],
        triangles: vec![[0, 1, 2]],
    };
    let hello = Envelope::new(ServerMessage::Hello {
        mesh,
        state_rate: 40.0,
        image: echothigh_runtime::live::ImageGeometry {
            width: 0.04,
            depth: 0.08,
        },
        image_link: Some("1f".into()),
    });
    let back: Envelope = serde_json::from_str(&serde_json::to_string(&hello).unwrap()).unwrap();
    match back.body {
        ServerMessage::Hello {
            mesh,
            state_rate,
            image,
            image_link,
        } => {
            assert_eq!(image_link.as_deref(), Some("1f"));
            assert_eq!(mesh.rest.len(), 3);
            assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
            assert_eq!(state_rate, 40.0);
            assert_eq!((image.width, image.depth), (0.04, 0.08));
        }
        other => panic!("decoded {other:?}"),
    }
    let err = Envelope::new(ServerMessage::Error {
        message: "nope".into(),
    });
    let text = serde_json::to_string(&err).unwrap();
    assert_eq!(text, r#"{"v":2,"type":"error","message":"nope"}"#);
}

#[test]
fn non_finite_snapshot_values_never_reach_the_page() {
    let snap = LiveSnapshot {
        status: LiveStatus {
            time: f64::NAN,
            rendered_force: [f64::INFINITY, 1.0, f64::NAN],
            model_age: f64::NEG_INFINITY,
            missed_deadlines: 7,
            ..Default::default()
        },
        ..Default::default()
    };
    let state = ViewState::from_snapshot(&snap, None, None);
    let s = state.status;
    assert_eq!(
        (s.time, s.rendered_force, s.model_age, s.missed_deadlines),
        (0.0, [0.0, 1.0, 0.0], 0.0, 7)
    );
    let value = serde_json::to_value(Envelope::new(ServerMessage::State(state))).unwrap();
    for key in ["time", "model_age", "max_force"] {
        assert!(value[key].is_f64(), "{key}: {value}");
    }
    assert!(value["rendered_force"]
        .as_array()
        .unwrap()
        .iter()
        .all(|c| c.is_f64()));
}

#[test]
fn sanitized_zeroes_every_non_finite_number_and_keeps_the_rest() {
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    let status = LiveStatus {
        time: f64::NAN,
        probe_position: bad,
        probe_orientation: [1.0, f64::NAN, 0.5, f64::INFINITY],
        device: bad,
        proxy: [0.1, f64::NAN, 0.2],
        rendered_force: bad,
        physics_force: [f64::NEG_INFINITY, 3.0, 0.0],
        max_force: f64::INFINITY,
        physics_rate: f64::NAN,
        haptic_rate: 999.0,
        missed_deadlines: 11,
        imaging_rate: f64::NAN,
        haptic_priority: echothigh_runtime::live::HapticPriority::Realtime,
        model_age: f64::NEG_INFINITY,
        mode: Some(CouplingMode::Direct),
        physics_rate_setting: f64::NAN,
        latency_setting: f64::INFINITY,
        exam_playing: true,
        level_s: f64::NAN,
        level: Some(echothigh_runtime::live::LegLevel::Popliteal),
        section: Some(SectionReading {
            s: f64::NAN,
            vein: Some(StructureId::Pv),
            vein_lumen_ratio: f64::INFINITY,
            artery_lumen_ratio: 0.9,
            walls_met: false,
            frame: 7,
            time: f64::NEG_INFINITY,
            image_depth: 0.060,
            target_band: [f64::NAN, 30.0],
            labels: Default::default(),
        }),
    };
    let expected = LiveStatus {
        time: 0.0,
        probe_position: [0.0; 3],
        probe_orientation: [1.0, 0.0, 0.5, 0.0],
        device: [0.0; 3],
        proxy: [0.1, 0.0, 0.2],
        rendered_force: [0.0; 3],
        physics_force: [0.0, 3.0, 0.0],
        max_force: 0.0,
        physics_rate: 0.0,
        haptic_rate: 999.0,
        missed_deadlines: 11,
        imaging_rate: 0.0,
        haptic_priority: echothigh_runtime::live::HapticPriority::Realtime,
        model_age: 0.0,
        mode: Some(CouplingMode::Direct),
        physics_rate_setting: 0.0,
        latency_setting: 0.0,
        exam_playing: true,
        level_s: 0.0,
        level: Some(echothigh_runtime::live::LegLevel::Popliteal),
        section: Some(SectionReading {
            s: 0.0,
            vein: Some(StructureId::Pv),
            vein_lumen_ratio: 0.0,
            artery_lumen_ratio: 0.9,
            walls_met: false,
            frame: 7,
            time: 0.0,
            image_depth: 0.060,
            target_band: [0.0, 30.0],
            labels: Default::default(),
        }),
    };
    assert_eq!(status.sanitized(), expected);
    assert_eq!(expected.sanitized(), expected, "finite values must be kept");
}

/// The state JSON carries the section reading (issue 13) under `section`,
/// additive: its fields by these names, the vein by its printed id, and
/// `null` before the imaging thread's first frame.
#[test]
fn the_state_carries_the_section_reading() {
    let mut snap = LiveSnapshot::default();
    snap.status.section = Some(SectionReading {
        s: 0.18,
        vein: Some(StructureId::Fv),
        vein_lumen_ratio: 0.02,
        artery_lumen_ratio: 0.97,
        walls_met: true,
        frame: 12,
        time: 3.5,
        image_depth: 0.060,
        target_band: [9.5, 28.0],
        labels: Default::default(),
    });
    let state = ViewState::from_snapshot(&snap, None, None);
    let j = serde_json::to_value(ServerMessage::State(state)).unwrap();
    let r = &j["section"];
    assert_eq!(r["s"], 0.18);
    assert_eq!(r["vein"], "fv");
    assert_eq!(r["vein_lumen_ratio"], 0.02);
    assert_eq!(r["artery_lumen_ratio"], 0.97);
    assert_eq!(r["walls_met"], true);
    assert_eq!(r["frame"], 12);
    assert_eq!(r["time"], 3.5);
    assert_eq!(r["target_band"], serde_json::json!([9.5, 28.0]));
    let none = ViewState::from_snapshot(&LiveSnapshot::default(), None, None);
    let j = serde_json::to_value(ServerMessage::State(none)).unwrap();
    assert!(j["section"].is_null(), "{j}");
}

#[test]
fn every_command_decodes_from_its_json() {
    let live = [
        LiveCommand::Probe {
            theta: 0.3,
            z: -0.05,
            depth: 0.01,
            tilt: -0.2,
        },
        LiveCommand::Lift,
        LiveCommand::PlayExam,
        LiveCommand::StopExam,
        LiveCommand::SetVein {
            vein: VeinState::Chronic,
        },
        LiveCommand::SetMode {
            mode: CouplingMode::Direct,
        },
        LiveCommand::SetPhysicsRate { hz: 250.0 },
        LiveCommand::SetLatency { seconds: 0.05 },
        LiveCommand::Reset,
    ];
    for cmd in live {
        let text = serde_json::to_string(&cmd).unwrap();
        assert_eq!(decode_client(&text), Ok(ClientMessage::Live(cmd)), "{text}");
    }
    let viewer = [
        ViewerCommand::ExamStart,
        ViewerCommand::ExamCall {
            site: "fv@190mm".into(),
            finding: echothigh_exam::Finding::ChronicPostThrombotic,
        },
        ViewerCommand::ExamFinish,
        ViewerCommand::ExamStop,
    ];
    for cmd in viewer {
        let text = serde_json::to_string(&cmd).unwrap();
        assert_eq!(
            decode_client(&text),
            Ok(ClientMessage::Viewer(cmd)),
            "{text}"
        );
    }
    // What the page literally sends.
    assert_eq!(
        decode_client(r#"{"type":"set_vein","vein":"acute"}"#),
        Ok(ClientMessage::Live(LiveCommand::SetVein {
            vein: VeinState::Acute
        }))
    );
    assert_eq!(
        decode_client(r#"{"type":"exam_call","site":"fv-mid","finding":"acute_dvt"}"#),
        Ok(ClientMessage::Viewer(ViewerCommand::ExamCall {
            site: "fv-mid".into(),
            finding: echothigh_exam::Finding::AcuteDvt
        }))
    );
}

fn refused(text: &str) -> ProtocolError {
    match decode_client(text) {
        Err(e) => e,
        Ok(m) => panic!("{text} was accepted as {m:?}"),
    }
}

#[test]
fn malformed_messages_are_refused() {
    assert!(matches!(refused("not json"), ProtocolError::Malformed(_)));
    assert!(matches!(refused("[1,2]"), ProtocolError::Malformed(_)));
    assert!(matches!(refused("42"), ProtocolError::Malformed(_)));
    assert!(matches!(
        refused(r#"{"theta":1}"#),
        ProtocolError::Malformed(_)
    ));
    assert!(matches!(
        refused(r#"{"type":7}"#),
        ProtocolError::Malformed(_)
    ));
    assert!(matches!(
        refused(&" ".repeat(MAX_CLIENT_MESSAGE + 1)),
        ProtocolError::TooLong(_)
    ));
}

#[test]
fn wrong_shapes_are_refused_naming_the_type() {
    let cases = [
        r#"{"type":"teleport"}"#,
        r#"{"type":"exam_cheat"}"#,
        r#"{"type":"probe","theta":"up","z":0,"depth":0,"tilt":0}"#,
        r#"{"type":"probe","theta":0,"z":0,"depth":0}"#,
        r#"{"type":"probe","theta":0,"z":0,"depth":0,"tilt":0,"force":9}"#,
        r#"{"type":"set_vein","vein":"purple"}"#,
        r#"{"type":"set_mode","mode":"Buffer"}"#,
        r#"{"type":"reset","now":true}"#,
        r#"{"type":"exam_call","site":"cfv","finding":"thrombus"}"#,
        r#"{"type":"exam_call","site":"cfv"}"#,
        r#"{"type":"exam_start","vein":"healthy"}"#,
        r#"{"type":"set_physics_rate","hz":1e400}"#,
    ];
    for text in cases {
        match refused(text) {
            ProtocolError::Invalid { kind, .. } => assert!(text.contains(&kind), "{text}"),
            ProtocolError::Malformed(_) => assert!(text.contains("1e400"), "{text}"),
            other => panic!("{text}: {other:?}"),
        }
    }
}

#[test]
fn out_of_range_numbers_are_refused_naming_the_field() {
    let cases = [
        (
            r#"{"type":"probe","theta":0,"z":0,"depth":-0.001,"tilt":0}"#,
            "probe.depth",
        ),
        (
            r#"{"type":"probe","theta":0,"z":0,"depth":0.3,"tilt":0}"#,
            "probe.depth",
        ),
        (
            r#"{"type":"probe","theta":0,"z":0,"depth":0.01,"tilt":1.2}"#,
            "probe.tilt",
        ),
        (
            r#"{"type":"probe","theta":40,"z":0,"depth":0.01,"tilt":0}"#,
            "probe.theta",
        ),
        (
            r#"{"type":"probe","theta":0,"z":5,"depth":0.01,"tilt":0}"#,
            "probe.z",
        ),
        (
            r#"{"type":"set_physics_rate","hz":5}"#,
            "set_physics_rate.hz",
        ),
        (
            r#"{"type":"set_physics_rate","hz":5000}"#,
            "set_physics_rate.hz",
        ),
        (
            r#"{"type":"set_latency","seconds":-0.01}"#,
            "set_latency.seconds",
        ),
        (
            r#"{"type":"set_latency","seconds":0.5}"#,
            "set_latency.seconds",
        ),
    ];
    for (text, expected) in cases {
        match refused(text) {
            ProtocolError::Command(CommandError::OutOfRange { field, .. }) => {
                assert_eq!(field, expected, "{text}")
            }
            other => panic!("{text}: {other:?}"),
        }
        assert!(refused(text).to_string().contains(expected));
    }
}

/// One validation (issue 16): a command out of range is refused by the page
/// protocol and by the runtime's seam (here the test double, which validates
/// through the same `LiveCommand::validate` as the live system) with the
/// same message, naming the field, its unit and its range.
#[test]
fn protocol_and_runtime_refuse_the_same_commands_with_the_same_message() {
    use echothigh_runtime::live::LiveControl;
    let fake = super::super::fake::FakeLive::new();
    let bad = [
        LiveCommand::Probe {
            theta: 3.5,
            z: 0.0,
            depth: 0.01,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.16,
            depth: 0.01,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: 0.041,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: -0.001,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: 0.01,
            tilt: -0.61,
        },
        LiveCommand::SetPhysicsRate { hz: 9.9 },
        LiveCommand::SetPhysicsRate { hz: 1000.5 },
        LiveCommand::SetLatency { seconds: 0.21 },
    ];
    for cmd in bad {
        let text = serde_json::to_string(&cmd).unwrap();
        let by_protocol = refused(&text).to_string();
        let by_runtime = fake.command(cmd.clone()).unwrap_err();
        assert_eq!(by_protocol, by_runtime, "{text}");
        let field = match cmd.validate(&limits()).unwrap_err() {
            CommandError::OutOfRange { field, .. } => field,
        };
        assert!(by_protocol.contains(field), "{by_protocol}");
        assert!(by_protocol.contains("out of range ["), "{by_protocol}");
    }
    // Just inside every range: accepted by both.
    let good = [
        LiveCommand::Probe {
            theta: -std::f64::consts::PI,
            z: 0.15,
            depth: 0.04,
            tilt: 0.6,
        },
        LiveCommand::SetPhysicsRate { hz: 1000.0 },
        LiveCommand::SetLatency { seconds: 0.2 },
    ];
    for cmd in good {
        let text = serde_json::to_string(&cmd).unwrap();
        assert!(decode_client(&text).is_ok(), "{text}");
        assert_eq!(fake.command(cmd), Ok(()));
    }
    // Nothing refused reached the double's state.
    assert_eq!(fake.commands().len(), 3);
}

#[test]
fn frames_round_trip_and_sanitise() {
    let pixels: Vec<u8> = (0..12).collect();
    let mut buf = Vec::new();
    encode_image(4, 3, &pixels, &mut buf);
    let (h, body) = FrameHeader::parse(&buf).unwrap();
    assert_eq!((h.kind, h.a, h.b), (FrameKind::Image, 4, 3));
    assert_eq!(body, &pixels[..]);
    assert!(
        FrameHeader::parse(&buf[..buf.len() - 1]).is_none(),
        "truncated frame parsed"
    );
    encode_image(5, 3, &pixels, &mut buf); // too few pixels: empty frame
    let (h, body) = FrameHeader::parse(&buf).unwrap();
    assert_eq!((h.a, h.b, body.len()), (0, 0, 0));

    let snap = LiveSnapshot {
        positions: vec![[1.0, 2.0, 3.0], [f32::NAN, 5.0, 6.0]],
        compression: vec![0.25, 0.5, 0.75],
        ..Default::default()
    };
    encode_surface(&snap, &mut buf);
    let (h, body) = FrameHeader::parse(&buf).unwrap();
    assert_eq!((h.kind, h.a), (FrameKind::Surface, 2));
    let floats: Vec<f32> = body
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(floats, vec![1.0, 2.0, 3.0, 0.0, 5.0, 6.0, 0.25, 0.5]);
    let mut bad = buf.clone();
    bad[0] = b'X';
    assert!(FrameHeader::parse(&bad).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = decode_client(&text);
        let _ = FrameHeader::parse(&bytes);
    }

    #[test]
    fn random_json_objects_never_panic(
        kind in prop_oneof![Just("probe".to_owned()), Just("set_vein".to_owned()), Just("exam_call".to_owned()), Just("set_latency".to_owned()), "[a-z_]{0,12}"],
        key in "[a-z_]{1,10}",
        num in any::<f64>(),
        s in "\\PC{0,8}",
    ) {
        for value in [serde_json::json!(num), serde_json::json!(s), serde_json::json!(null), serde_json::json!([num])] {
            let text = serde_json::json!({ "type": kind, key.clone(): value }).to_string();
            let _ = decode_client(&text);
        }
    }

    #[test]
    fn probe_depth_accepted_iff_in_range(depth in -0.2f64..0.2) {
        let text = format!(r#"{{"type":"probe","theta":0.1,"z":0.0,"depth":{depth},"tilt":0.0}}"#);
        let ok = decode_client(&text).is_ok();
        prop_assert_eq!(ok, (DEPTH_RANGE.0..=DEPTH_RANGE.1).contains(&depth));
    }
}
