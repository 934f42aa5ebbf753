//! Recordings streamed to disk as they are made (issue 20: nothing lost).
//!
//! The real-time loops push their records into lock-free single-producer
//! rings ([`RecordSink`], the `rtrb` crate: no allocation, no lock, no
//! system call on push); a writer thread drains them into `haptic.csv` and
//! `physics.csv`, flushing to the kernel at least every
//! [`FLUSH_INTERVAL`], so that a `kill -9` loses at most the last second and
//! a SIGINT or SIGTERM (which only stop the loops) loses nothing. The output
//! directory is created, checked for free space and its files opened
//! *before* the run starts; a write error (a full disk) names its file and
//! stops the run at once through the run's stop signal.

use crate::trace::{write_physics_header, write_physics_row, write_tick_header, write_tick_row};
use crate::trace::{PhysicsRecord, TickRecord};
use anyhow::{bail, Context, Result};
use echothigh_table::RowWriter;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Longest time a record waits in memory before it reaches the kernel (s).
pub const FLUSH_INTERVAL: Duration = Duration::from_millis(250);

/// How often the writer thread drains the rings.
const DRAIN_PERIOD: Duration = Duration::from_millis(20);

/// Ring capacity (records): 16 s of ticks at 1 kHz, so that a writer held
/// up by the disk for seconds loses nothing.
const RING_CAPACITY: usize = 1 << 14;

/// Bytes of a CSV row, an upper bound used to check the free space before
/// the run (a `haptic.csv` row is ~200 bytes, a `physics.csv` row ~250).
const ROW_BYTES: u64 = 320;

/// Where a real-time loop puts its records: a buffer preallocated for the
/// whole run (the virtual clock, tests) or a lock-free ring drained by the
/// writer thread. `push` never allocates; a full buffer or ring drops the
/// record and counts it ([`RecordSink::dropped`]).
pub enum RecordSink<T> {
    /// Records kept in memory (capacity fixed at setup).
    Memory(Vec<T>),
    /// Records streamed to the writer thread.
    Ring(rtrb::Producer<T>, u64),
    /// Records not kept.
    Discard,
}

impl<T: Copy> RecordSink<T> {
    /// A memory sink with room for `capacity` records (allocates now, never after).
    pub fn memory(capacity: usize) -> Self {
        RecordSink::Memory(Vec::with_capacity(capacity))
    }

    /// Keeps `record` (real-time safe).
    pub fn push(&mut self, record: T) {
        match self {
            RecordSink::Memory(v) => {
                if v.len() < v.capacity() {
                    v.push(record);
                }
            }
            RecordSink::Ring(p, dropped) => {
                if p.push(record).is_err() {
                    *dropped += 1;
                }
            }
            RecordSink::Discard => {}
        }
    }

    /// Keeps `record`, waiting for room in a full ring: for producers that
    /// are not real-time (the virtual clock runs faster than a disk may
    /// write, and must lose nothing). Gives up, counting the record dropped,
    /// only when the writer has stopped (a write error, which has already
    /// stopped the run).
    pub fn push_wait(&mut self, record: T) {
        let RecordSink::Ring(p, dropped) = self else {
            return self.push(record);
        };
        let mut r = record;
        loop {
            match p.push(r) {
                Ok(()) => return,
                Err(rtrb::PushError::Full(back)) => {
                    if p.is_abandoned() {
                        *dropped += 1;
                        return;
                    }
                    r = back;
                    std::thread::sleep(Duration::from_millis(1));
                }
            }
        }
    }

    /// Records dropped because the ring was full (0 for memory sinks; a full
    /// memory sink stops at its capacity, sized for the run).
    pub fn dropped(&self) -> u64 {
        match self {
            RecordSink::Ring(_, d) => *d,
            _ => 0,
        }
    }

    /// The records kept in memory (empty for a ring).
    pub fn into_records(self) -> Vec<T> {
        match self {
            RecordSink::Memory(v) => v,
            _ => Vec::new(),
        }
    }
}

/// Which files a recording streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Streams {
    /// `haptic.csv` (the 1 kHz loop's ticks).
    pub ticks: bool,
    /// `physics.csv` (the physics steps).
    pub steps: bool,
}

impl Streams {
    /// Both files.
    pub const BOTH: Streams = Streams {
        ticks: true,
        steps: true,
    };
}

/// The CSV writer of a streamed file (the project's one writer).
type Csv = RowWriter<BufWriter<File>>;

/// Writes one record as a CSV row.
type RowFn<T> = Box<dyn FnMut(&mut Csv, &T) -> std::io::Result<()> + Send>;

/// One CSV file the writer streams to.
struct CsvStream<T> {
    path: PathBuf,
    out: Csv,
    ring: rtrb::Consumer<T>,
    row: RowFn<T>,
    kept: Vec<T>,
}

impl<T: Copy> CsvStream<T> {
    fn drain(&mut self) -> Result<()> {
        while let Ok(r) = self.ring.pop() {
            (self.row)(&mut self.out, &r)
                .with_context(|| format!("writing {}", self.path.display()))?;
            self.kept.push(r);
        }
        Ok(())
    }

    fn flush(&mut self) -> Result<()> {
        self.out
            .flush()
            .with_context(|| format!("writing {}", self.path.display()))
    }
}

/// What the writer thread hands back.
pub struct Recorded {
    /// Every tick written to `haptic.csv`.
    pub ticks: Vec<TickRecord>,
    /// Every step written to `physics.csv`.
    pub steps: Vec<PhysicsRecord>,
}

/// A run directory being written (see the module docs).
pub struct Recording {
    dir: PathBuf,
    stop_writer: Arc<AtomicBool>,
    writer: JoinHandle<Result<Recorded>>,
}

impl Recording {
    /// Creates `dir` (refusing a directory that already holds a run),
    /// checks that its disk has room for `expected_rows` rows, opens
    /// `haptic.csv` and `physics.csv` with their headers, and starts the
    /// writer thread. `run_stop` is set if a write fails, so that the run
    /// stops as soon as its data can no longer be kept. Returns the two
    /// sinks for the real-time loops.
    pub fn create(
        dir: &Path,
        mode: &str,
        streams: Streams,
        expected_rows: u64,
        run_stop: Arc<AtomicBool>,
    ) -> Result<(Self, RecordSink<TickRecord>, RecordSink<PhysicsRecord>)> {
        if dir.join("summary.json").exists() || dir.join("haptic.csv").exists() {
            bail!(
                "{} already holds a run: choose another --out (nothing was overwritten)",
                dir.display()
            );
        }
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let need = expected_rows.saturating_mul(ROW_BYTES);
        let free = fs4::available_space(dir)
            .with_context(|| format!("reading the free space of {}", dir.display()))?;
        if free < need {
            bail!(
                "{}: {} MB free, the run needs ~{} MB: free some space or choose another --out",
                dir.display(),
                free / 1_000_000,
                need.div_ceil(1_000_000)
            );
        }
        let open = |name: &str| -> Result<(PathBuf, Csv)> {
            let path = dir.join(name);
            let f = File::create(&path).with_context(|| format!("creating {}", path.display()))?;
            Ok((path, RowWriter::new(BufWriter::with_capacity(1 << 16, f))))
        };
        let mode_name = mode.to_string();
        let (tick_sink, mut ticks) = if streams.ticks {
            let (path, mut out) = open("haptic.csv")?;
            write_tick_header(&mut out, mode)
                .with_context(|| format!("writing {}", path.display()))?;
            let (producer, ring) = rtrb::RingBuffer::new(RING_CAPACITY);
            let stream = CsvStream {
                path,
                out,
                ring,
                row: Box::new(move |w, r| write_tick_row(w, r, &mode_name)),
                kept: Vec::new(),
            };
            (RecordSink::Ring(producer, 0), Some(stream))
        } else {
            (RecordSink::Discard, None)
        };
        let (step_sink, mut steps) = if streams.steps {
            let (path, mut out) = open("physics.csv")?;
            write_physics_header(&mut out)
                .with_context(|| format!("writing {}", path.display()))?;
            let (producer, ring) = rtrb::RingBuffer::new(RING_CAPACITY);
            let stream = CsvStream {
                path,
                out,
                ring,
                row: Box::new(write_physics_row),
                kept: Vec::new(),
            };
            (RecordSink::Ring(producer, 0), Some(stream))
        } else {
            (RecordSink::Discard, None)
        };
        let stop_writer = Arc::new(AtomicBool::new(false));
        let st = stop_writer.clone();
        let writer = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || -> Result<Recorded> {
                let result = write_loop(&mut ticks, &mut steps, &st);
                if result.is_err() {
                    run_stop.store(true, Ordering::Relaxed);
                }
                result?;
                Ok(Recorded {
                    ticks: ticks.map(|s| s.kept).unwrap_or_default(),
                    steps: steps.map(|s| s.kept).unwrap_or_default(),
                })
            })
            .context("starting the recorder thread")?;
        Ok((
            Recording {
                dir: dir.to_path_buf(),
                stop_writer,
                writer,
            },
            tick_sink,
            step_sink,
        ))
    }

    /// The run directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Stops the writer after it has written everything pushed so far (call
    /// once the loops have stopped) and returns what it wrote.
    pub fn finish(self) -> Result<Recorded> {
        self.stop_writer.store(true, Ordering::Release);
        self.writer
            .join()
            .map_err(|_| anyhow::anyhow!("the recorder thread panicked"))?
    }
}

fn write_loop(
    ticks: &mut Option<CsvStream<TickRecord>>,
    steps: &mut Option<CsvStream<PhysicsRecord>>,
    stop: &AtomicBool,
) -> Result<()> {
    let mut last_flush = Instant::now();
    loop {
        // Read the flag before draining: everything pushed before the loops
        // stopped is in the rings when the flag is seen.
        let stopping = stop.load(Ordering::Acquire);
        let flush = stopping || last_flush.elapsed() >= FLUSH_INTERVAL;
        if let Some(t) = ticks.as_mut() {
            t.drain()?;
            if flush {
                t.flush()?;
            }
        }
        if let Some(s) = steps.as_mut() {
            s.drain()?;
            if flush {
                s.flush()?;
            }
        }
        if stopping {
            return Ok(());
        }
        if flush {
            last_flush = Instant::now();
        }
        std::thread::sleep(DRAIN_PERIOD);
    }
}
