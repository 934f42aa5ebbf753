//! The state message as the page receives it: the top-level keys are the
//! ones the embedded scripts read, and the text is pinned byte for byte.

use super::super::protocol::{Envelope, ServerMessage};
use super::protocol::sample_state;

/// Top-level keys of a state message that the page reads: `msg.v` and
/// `msg.type` in `app.js`'s `onJson`, the rest as `s.<key>` in `onState`,
/// `syncControls` (app.js), `showStatus` (panels.js) and `updateState`
/// (scene.js).
const PAGE_STATE_KEYS: [&str; 30] = [
    "v",
    "type",
    "time",
    "probe_position",
    "probe_orientation",
    "device",
    "proxy",
    "rendered_force",
    "physics_force",
    "max_force",
    "physics_rate",
    "haptic_rate",
    "missed_deadlines",
    "imaging_rate",
    "haptic_priority",
    "model_age",
    "mode",
    "physics_rate_setting",
    "latency_setting",
    "exam_playing",
    "level_s",
    "level",
    "section",
    "vein",
    "exam",
    "observer",
    "seq",
    "sent_ms",
    "fault",
    "haptic_device",
];

#[test]
fn state_message_top_level_keys_are_the_ones_the_page_reads() {
    use std::collections::BTreeSet;
    let value = serde_json::to_value(Envelope::new(ServerMessage::State(sample_state()))).unwrap();
    let sent: BTreeSet<&str> = value
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    let page: BTreeSet<&str> = PAGE_STATE_KEYS.into_iter().collect();
    assert_eq!(sent, page);
    // The list is the page's: each key is read by the embedded scripts.
    let js: String = crate::assets::ASSETS
        .iter()
        .filter(|a| a.path.ends_with(".js") && !a.path.contains("vendor"))
        .map(|a| String::from_utf8_lossy(a.body).into_owned())
        .collect();
    for key in PAGE_STATE_KEYS {
        let read = [format!("msg.{key}"), format!("s.{key}")];
        assert!(
            read.iter().any(|r| js.contains(r.as_str())),
            "the page never reads `{key}`"
        );
    }
}

/// The page's copy of the imaging thread's schedule (`panels.js`
/// `IMAGING_RATE`, against which it says the image falls behind) is the
/// runtime's.
#[test]
fn the_pages_imaging_rate_is_the_runtimes() {
    let panels = crate::assets::ASSETS
        .iter()
        .find(|a| a.path.ends_with("panels.js"))
        .expect("panels.js is embedded");
    let text = String::from_utf8_lossy(panels.body);
    let want = format!(
        "export const IMAGING_RATE = {};",
        echothigh_runtime::live::IMAGING_RATE_SETTING
    );
    assert!(text.contains(&want), "panels.js lacks `{want}`");
}

#[test]
fn state_json_is_unchanged_byte_for_byte() {
    // The exact text the page received before `ViewState` flattened
    // `LiveStatus`: same keys, same nesting, same order (plus `observer`,
    // `seq` and `fault`, added last for issues 19 and 16; `level_s` and
    // `level`, the probe's place along the leg, for issue 12; `section`, the
    // imaged section's reading, for issue 13; the exam's case status for
    // issue 14, with its Doppler sites and the score's Doppler part;
    // `haptic_device`, the real device driving the probe, added last for
    // issue 15; `haptic_priority`, the haptic thread's scheduling, for
    // issue 19; `imaging_rate`, the image's achieved frames/s, for issue 19;
    // `sent_ms`, when the server sent it, for issue 19's lag split —
    // this golden was updated deliberately for each).
    let expected = concat!(
        r#"{"v":2,"type":"state","time":1.25,"probe_position":[0.0,0.07,0.01],"#,
        r#""probe_orientation":[1.0,0.0,0.0,0.0],"device":[0.0,0.0,0.0],"#,
        r#""proxy":[0.0,0.0,0.0],"rendered_force":[0.0,4.5,0.0],"#,
        r#""physics_force":[0.0,4.0,0.1],"max_force":30.0,"physics_rate":98.0,"#,
        r#""haptic_rate":1000.0,"missed_deadlines":3,"imaging_rate":0.0,"haptic_priority":"normal","model_age":0.012,"mode":"hold","#,
        r#""physics_rate_setting":100.0,"latency_setting":0.02,"exam_playing":true,"#,
        r#""level_s":0.2,"level":"femoral_canal","section":null,"#,
        r#""vein":"acute","exam":{"rev":7,"active":true,"trainee":"ada","protocol":"two-point","#,
        r#""recording":"not recorded (practice)","case_number":2,"cases_total":3,"open":false,"#,
        r#""vignette":null,"sites":[],"doppler":[],"coverage":[],"presses":0,"peak_force":0.0,"cases_done":2,"#,
        r#""calls_correct":3,"calls_total":4,"last":{"case":"popliteal-acute","#,
        r#""title":"Popliteal thrombus","diagnosis":"acute_dvt","teaching":null,"#,
        r#""score":{"case":"popliteal-acute","protocol":"two-point","coverage":1.0,"#,
        r#""calls_correct":2,"calls_total":2,"pressure_adequate":1.0,"excessive_force_on_tail":0,"#,
        r#""duration":61.5,"peak_force":14.0,"mean_force":6.5,"sites":[],"missed":[],"#,
        r#""doppler":{"correct":0,"total":0,"sites":[]}},"#,
        r#""truth":[{"vein":"pv","s_start":0.33,"s_end":0.37,"kind":"acute_occlusive"}],"#,
        r#""coverage":[]},"error":null},"observer":false,"seq":0,"sent_ms":0.0,"fault":null,"haptic_device":null}"#
    );
    let text = serde_json::to_string(&Envelope::new(ServerMessage::State(sample_state()))).unwrap();
    assert_eq!(text, expected);
}

#[test]
fn the_device_status_json_is_pinned() {
    // Issue 15: what the page's `device.js` reads of `haptic_device`, byte
    // for byte (a lost device: `connected` false, its reason in `lost`).
    use echothigh_runtime::live_device::LiveDeviceStatus;
    let mut corners = [[0.0; 3]; 8];
    for (i, c) in corners.iter_mut().enumerate() {
        *c = [
            (i & 1) as f64 * 0.5,
            ((i >> 1) & 1) as f64 * 0.25,
            ((i >> 2) & 1) as f64 * 0.125,
        ];
    }
    let mut state = sample_state();
    state.haptic_device = Some(LiveDeviceStatus {
        name: "openhaptics: Touch".into(),
        connected: false,
        clutched: true,
        force: [0.0, 1.5, f64::NAN],
        max_force: 3.3,
        orientation_sensed: true,
        workspace: Some(corners),
        lost: Some("gone".into()),
    });
    // The sanitizing of `ViewState::from_snapshot` is what the server sends.
    let d = state.haptic_device.as_ref().unwrap().sanitized();
    let text = serde_json::to_string(&d).unwrap();
    let expected = concat!(
        r#"{"name":"openhaptics: Touch","connected":false,"clutched":true,"force":[0.0,1.5,0.0],"#,
        r#""max_force":3.3,"orientation_sensed":true,"workspace":[[0.0,0.0,0.0],[0.5,0.0,0.0],"#,
        r#"[0.0,0.25,0.0],[0.5,0.25,0.0],[0.0,0.0,0.125],[0.5,0.0,0.125],[0.0,0.25,0.125],"#,
        r#"[0.5,0.25,0.125]],"lost":"gone"}"#
    );
    assert_eq!(text, expected);
    // Every key is read by the page's device.js.
    let js = crate::assets::ASSETS
        .iter()
        .find(|a| a.path == "/device.js")
        .map(|a| String::from_utf8_lossy(a.body).into_owned())
        .unwrap();
    for key in [
        "name",
        "connected",
        "clutched",
        "force",
        "max_force",
        "orientation_sensed",
        "workspace",
        "lost",
    ] {
        assert!(
            js.contains(&format!("d.{key}")),
            "device.js never reads `{key}`"
        );
    }
}
