//! Interactive landmark calibration (`echothigh devices calibrate`): the
//! trainee touches named landmarks of the leg with the probe, pressing the
//! clutch button on each and holding still; the device-frame points and the
//! landmarks' leg-frame positions give the device → leg transform through
//! [`fit_landmarks`] (Kabsch–Umeyama).
//!
//! The capture is not real-time work (the force is zero throughout) but it
//! keeps exchanging with the servo thread at 1 kHz, as the haptic tick
//! would, so that the watchdog never trips and the SDK sees a live client.

use crate::calibration::{fit_landmarks, CalibrationError, LandmarkFit};
use crate::hardware::HardwareDevice;
use crate::Vec3;
use echothigh_device::HapticDevice;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A named point of the leg the trainee touches (leg frame, m).
#[derive(Debug, Clone, PartialEq)]
pub struct Landmark {
    /// What to touch, in the trainee's words.
    pub name: String,
    /// Where it is in the leg frame (m).
    pub leg: Vec3,
}

/// How a landmark is captured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureConfig {
    /// Time the probe must be held still with the button down (s); the
    /// captured point is the mean over it.
    pub hold: f64,
    /// Largest distance from that mean during the hold (m): a hand that
    /// moved more is asked again.
    pub max_motion: f64,
    /// Time to wait for each landmark before giving up (s).
    pub timeout: f64,
    /// Largest RMS residual of the fit accepted (m): more means a landmark
    /// was touched at the wrong place.
    pub max_rms: f64,
}

impl Default for CaptureConfig {
    /// 0.3 s held within 2 mm (a still hand's tremor is ~0.1–0.5 mm), 120 s
    /// per landmark, a fit within 5 mm RMS (the landmarks' own placement on
    /// skin by palpation is uncertain by a few mm).
    fn default() -> Self {
        CaptureConfig {
            hold: 0.3,
            max_motion: 0.002,
            timeout: 120.0,
            max_rms: 0.005,
        }
    }
}

/// What the capture tells the person calibrating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CaptureEvent<'a> {
    /// Touch this landmark (`index` of `total`, from 1) and press the button.
    Touch {
        /// The landmark.
        landmark: &'a Landmark,
        /// Its number, from 1.
        index: usize,
        /// How many there are.
        total: usize,
    },
    /// The probe moved more than allowed while the button was down: again.
    Moved {
        /// The landmark.
        landmark: &'a Landmark,
        /// How far it moved from its mean (m).
        motion: f64,
    },
    /// Captured at this device-frame point (m).
    Captured {
        /// The landmark.
        landmark: &'a Landmark,
        /// The device-frame point (m).
        point: Vec3,
    },
}

/// Why a calibration did not finish.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CaptureError {
    /// Fewer than three landmarks were given.
    #[error("a calibration needs at least 3 landmarks, got {0}")]
    TooFewLandmarks(usize),
    /// No capture within the timeout.
    #[error("no touch of \"{landmark}\" within {timeout} s (press and hold the clutch button with the probe on it)")]
    Timeout {
        /// The landmark waited for.
        landmark: String,
        /// The timeout (s).
        timeout: f64,
    },
    /// Stopped from outside (Ctrl-C).
    #[error("calibration interrupted before \"{0}\"")]
    Interrupted(String),
    /// The device stopped answering.
    #[error("the device stopped (SDK error {0:#x}) during the calibration")]
    DeviceFault(u32),
    /// The fit failed (collinear landmarks, a non-finite point).
    #[error(transparent)]
    Fit(#[from] CalibrationError),
    /// The fit is poor: a landmark was touched at the wrong place.
    #[error("the landmarks do not fit a rigid placement: RMS residual {rms_mm:.1} mm (at most {max_mm:.1} mm), worst \"{worst}\" off by {worst_mm:.1} mm: touch them again")]
    PoorFit {
        /// RMS residual (mm).
        rms_mm: f64,
        /// The bound (mm).
        max_mm: f64,
        /// The landmark farthest from its mapped touch.
        worst: String,
        /// Its distance (mm).
        worst_mm: f64,
    },
}

/// The raw side of a device the capture needs: its device-frame position
/// (m), whether the capture button is held, its fault, and the exchange
/// with its servo thread (one 1 ms tick at zero force).
pub trait Touchable {
    /// Device-frame position (m).
    fn device_point(&self) -> Vec3;
    /// True while the capture (clutch) button is held.
    fn button(&self) -> bool;
    /// The SDK error that stopped the device, if any.
    fn device_fault(&self) -> Option<u32>;
    /// One tick at zero force.
    fn tick_zero(&mut self);
}

impl Touchable for HardwareDevice {
    fn device_point(&self) -> Vec3 {
        self.device_position()
    }
    fn button(&self) -> bool {
        self.clutched()
    }
    fn device_fault(&self) -> Option<u32> {
        self.fault()
    }
    fn tick_zero(&mut self) {
        self.set_force(Vec3::zeros());
        self.advance(1e-3);
    }
}

/// Paced 1 kHz ticks at zero force (not real-time: a sleep per tick).
struct Pacer {
    next: Instant,
}

impl Pacer {
    fn tick(&mut self, device: &mut impl Touchable) -> Result<(), CaptureError> {
        device.tick_zero();
        if let Some(code) = device.device_fault() {
            return Err(CaptureError::DeviceFault(code));
        }
        self.next += Duration::from_millis(1);
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
        } else {
            self.next = now;
        }
        Ok(())
    }
}

/// Captures each landmark in turn (see the module docs) and fits the
/// transform; `on_event` tells the person what to do. `stop` interrupts.
/// Returns the device-frame points and the fit.
pub fn capture_landmarks(
    device: &mut impl Touchable,
    landmarks: &[Landmark],
    config: &CaptureConfig,
    stop: &AtomicBool,
    mut on_event: impl FnMut(CaptureEvent<'_>),
) -> Result<(Vec<Vec3>, LandmarkFit), CaptureError> {
    if landmarks.len() < 3 {
        return Err(CaptureError::TooFewLandmarks(landmarks.len()));
    }
    let mut pacer = Pacer {
        next: Instant::now(),
    };
    let hold_ticks = ((config.hold * 1e3).ceil() as usize).max(1);
    let mut points = Vec::with_capacity(landmarks.len());
    for (i, lm) in landmarks.iter().enumerate() {
        on_event(CaptureEvent::Touch {
            landmark: lm,
            index: i + 1,
            total: landmarks.len(),
        });
        let start = Instant::now();
        let point = loop {
            // Wait for the button to be up, then down (a fresh press).
            for want in [false, true] {
                while device.button() != want {
                    if stop.load(Ordering::Relaxed) {
                        return Err(CaptureError::Interrupted(lm.name.clone()));
                    }
                    if start.elapsed().as_secs_f64() > config.timeout {
                        return Err(CaptureError::Timeout {
                            landmark: lm.name.clone(),
                            timeout: config.timeout,
                        });
                    }
                    pacer.tick(device)?;
                }
            }
            let mut samples = Vec::with_capacity(hold_ticks);
            while samples.len() < hold_ticks && device.button() {
                samples.push(device.device_point());
                pacer.tick(device)?;
            }
            if samples.len() < hold_ticks {
                continue; // released too early: press again
            }
            let mean = samples.iter().sum::<Vec3>() / samples.len() as f64;
            let motion = samples
                .iter()
                .map(|p| (p - mean).norm())
                .fold(0.0, f64::max);
            if motion > config.max_motion {
                on_event(CaptureEvent::Moved {
                    landmark: lm,
                    motion,
                });
                continue;
            }
            break mean;
        };
        on_event(CaptureEvent::Captured {
            landmark: lm,
            point,
        });
        points.push(point);
    }
    let leg: Vec<Vec3> = landmarks.iter().map(|l| l.leg).collect();
    let fit = fit_landmarks(&points, &leg)?;
    if fit.rms_residual > config.max_rms {
        let iso = fit.transform.isometry();
        let (worst, d) = landmarks
            .iter()
            .zip(&points)
            .map(|(l, p)| (l, (iso * nalgebra::Point3::from(*p)).coords - l.leg))
            .map(|(l, r)| (l, r.norm()))
            .fold((&landmarks[0], 0.0), |a, b| if b.1 > a.1 { b } else { a });
        return Err(CaptureError::PoorFit {
            rms_mm: fit.rms_residual * 1e3,
            max_mm: config.max_rms * 1e3,
            worst: worst.name.clone(),
            worst_mm: d * 1e3,
        });
    }
    Ok((points, fit))
}
