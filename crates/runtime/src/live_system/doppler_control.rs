//! The page's Doppler commands applied to the shared flow state (issue
//! 17): the imaging mode, a calf squeeze and a held Valsalva stamped with
//! the physics' clock, the PW gate.

use super::doppler::{mode_code, DopplerShared};
use crate::live_doppler::{DopplerCommand, DopplerMode, DopplerStatus};
use echothigh_cases::Case;
use std::sync::atomic::Ordering;

impl DopplerShared {
    /// Takes the loaded case's iliac obstruction flag (`None`: no case,
    /// none), and lets the held manoeuvres go (a new leg starts at rest).
    pub fn set_case(&self, case: Option<&Case>) {
        self.proximal_obstruction.store(
            case.is_some_and(|c| c.file.doppler.proximal_obstruction),
            Ordering::Release,
        );
        if let Ok(mut c) = self.controls.lock() {
            c.maneuvers = Default::default();
        }
    }

    /// Applies a validated command at the physics' time `now` (s).
    pub fn command(&self, cmd: DopplerCommand, now: f64) -> Result<(), String> {
        let mut c = self
            .controls
            .lock()
            .map_err(|_| "the Doppler controls are poisoned".to_string())?;
        match cmd {
            DopplerCommand::DopplerMode { mode } => {
                self.mode.store(mode_code(mode), Ordering::Release);
                if let Ok(mut s) = self.status.lock() {
                    s.mode = mode;
                }
            }
            DopplerCommand::Squeeze => c.maneuvers.squeeze(now),
            DopplerCommand::Valsalva { hold: true } => {
                if !c.maneuvers.valsalva_held() {
                    c.maneuvers.begin_valsalva(now);
                }
            }
            DopplerCommand::Valsalva { hold: false } => {
                c.maneuvers.end_valsalva(now);
            }
            DopplerCommand::DopplerGate { x, y, angle_deg } => {
                c.gate = crate::live_doppler::Gate { x, y, angle_deg };
            }
        }
        if let Ok(mut s) = self.status.lock() {
            s.valsalva = c.maneuvers.valsalva_held();
            s.gate = c.gate;
        }
        Ok(())
    }

    /// The status the imaging thread last published, with the mode and
    /// controls as set now.
    pub fn status(&self) -> DopplerStatus {
        let mut s = self.status.lock().map(|s| *s).unwrap_or_default();
        s.mode = self.mode();
        if s.mode == DopplerMode::Bmode {
            s.gate_in_flow = false;
        }
        s
    }
}
