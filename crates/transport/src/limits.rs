//! What a message may carry: every `f64` finite and within a physical
//! bound, every code one of its defined values. The same check runs before
//! a message is sent ([`crate::Link::send`], [`crate::encode`]) and after a
//! datagram is received ([`crate::decode_any`], [`crate::open`]), so a
//! value that could not come from the simulator (a probe at 1e300 m, a
//! sample with `D = ∞`) neither leaves nor enters a process.
//!
//! The bounds are "absurd beyond", not clinical ranges: each is orders of
//! magnitude past anything the simulator produces, with the reason beside
//! it, so that no legitimate value is ever refused.

use crate::message::{contact_state, Message};

/// Largest |time| in any time field, s: 10⁹ s ≈ 32 years of uptime (the
/// clocks start at 0 when a process starts).
pub const MAX_TIME: f64 = 1e9;
/// Largest |coordinate| of a probe position, m: the thigh is ~0.1 m and the
/// device workspace < 1 m.
pub const MAX_POSITION: f64 = 10.0;
/// Largest |component| of an orientation quaternion: 1 for a unit
/// quaternion; 2 leaves room for one that is not normalized (the receiver
/// normalizes it).
pub const MAX_QUATERNION: f64 = 2.0;
/// Largest |D|, m (as [`MAX_POSITION`]); see also
/// [`crate::NO_SURFACE_DISTANCE`].
pub const MAX_DISTANCE: f64 = 10.0;
/// Largest |component| of `∇D` (a unit vector; 2 leaves room for rounding
/// and an unnormalized gradient, which the model manager checks itself).
pub const MAX_GRADIENT: f64 = 2.0;
/// Largest |k|, N/m: soft tissue is ~10³ N/m, a penalty contact 10⁴–10⁵.
pub const MAX_STIFFNESS: f64 = 1e9;
/// Largest |force component|, N: the device's maximum is ~10 N.
pub const MAX_FORCE: f64 = 1e6;
/// Largest physics rate, Hz (the simulator runs at ~10² Hz).
pub const MAX_RATE: f64 = 1e9;

/// A value a message may not carry.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("field `{field}` = {value:e} is outside [{min:e}, {max:e}] or not finite")]
pub struct ValueError {
    /// Name of the field.
    pub field: &'static str,
    /// The offending value (a code is shown as a number).
    pub value: f64,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
}

fn within(field: &'static str, values: &[f64], min: f64, max: f64) -> Result<(), ValueError> {
    for &value in values {
        // NaN fails both comparisons' negation: `!(NaN >= min)`.
        if !(value >= min && value <= max) {
            return Err(ValueError {
                field,
                value,
                min,
                max,
            });
        }
    }
    Ok(())
}

fn sym(field: &'static str, values: &[f64], bound: f64) -> Result<(), ValueError> {
    within(field, values, -bound, bound)
}

/// Checks every field of `msg` against the bounds of this module.
pub fn check(msg: &Message) -> Result<(), ValueError> {
    sym("t_send", &[msg.header().t_send], MAX_TIME)?;
    match msg {
        Message::Probe(m) => {
            sym("t_device", &[m.t_device], MAX_TIME)?;
            sym("position", &m.position, MAX_POSITION)?;
            sym("orientation", &m.orientation, MAX_QUATERNION)
        }
        Message::Sample(m) => {
            sym("t_sample", &[m.t_sample], MAX_TIME)?;
            sym("p", &m.p, MAX_POSITION)?;
            sym("distance", &[m.distance], MAX_DISTANCE)?;
            sym("gradient", &m.gradient, MAX_GRADIENT)?;
            sym("stiffness", &[m.stiffness], MAX_STIFFNESS)?;
            sym("force", &m.force, MAX_FORCE)?;
            within("physics_rate", &[m.physics_rate], 0.0, MAX_RATE)?;
            within(
                "contact",
                &[f64::from(m.contact)],
                0.0,
                f64::from(contact_state::NO_SURFACE),
            )
        }
        Message::Welcome(m) => within("physics_rate", &[m.physics_rate], 0.0, MAX_RATE),
        Message::Hello(_) | Message::Bye(_) => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::message::{ProbeMsg, SampleMsg};

    #[test]
    fn absurd_and_non_finite_values_are_named() {
        let ok = ProbeMsg::new(1.0, [0.0, 0.08, 0.0], [1.0, 0.0, 0.0, 0.0], 0);
        assert!(check(&Message::Probe(ok)).is_ok());
        for (bad, field) in [
            (
                ProbeMsg {
                    position: [0.0, 1e300, 0.0],
                    ..ok
                },
                "position",
            ),
            (
                ProbeMsg {
                    orientation: [f64::NAN, 0.0, 0.0, 0.0],
                    ..ok
                },
                "orientation",
            ),
            (
                ProbeMsg {
                    t_device: f64::NEG_INFINITY,
                    ..ok
                },
                "t_device",
            ),
        ] {
            let e = check(&Message::Probe(bad)).unwrap_err();
            assert_eq!(e.field, field);
            assert!(e.to_string().contains(field), "{e}");
        }
        let s = SampleMsg {
            distance: f64::INFINITY,
            ..SampleMsg::default()
        };
        assert_eq!(check(&Message::Sample(s)).unwrap_err().field, "distance");
        let s = SampleMsg {
            contact: 3,
            ..SampleMsg::default()
        };
        assert_eq!(check(&Message::Sample(s)).unwrap_err().field, "contact");
        // The bounds themselves are allowed.
        let edge = ProbeMsg {
            position: [MAX_POSITION, -MAX_POSITION, 0.0],
            ..ok
        };
        assert!(check(&Message::Probe(edge)).is_ok());
    }
}
