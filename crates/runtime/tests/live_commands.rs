//! One validation per command (issue 16): the live system refuses a
//! command out of range with exactly the message of `LiveCommand::validate`
//! (the check the page protocol runs too), and the limits it reports are the
//! scenario's.

use echothigh_runtime::live::{CommandError, LiveCommand, LiveControl};
use echothigh_runtime::live_system::LiveSystem;
use echothigh_runtime::scenario::Scenario;

#[test]
fn the_live_system_refuses_with_the_shared_validation() {
    let scenario = Scenario::default();
    let system = LiveSystem::start(scenario.clone()).unwrap();
    let limits = system.limits();
    assert_eq!(limits.half_length, 0.5 * scenario.thigh.length);
    assert_eq!(limits.max_physics_rate, scenario.coupling.haptic_rate);
    let half = limits.half_length;
    let bad = [
        LiveCommand::Probe {
            theta: -3.2,
            z: 0.0,
            depth: 0.01,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: half + 1e-3,
            depth: 0.01,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: f64::NAN,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: 0.045,
            tilt: 0.0,
        },
        LiveCommand::Probe {
            theta: 0.0,
            z: 0.0,
            depth: 0.01,
            tilt: 0.7,
        },
        LiveCommand::SetPhysicsRate {
            hz: limits.max_physics_rate + 1.0,
        },
        LiveCommand::SetLatency { seconds: -1e-3 },
    ];
    for cmd in bad {
        let expected = cmd.validate(&limits).unwrap_err();
        let CommandError::OutOfRange { field, .. } = &expected;
        let got = system.command(cmd.clone()).unwrap_err();
        assert_eq!(got, expected.to_string(), "{cmd:?}");
        assert!(got.contains(field), "{got}");
    }
    // At the edge of every range: accepted.
    system
        .command(LiveCommand::Probe {
            theta: std::f64::consts::PI,
            z: half,
            depth: 0.0,
            tilt: -0.6,
        })
        .unwrap();
    system.shutdown().unwrap();
}
