//! The server with a real haptic device driving the probe (issue 15),
//! against the runtime's test double: the page's probe commands are refused
//! like an observer tab's, and the state carries the device's status. (The
//! live system's own refusal, with the emulated Touch, is tested in
//! `echothigh-runtime`'s `tests/suite/live_device.rs`.)

use super::super::fake::FakeLive;
use super::server::{connect, next_error, next_state, send, start};
use echothigh_runtime::live::LiveCommand;
use echothigh_runtime::live_device::LiveDeviceStatus;
use std::sync::Arc;

fn touch() -> LiveDeviceStatus {
    LiveDeviceStatus {
        name: "openhaptics: Touch".into(),
        connected: true,
        clutched: true,
        force: [0.0, 1.5, 0.0],
        max_force: 3.3,
        orientation_sensed: true,
        workspace: None,
        lost: None,
    }
}

#[tokio::test]
async fn probe_commands_are_refused_while_a_device_drives() {
    let fake = Arc::new(FakeLive::new());
    fake.attach_device(touch());
    let mut ws = connect(start(fake.clone()).await).await;
    let s = next_state(&mut ws, |s| s.haptic_device.is_some()).await;
    let d = s.haptic_device.unwrap();
    assert_eq!(
        d,
        touch(),
        "the device's status reaches the page as the runtime gave it"
    );
    assert!(!s.observer, "the only tab still drives the other controls");
    for cmd in [
        r#"{"type":"probe","theta":0.1,"z":0.0,"depth":0.01,"tilt":0.0}"#,
        r#"{"type":"lift"}"#,
        r#"{"type":"play_exam"}"#,
    ] {
        send(&mut ws, cmd).await;
        let e = next_error(&mut ws).await;
        assert!(
            e.contains("openhaptics: Touch") && e.contains("drives the probe"),
            "{cmd}: {e}"
        );
    }
    // The settings still pass; no probe command reached the runtime.
    send(&mut ws, r#"{"type":"set_latency","seconds":0.01}"#).await;
    let s = next_state(&mut ws, |s| s.status.latency_setting == 0.01).await;
    assert_eq!(s.status.latency_setting, 0.01);
    let cmds = fake.commands();
    assert!(
        !cmds.iter().any(|c| matches!(
            c,
            LiveCommand::Probe { .. } | LiveCommand::Lift | LiveCommand::PlayExam
        )),
        "{cmds:?}"
    );
}

#[tokio::test]
async fn without_a_device_the_mouse_drives() {
    let fake = Arc::new(FakeLive::new());
    let mut ws = connect(start(fake.clone()).await).await;
    send(
        &mut ws,
        r#"{"type":"probe","theta":0.1,"z":0.0,"depth":0.01,"tilt":0.0}"#,
    )
    .await;
    let s = next_state(&mut ws, |s| s.status.rendered_force[1] > 0.0).await;
    assert!(s.haptic_device.is_none());
    assert!(fake
        .commands()
        .iter()
        .any(|c| matches!(c, LiveCommand::Probe { .. })));
}
