//! The Inverse Service's JSON frames, built and read with the `haply`
//! crate's message types (Inverse Service 3.5 format).
//!
//! Outgoing: one [`ServiceMsg`] per round trip carrying the Inverse3's
//! `set_cursor_force` (N, device frame); the first also registers the
//! session's profile. Incoming: the first frame is the service's inventory
//! (every device with its `config`), each later one the devices' `state`.
//!
//! Incoming frames are read field by field ([`Vec3D`], [`Vec4D`],
//! [`Buttons`] of the crate) rather than as the crate's whole
//! `ServiceState`: its derive requires fields (e.g. `Inverse3State::mode`,
//! every `Inverse3Status` flag) that the 3.5 documentation's frames do not
//! all carry, which is why the crate's own listener falls back through three
//! parsers. Reading only what the backend uses keeps a frame with extra or
//! missing unrelated fields usable.

use haply::device_model::{
    Buttons, Force, Inverse3Commands, Inverse3OutMsg, ProfileConfig, ServiceMsg, SessionConfigure,
    SessionMsg, SetCursorForceCmd, Vec3D, Vec4D,
};
use nalgebra::{Quaternion, UnitQuaternion};
use serde_json::Value;

/// The profile name the session registers under (shown by Haply Hub).
pub const PROFILE: &str = "echothigh";

/// One Inverse3 or VerseGrip the service listed.
#[derive(Debug, Clone, PartialEq)]
pub struct Listed {
    /// The service's `device_id`.
    pub id: String,
    /// `config.type` (`inverse3`, `minverse`, `wireless_verse_grip`, ...).
    pub kind: String,
}

/// The service's first frame: its session and devices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Inventory {
    /// Session number the service gave this connection.
    pub session_id: u64,
    /// Inverse3-family devices.
    pub inverse3: Vec<Listed>,
    /// VerseGrips, wired, wireless and custom.
    pub grips: Vec<Listed>,
}

/// What one state frame says of the driven devices (SI units, device frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// Cursor position (m).
    pub position: [f64; 3],
    /// Cursor velocity (m/s).
    pub velocity: [f64; 3],
    /// The VerseGrip's orientation, row-major device ← grip; `None` without a grip.
    pub rotation: Option<[f64; 9]>,
    /// Grip buttons: bit 0 = `a` (or a wired grip's button), 1 = `b`, 2 = `c`.
    pub buttons: u32,
}

/// Parses the inventory frame.
pub fn inventory(text: &str) -> Result<Inventory, String> {
    let v: Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let listed = |key: &str, default_kind: &str| -> Vec<Listed> {
        v.get(key)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|d| {
                        let id = d.get("device_id")?.as_str()?.to_string();
                        let kind = d
                            .pointer("/config/type")
                            .and_then(Value::as_str)
                            .unwrap_or(default_kind)
                            .to_string();
                        Some(Listed { id, kind })
                    })
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut grips = listed("wireless_verse_grip", "wireless_verse_grip");
    grips.extend(listed("custom_verse_grip", "custom_verse_grip"));
    grips.extend(listed("verse_grip", "verse_grip"));
    Ok(Inventory {
        session_id: v.get("session_id").and_then(Value::as_u64).unwrap_or(0),
        inverse3: listed("inverse3", "inverse3"),
        grips,
    })
}

/// Finds `id` in the array `key` of a frame.
fn entry<'a>(frame: &'a Value, key: &str, id: &str) -> Option<&'a Value> {
    frame
        .get(key)?
        .as_array()?
        .iter()
        .find(|d| d.get("device_id").and_then(Value::as_str) == Some(id))
}

fn vec3(v: Option<&Value>) -> Option<[f64; 3]> {
    let p: Vec3D = serde_json::from_value(v?.clone()).ok()?;
    let out = [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
    out.iter().all(|c| c.is_finite()).then_some(out)
}

/// Parses a state frame for the Inverse3 `device` and the grip `grip`.
/// `Ok(None)` when the frame no longer lists the Inverse3 (disconnected).
pub fn reading(text: &str, device: &str, grip: Option<&str>) -> Result<Option<Reading>, String> {
    let v: Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let Some(inv) = entry(&v, "inverse3", device) else {
        return Ok(None);
    };
    let state = inv.get("state");
    let position = vec3(state.and_then(|s| s.get("cursor_position")))
        .ok_or("a state frame without a finite cursor_position")?;
    let velocity = vec3(state.and_then(|s| s.get("cursor_velocity"))).unwrap_or([0.0; 3]);
    let (mut rotation, mut buttons) = (None, 0);
    if let Some(grip) = grip {
        let found = ["wireless_verse_grip", "custom_verse_grip", "verse_grip"]
            .iter()
            .find_map(|k| entry(&v, k, grip));
        if let Some(g) = found.and_then(|g| g.get("state")) {
            rotation = g
                .get("orientation")
                .and_then(|q| serde_json::from_value::<Vec4D>(q.clone()).ok())
                .and_then(rotation_of);
            if let Some(b) = g
                .get("buttons")
                .and_then(|b| serde_json::from_value::<Buttons>(b.clone()).ok())
            {
                buttons = u32::from(b.a) | (u32::from(b.b) << 1) | (u32::from(b.c) << 2);
            } else if g.get("button").and_then(Value::as_bool) == Some(true) {
                buttons = 1;
            }
        }
    }
    Ok(Some(Reading {
        position,
        velocity,
        rotation,
        buttons,
    }))
}

/// Row-major rotation matrix of a (not necessarily unit) quaternion; `None`
/// when it is not finite or has no length.
fn rotation_of(q: Vec4D) -> Option<[f64; 9]> {
    let q = Quaternion::new(
        f64::from(q.w),
        f64::from(q.x),
        f64::from(q.y),
        f64::from(q.z),
    );
    if !(q.norm().is_finite() && q.norm() > 1e-6) {
        return None;
    }
    let m = UnitQuaternion::from_quaternion(q).to_rotation_matrix();
    let m = m.matrix();
    Some([
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 0)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 0)],
        m[(2, 1)],
        m[(2, 2)],
    ])
}

/// The command frame of one Inverse3, reused across round trips.
pub struct CommandFrame {
    msg: ServiceMsg,
}

impl CommandFrame {
    /// The first frame registers the profile; `force_render_full_state`
    /// (the crate's default) is dropped: the inventory already came.
    pub fn new(device: &str) -> Self {
        CommandFrame {
            msg: ServiceMsg {
                session: SessionMsg {
                    force_render_full_state: None,
                    configure: Some(SessionConfigure {
                        profile: Some(ProfileConfig {
                            name: PROFILE.to_string(),
                            required_version: None,
                        }),
                        ..SessionConfigure::default()
                    }),
                },
                inverse3: vec![Inverse3OutMsg {
                    device_id: device.to_string(),
                    commands: Some(Inverse3Commands {
                        set_cursor_force: Some(SetCursorForceCmd {
                            vector: Force::default(),
                            execute: true,
                        }),
                        ..Inverse3Commands::default()
                    }),
                    configure: None,
                }],
                verse_grip: Vec::new(),
                wireless_verse_grip: Vec::new(),
            },
        }
    }

    /// The JSON text commanding `force` (N, device frame; the wire carries
    /// f32). After the first call the session part is empty.
    pub fn encode(&mut self, force: [f64; 3]) -> String {
        if let Some(cmd) = self.msg.inverse3[0]
            .commands
            .as_mut()
            .and_then(|c| c.set_cursor_force.as_mut())
        {
            cmd.vector = Vec3D {
                x: force[0] as f32,
                y: force[1] as f32,
                z: force[2] as f32,
            };
        }
        // Serialising plain structs of numbers and strings cannot fail.
        let text = serde_json::to_string(&self.msg).unwrap_or_default();
        self.msg.session.configure = None;
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_frame_carries_the_force_and_registers_once() {
        let mut f = CommandFrame::new("049D");
        let first: Value = serde_json::from_str(&f.encode([1.0, -2.0, 0.5])).unwrap();
        assert_eq!(first["session"]["configure"]["profile"]["name"], PROFILE);
        let cmd = &first["inverse3"][0]["commands"]["set_cursor_force"];
        assert_eq!(first["inverse3"][0]["device_id"], "049D");
        assert_eq!(
            (cmd["vector"]["x"].as_f64(), cmd["vector"]["y"].as_f64()),
            (Some(1.0), Some(-2.0))
        );
        let second: Value = serde_json::from_str(&f.encode([0.0; 3])).unwrap();
        assert!(second["session"].get("configure").is_none(), "{second}");
        // The command parses as the crate's own command type.
        let third: Value = serde_json::from_str(&f.encode([0.25, 0.0, 0.0])).unwrap();
        let c = third
            .pointer("/inverse3/0/commands/set_cursor_force")
            .unwrap();
        let back: SetCursorForceCmd = serde_json::from_value(c.clone()).unwrap();
        assert_eq!((back.vector.x, back.execute), (0.25, true));
    }

    #[test]
    fn reading_takes_position_orientation_and_buttons() {
        // A quarter turn about z: (w, z) = (cos 45°, sin 45°).
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let text = format!(
            r#"{{"inverse3":[{{"device_id":"A","state":{{"cursor_position":{{"x":0.01,"y":-0.12,"z":0.15}},
            "cursor_velocity":{{"x":0.5,"y":0,"z":0}}}}}}],
            "wireless_verse_grip":[{{"device_id":"G","state":{{"orientation":{{"w":{h},"x":0,"y":0,"z":{h}}},
            "buttons":{{"a":false,"b":true,"c":false}}}}}}]}}"#
        );
        let r = reading(&text, "A", Some("G")).unwrap().unwrap();
        // f32 on the wire: 0.01 m to within f32's 6e-8 relative precision.
        assert!((r.position[0] - 0.01).abs() < 1e-9 && r.position[1] == -0.12f32 as f64);
        assert_eq!(r.velocity, [0.5, 0.0, 0.0]);
        assert_eq!(r.buttons, 0b10);
        // R_z(90°) maps x to y: row-major [0 -1 0; 1 0 0; 0 0 1] to f32 precision.
        let m = r.rotation.unwrap();
        let expected = [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        assert!(
            m.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6),
            "{m:?}"
        );
        assert_eq!(reading(&text, "B", None).unwrap(), None);
        assert!(reading("{", "A", None).is_err());
    }
}
