//! Replay of recorded trajectories: interpolation and CSV errors.

use echothigh_device::{DeviceConfig, HapticDevice, ReplayDevice, ReplayError, Vec3};

fn replay(text: &str) -> Result<ReplayDevice, ReplayError> {
    ReplayDevice::from_reader(text.as_bytes(), DeviceConfig::default())
}

#[test]
fn interpolates_linearly_and_holds_the_ends() {
    let mut d = replay("t,x,y,z\n1.0,0,0.1,0\n1.5,0.01,0.09,0\n2.5,0.01,0.09,0.02\n").unwrap();
    assert_eq!(d.start_time(), 1.0);
    assert_eq!(d.position(), Vec3::new(0.0, 0.1, 0.0));
    d.advance(0.25);
    assert!((d.position() - Vec3::new(0.005, 0.095, 0.0)).norm() < 1e-15);
    assert!((d.velocity() - Vec3::new(0.02, -0.02, 0.0)).norm() < 1e-12);
    // Step in 1 ms ticks across the sample at 1.5 s: position continuous.
    let mut prev = d.position();
    for _ in 0..500 {
        d.advance(1e-3);
        assert!((d.position() - prev).norm() <= 0.02 * 1e-3 * 2.0f64.sqrt() + 1e-12);
        prev = d.position();
    }
    assert!((d.time() - 1.75).abs() < 1e-9);
    assert!((d.position() - Vec3::new(0.01, 0.09, 0.005)).norm() < 1e-12);
    assert!((d.velocity() - Vec3::new(0.0, 0.0, 0.02)).norm() < 1e-12);
    d.advance(10.0);
    assert!(d.finished());
    assert_eq!(d.position(), Vec3::new(0.01, 0.09, 0.02));
    assert_eq!(d.velocity(), Vec3::zeros());
    d.seek(1.25);
    assert!((d.position() - Vec3::new(0.005, 0.095, 0.0)).norm() < 1e-15);
}

#[test]
fn column_order_and_extra_columns_are_free() {
    let d = replay("phase, z ,y,x,t\npress,3,2,1,0\n").unwrap();
    assert_eq!(d.position(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(d.len(), 1);
}

#[test]
fn forces_are_limited_and_recorded_not_applied() {
    let mut d = replay("t,x,y,z\n0,0,0,0\n1,1,0,0\n").unwrap();
    d.set_force(Vec3::new(0.0, 100.0, 0.0));
    assert_eq!(d.force(), Vec3::new(0.0, 6.0, 0.0));
    d.set_force(Vec3::new(f64::NAN, 0.0, 0.0));
    assert_eq!(d.force(), Vec3::zeros());
    assert_eq!(d.faults().clamped, 1);
    assert_eq!(d.faults().non_finite, 1);
    d.advance(0.5);
    assert_eq!(d.position(), Vec3::new(0.5, 0.0, 0.0));
}

#[test]
fn csv_errors_name_the_line() {
    let missing = replay("t,x,z\n0,0,0\n").unwrap_err();
    assert!(
        matches!(missing, ReplayError::MissingColumn { column: "y", .. }),
        "{missing}"
    );
    assert!(missing.to_string().contains("`y`"));

    let e = replay("t,x,y,z\n0,0,0,0\n0.1,0,abc,0\n").unwrap_err();
    assert_eq!(
        e,
        ReplayError::NotNumeric {
            line: 3,
            column: "y",
            value: "abc".into()
        }
    );
    assert!(e.to_string().starts_with("line 3:"), "{e}");

    let e = replay("t,x,y,z\n0,0,0,0\n0.1,0,0,0\n0.1,0,0,0\n").unwrap_err();
    assert!(
        matches!(e, ReplayError::NonIncreasingTime { line: 4, .. }),
        "{e}"
    );
    let e = replay("t,x,y,z\n0,0,0,0\n-1,0,0,0\n").unwrap_err();
    assert!(
        matches!(e, ReplayError::NonIncreasingTime { line: 3, .. }),
        "{e}"
    );

    let e = replay("t,x,y,z\n0,0,0,0\n1,0,NaN,0\n").unwrap_err();
    assert!(
        matches!(
            e,
            ReplayError::NotFinite {
                line: 3,
                column: "y",
                ..
            }
        ),
        "{e}"
    );

    let e = replay("t,x,y,z\n0,0,0,0\n1,0,0\n").unwrap_err();
    assert!(matches!(e, ReplayError::Csv { line: 3, .. }), "{e}");

    assert_eq!(replay("t,x,y,z\n").unwrap_err(), ReplayError::Empty);
    assert!(matches!(
        ReplayDevice::from_path("/nonexistent/trajectory.csv", DeviceConfig::default()),
        Err(ReplayError::Io { .. })
    ));
}

#[test]
fn sample_constructor_checks_its_input() {
    let ok = ReplayDevice::from_samples(
        vec![0.0, 1.0],
        vec![Vec3::zeros(); 2],
        DeviceConfig::default(),
    );
    assert!(ok.is_ok());
    for (t, p) in [
        (vec![0.0, 1.0], vec![Vec3::zeros()]),
        (vec![1.0, 1.0], vec![Vec3::zeros(); 2]),
        (vec![0.0, f64::NAN], vec![Vec3::zeros(); 2]),
    ] {
        assert!(matches!(
            ReplayDevice::from_samples(t, p, DeviceConfig::default()),
            Err(ReplayError::Samples(_))
        ));
    }
    let bad_limits = DeviceConfig {
        max_force: -1.0,
        ..DeviceConfig::default()
    };
    let e = ReplayDevice::from_samples(vec![0.0], vec![Vec3::zeros()], bad_limits).unwrap_err();
    assert!(e.to_string().contains("device.max_force"), "{e}");
}

/// Line numbers count comment and blank lines (issue 16): the bad field
/// stands on line 6, after a comment (line 1) and a blank line (line 4).
#[test]
fn error_after_a_comment_and_a_blank_line_says_line_6() {
    let text = "# recorded on rig 2\nt,x,y,z\n0,0,0,0\n\n0.1,0,0,0\n0.2,0,abc,0\n";
    let e = replay(text).unwrap_err();
    assert_eq!(
        e,
        ReplayError::NotNumeric {
            line: 6,
            column: "y",
            value: "abc".into()
        }
    );
    assert!(e.to_string().starts_with("line 6:"), "{e}");
    let e = replay("# c\n\nt,x,z\n0,0,0\n").unwrap_err();
    assert!(
        matches!(
            e,
            ReplayError::MissingColumn {
                line: 3,
                column: "y",
                ..
            }
        ),
        "{e}"
    );
}
