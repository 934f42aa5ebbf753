//! Replay of a recorded probe trajectory as a [`HapticDevice`].
//!
//! The CSV has a header line naming at least the columns `t,x,y,z` (time in
//! s, position in m, thigh frame; other columns are ignored, order and ASCII
//! case are free; `#` comment lines and blank lines are skipped)
//! and one sample per line with strictly increasing time. Between samples
//! the position is interpolated linearly; before the first sample and after
//! the last it holds the end position (velocity zero). Replay time starts
//! at the first sample's time. Forces written are limited like a real
//! device's and recorded ([`HapticDevice::force`]) but move nothing.

use crate::config::DeviceConfig;
use crate::device::{limit_force, DeviceFaults, HapticDevice};
use crate::error::ReplayError;
use crate::Vec3;
use echothigh_table::Table;
use std::io::Read;
use std::path::Path;

/// A device that replays a recorded trajectory (see the module docs).
#[derive(Debug, Clone)]
pub struct ReplayDevice {
    times: Vec<f64>,
    points: Vec<Vec3>,
    limits: DeviceConfig,
    time: f64,
    segment: usize,
    force: Vec3,
    faults: DeviceFaults,
}

const COLUMNS: [&str; 4] = ["t", "x", "y", "z"];

/// Largest trajectory file read (bytes): an hour at 1 kHz of `t,x,y,z`
/// rows of ~60 bytes is ~216 MB.
pub const MAX_TRAJECTORY_BYTES: u64 = 256 << 20;

impl ReplayDevice {
    /// A replay of `times` (s, strictly increasing, finite) and `points`
    /// (m). `limits` gives the reported force limit, stiffness and rate
    /// (validated with prefix `device`).
    pub fn from_samples(
        times: Vec<f64>,
        points: Vec<Vec3>,
        limits: DeviceConfig,
    ) -> Result<Self, ReplayError> {
        limits.validate("device")?;
        if times.is_empty() {
            return Err(ReplayError::Empty);
        }
        if times.len() != points.len() {
            return Err(ReplayError::Samples("times and points differ in length"));
        }
        if times.iter().any(|t| !t.is_finite())
            || points.iter().any(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(ReplayError::Samples("non-finite time or position"));
        }
        if times.windows(2).any(|w| w[1] <= w[0]) {
            return Err(ReplayError::Samples("time does not strictly increase"));
        }
        Ok(ReplayDevice {
            time: times[0],
            times,
            points,
            limits,
            segment: 0,
            force: Vec3::zeros(),
            faults: DeviceFaults::default(),
        })
    }

    /// Reads a `t,x,y,z` CSV trajectory (see the module docs) of at most
    /// [`MAX_TRAJECTORY_BYTES`]. Errors carry the 1-based line number,
    /// counting comment and blank lines (the project's one reader,
    /// [`echothigh_table`]).
    pub fn from_reader<R: Read>(reader: R, limits: DeviceConfig) -> Result<Self, ReplayError> {
        let table = Table::read(reader, MAX_TRAJECTORY_BYTES)?;
        let mut index = [0usize; 4];
        for (slot, name) in index.iter_mut().zip(COLUMNS) {
            *slot = table.column(name)?;
        }
        let mut times = Vec::with_capacity(table.rows().len());
        let mut points = Vec::with_capacity(table.rows().len());
        for row in table.rows() {
            let line = row.line;
            let mut values = [0.0; 4];
            for ((value, &col), name) in values.iter_mut().zip(&index).zip(COLUMNS) {
                *value = row.number(col, name)?;
                if !value.is_finite() {
                    return Err(ReplayError::NotFinite {
                        line,
                        column: name,
                        value: *value,
                    });
                }
            }
            if let Some(&previous) = times.last() {
                if values[0] <= previous {
                    return Err(ReplayError::NonIncreasingTime {
                        line,
                        time: values[0],
                        previous,
                    });
                }
            }
            times.push(values[0]);
            points.push(Vec3::new(values[1], values[2], values[3]));
        }
        Self::from_samples(times, points, limits)
    }

    /// Reads a `t,x,y,z` CSV trajectory from a file.
    pub fn from_path(path: impl AsRef<Path>, limits: DeviceConfig) -> Result<Self, ReplayError> {
        let path = path.as_ref();
        let file = std::fs::File::open(path).map_err(|e| ReplayError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::from_reader(std::io::BufReader::new(file), limits)
    }

    /// Current replay time (s, on the recording's clock).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Time of the first sample (s).
    pub fn start_time(&self) -> f64 {
        self.times[0]
    }

    /// Time of the last sample (s).
    pub fn end_time(&self) -> f64 {
        self.times[self.times.len() - 1]
    }

    /// Whether the replay has reached its last sample.
    pub fn finished(&self) -> bool {
        self.time >= self.end_time()
    }

    /// Number of samples in the recording.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Always false: a replay holds at least one sample.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Jumps to recording time `t` (s; clamped to the recording's span).
    pub fn seek(&mut self, t: f64) {
        if t.is_finite() {
            self.time = t.clamp(self.start_time(), self.end_time());
            self.segment = 0;
            self.find_segment();
        }
    }

    /// Moves `segment` so that `times[segment] ≤ time < times[segment + 1]`
    /// (or to the last sample); forward only, amortized O(1) per tick.
    fn find_segment(&mut self) {
        while self.segment + 1 < self.times.len() && self.times[self.segment + 1] <= self.time {
            self.segment += 1;
        }
    }
}

impl HapticDevice for ReplayDevice {
    fn position(&self) -> Vec3 {
        let i = self.segment;
        if i + 1 >= self.times.len() || self.time <= self.times[0] {
            return self.points[i];
        }
        let s = (self.time - self.times[i]) / (self.times[i + 1] - self.times[i]);
        self.points[i] + (self.points[i + 1] - self.points[i]) * s
    }

    fn velocity(&self) -> Vec3 {
        let i = self.segment;
        if i + 1 >= self.times.len() || self.time < self.times[0] {
            return Vec3::zeros();
        }
        (self.points[i + 1] - self.points[i]) / (self.times[i + 1] - self.times[i])
    }

    fn set_force(&mut self, force: Vec3) {
        self.force = limit_force(force, self.limits.max_force, &mut self.faults);
    }

    fn force(&self) -> Vec3 {
        self.force
    }

    fn max_force(&self) -> f64 {
        self.limits.max_force
    }

    fn max_stiffness(&self) -> f64 {
        self.limits.max_stiffness
    }

    fn sampling_rate(&self) -> f64 {
        self.limits.sampling_rate
    }

    fn advance(&mut self, dt: f64) {
        if dt.is_finite() && dt > 0.0 {
            self.time = (self.time + dt).min(self.end_time());
            self.find_segment();
        }
    }

    fn faults(&self) -> DeviceFaults {
        self.faults
    }
}
