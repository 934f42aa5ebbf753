//! One client connection of the emulated Inverse Service: a WebSocket
//! session (inventory, then one state frame per message) or one plain HTTP
//! request on the same port.

use super::{Hardware, Shared, DEVICE_ID, GRIP_ID};
use crate::lock;
use haply::device_model::{
    Buttons, DeviceConfig, DeviceInfo, DeviceType, Inverse3Device, Inverse3Message, Inverse3State,
    Inverse3Status, ServiceData, ServiceState, SetCursorForceCmd, Vec3D, Vec4D, VersionResponse,
    WVGConfig, WirelessVerseGripDevice, WirelessVerseGripMessage, WirelessVerseGripState,
    WirelessVerseGripStatus,
};
use serde_json::Value;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;
use tungstenite::Message;

const SESSION_ID: u64 = 1;

fn v3(a: [f64; 3]) -> Vec3D {
    Vec3D {
        x: a[0] as f32,
        y: a[1] as f32,
        z: a[2] as f32,
    }
}

fn inverse3_state(hw: &Hardware) -> (Inverse3State, Inverse3Status) {
    let state = Inverse3State {
        cursor_position: Some(v3(hw.arm.position)),
        cursor_velocity: Some(v3(hw.arm.velocity)),
        current_cursor_force: Some(v3(hw.arm.motor)),
        ..Inverse3State::default()
    };
    let status = Inverse3Status {
        calibrated: true,
        in_use: true,
        power_supply: true,
        ready: true,
        started: true,
        navigation: None,
    };
    (state, status)
}

fn grip_state(q: [f64; 4], buttons: u32) -> (WirelessVerseGripState, WirelessVerseGripStatus) {
    let state = WirelessVerseGripState {
        orientation: Some(Vec4D {
            w: q[0] as f32,
            x: q[1] as f32,
            y: q[2] as f32,
            z: q[3] as f32,
        }),
        buttons: Some(Buttons {
            a: buttons & 1 != 0,
            b: buttons & 2 != 0,
            c: buttons & 4 != 0,
            ..Buttons::default()
        }),
        battery_level: Some(1.0),
        ..WirelessVerseGripState::default()
    };
    let status = WirelessVerseGripStatus {
        ready: true,
        connected: true,
        awake: true,
    };
    (state, status)
}

/// The inventory: every listed device with its `config`.
fn inventory(hw: &Hardware) -> ServiceData {
    let mut data = ServiceData {
        session_id: SESSION_ID,
        ..ServiceData::default()
    };
    if hw.present {
        let (state, status) = inverse3_state(hw);
        data.inverse3.push(Inverse3Device {
            device_id: DEVICE_ID.into(),
            config: Some(DeviceConfig {
                id: DEVICE_ID.into(),
                type_: DeviceType::Inverse3,
                device_info: DeviceInfo {
                    id: DEVICE_ID.into(),
                    major_version: 7,
                    minor_version: 4,
                    device_type: DeviceType::Inverse3,
                    uuid: "echothigh-emulated".into(),
                },
                port: "emulated".into(),
                preset: Some("defaults".into()),
                ..DeviceConfig::default()
            }),
            state,
            status,
        });
    }
    if let Some((q, b)) = hw.grip {
        let (state, status) = grip_state(q, b);
        data.wireless_verse_grip.push(WirelessVerseGripDevice {
            device_id: GRIP_ID.into(),
            config: Some(WVGConfig {
                id: GRIP_ID.into(),
                port: "emulated".into(),
                type_: DeviceType::WirelessVerseGrip,
                major_version: 1,
                ..WVGConfig::default()
            }),
            state,
            status,
        });
    }
    data
}

/// A state frame (no `config`).
fn state_frame(hw: &Hardware) -> ServiceState {
    let mut s = ServiceState {
        session_id: SESSION_ID,
        ..ServiceState::default()
    };
    if hw.present {
        let (state, status) = inverse3_state(hw);
        s.inverse3.push(Inverse3Message {
            device_id: DEVICE_ID.into(),
            state,
            status,
        });
    }
    if let Some((q, b)) = hw.grip {
        let (state, status) = grip_state(q, b);
        s.wireless_verse_grip.push(WirelessVerseGripMessage {
            device_id: GRIP_ID.into(),
            state,
            status,
        });
    }
    s
}

/// Applies one client message (the arm integrated up to its arrival with
/// the previous force held) and returns the state frame answering it.
fn handle(shared: &Shared, text: &str) -> String {
    let mut hw = lock(&shared.hw);
    hw.integrate();
    hw.frames += 1;
    // A message the service cannot read still gets its one reply. The
    // command is read as the crate's `SetCursorForceCmd`, not the whole
    // `ServiceMsg`: that type skips its empty device arrays when it
    // serialises but requires them when it parses, so it cannot read a
    // frame of its own making that names only an Inverse3.
    let cmd = serde_json::from_str::<Value>(text).ok().and_then(|v| {
        v.get("inverse3")?
            .as_array()?
            .iter()
            .filter(|m| m.get("device_id").and_then(Value::as_str) == Some(DEVICE_ID))
            .filter_map(|m| m.pointer("/commands/set_cursor_force"))
            .filter_map(|c| serde_json::from_value::<SetCursorForceCmd>(c.clone()).ok())
            .next_back()
    });
    if let Some(cmd) = cmd.filter(|c| c.execute) {
        let f = [
            f64::from(cmd.vector.x),
            f64::from(cmd.vector.y),
            f64::from(cmd.vector.z),
        ];
        hw.last_force = (f, crate::now());
        if hw.present && f.iter().all(|c| c.is_finite()) {
            hw.arm.motor = f;
            let n = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            hw.max_applied = hw.max_applied.max(n);
        }
    }
    serde_json::to_string(&state_frame(&hw)).unwrap_or_default()
}

/// Serves one connection until the client leaves or the service is killed.
pub(crate) fn serve(stream: TcpStream, shared: Arc<Shared>) {
    let _ = stream.set_nonblocking(false);
    let _ = stream.set_nodelay(true);
    // Poll the kill flag between reads.
    let _ = stream.set_read_timeout(Some(Duration::from_millis(5)));
    let mut head = [0u8; 1024];
    let mut n = 0;
    for _ in 0..200 {
        match stream.peek(&mut head) {
            Ok(k) if k > 0 && head[..k].windows(4).any(|w| w == b"\r\n\r\n") => {
                n = k;
                break;
            }
            Ok(0) => return,
            _ => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    let request = String::from_utf8_lossy(&head[..n]).to_ascii_lowercase();
    if !request.contains("upgrade: websocket") {
        http(stream, &request, &shared);
        return;
    }
    let _ = stream.set_read_timeout(Some(Duration::from_secs(1)));
    let Ok(mut ws) = tungstenite::accept(stream) else {
        return;
    };
    let _ = ws
        .get_mut()
        .set_read_timeout(Some(Duration::from_millis(5)));
    let first = serde_json::to_string(&inventory(&lock(&shared.hw))).unwrap_or_default();
    if ws.send(Message::Text(first.into())).is_err() {
        return;
    }
    while !shared.killed.load(Ordering::Acquire) {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let reply = handle(&shared, t.as_str());
                if ws.send(Message::Text(reply.into())).is_err() {
                    break;
                }
            }
            Ok(Message::Close(_)) => {
                let _ = ws.flush();
                break;
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => break,
        }
    }
    // The session ended (or the service died): the emulator releases the motors.
    let mut hw = lock(&shared.hw);
    hw.integrate();
    if hw.last_force.0 != [0.0; 3] {
        hw.closed_with_force += 1;
    }
    hw.arm.motor = [0.0; 3];
}

/// Answers `GET /version` and `GET /devices` as the service's REST interface.
fn http(mut stream: TcpStream, request: &str, shared: &Shared) {
    let mut sink = vec![0u8; request.len()];
    let _ = stream.read_exact(&mut sink);
    let path = request.split_whitespace().nth(1).unwrap_or("/");
    let (status, body) = match path.trim_end_matches('/') {
        "/version" => (
            "200 OK",
            serde_json::to_string(&VersionResponse {
                project_name: "echothigh inverse-service emulator".into(),
                project_version: "3.5.0".into(),
                ..VersionResponse::default()
            })
            .unwrap_or_default(),
        ),
        "/devices" => (
            "200 OK",
            serde_json::to_string(&inventory(&lock(&shared.hw))).unwrap_or_default(),
        ),
        _ => (
            "404 Not Found",
            r#"{"ok":false,"error":"not emulated"}"#.to_string(),
        ),
    };
    let _ = write!(
        stream,
        "HTTP/1.1 {status}\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{body}",
        body.len()
    );
}
