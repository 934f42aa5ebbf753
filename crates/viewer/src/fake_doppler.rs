//! The test double's flow (issue 17): it records the Doppler commands,
//! reports their settings, colours a known disc of the image in colour and
//! power modes and makes four spectral lines an image frame in spectral
//! mode, each line a known ramp, so the server's tests can check what
//! reaches the page.

use echothigh_runtime::live_doppler::{
    DopplerCommand, DopplerMode, DopplerStatus, Gate, SpectralLines, SPECTRAL_RING, SPECTRAL_ROWS,
};
use std::sync::Mutex;

/// Lines the double makes per image frame in spectral mode.
pub const LINES_PER_FRAME: u64 = 4;

/// The overlay code of the double's coloured disc (flow towards the probe
/// at 56 % of Nyquist: `128 + 72`).
pub const DISC_CODE: u8 = 200;

#[derive(Debug, Default)]
struct State {
    status: DopplerStatus,
    commands: Vec<DopplerCommand>,
    lines: u64,
}

/// The double's flow (see the module docs).
#[derive(Debug, Default)]
pub struct FakeDoppler(Mutex<State>);

impl FakeDoppler {
    /// The commands received, in order.
    pub fn commands(&self) -> Vec<DopplerCommand> {
        self.0.lock().unwrap().commands.clone()
    }

    /// Applies a command (validated as the runtime does).
    pub fn command(&self, cmd: DopplerCommand) -> Result<(), String> {
        cmd.validate().map_err(|e| e.to_string())?;
        let mut s = self.0.lock().unwrap();
        s.commands.push(cmd.clone());
        match cmd {
            DopplerCommand::DopplerMode { mode } => s.status.mode = mode,
            DopplerCommand::Valsalva { hold } => s.status.valsalva = hold,
            DopplerCommand::DopplerGate { x, y, angle_deg } => {
                s.status.gate = Gate { x, y, angle_deg }
            }
            DopplerCommand::Squeeze => {}
        }
        Ok(())
    }

    /// The status, available, with the runtime's default scales.
    pub fn status(&self) -> DopplerStatus {
        DopplerStatus {
            available: true,
            prf: 4000.0,
            line_rate: 200.0,
            ..self.0.lock().unwrap().status
        }
    }

    /// A new image frame of `w × h`: the overlay of the disc in colour or
    /// power mode (else empty), new lines in spectral mode.
    pub fn frame(&self, w: usize, h: usize, overlay: &mut Vec<u8>) {
        let mut s = self.0.lock().unwrap();
        overlay.clear();
        match s.status.mode {
            DopplerMode::Color | DopplerMode::Power => {
                let (cx, cy, r) = (w as f64 / 2.0, h as f64 / 2.0, h as f64 / 4.0);
                overlay.extend((0..w * h).map(|k| {
                    let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
                    if (x - cx).hypot(y - cy) < r {
                        DISC_CODE
                    } else {
                        0
                    }
                }));
            }
            DopplerMode::Spectral => s.lines += LINES_PER_FRAME,
            DopplerMode::Bmode => {}
        }
    }

    /// Line `n`'s magnitude at row `r`: `(n + r) mod 256`.
    pub fn magnitude(n: u64, r: usize) -> u8 {
        ((n + r as u64) % 256) as u8
    }

    /// How many spectral lines the double has made.
    pub fn lines_made(&self) -> u64 {
        self.0.lock().unwrap().lines
    }

    /// The lines from `from` on (the last [`SPECTRAL_RING`]).
    pub fn lines(&self, from: u64, out: &mut SpectralLines) {
        let next = self.0.lock().unwrap().lines;
        let first = from.max(next.saturating_sub(SPECTRAL_RING as u64));
        out.first = first;
        out.count = next.saturating_sub(first) as usize;
        out.interval = 0.005;
        out.time = first as f64 * 0.005;
        out.data.clear();
        for n in first..next {
            out.data
                .extend((0..SPECTRAL_ROWS).map(|r| Self::magnitude(n, r)));
        }
    }
}
