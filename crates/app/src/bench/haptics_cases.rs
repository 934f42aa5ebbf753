//! Measurements behind `echothigh bench haptics`: compute time per haptic
//! tick, per model-manager update, and the loop runner's period error. The
//! scenario is analytic: a sphere of radius 8 cm (a thigh-sized local
//! surface) whose radius breathes by ±1 cm at 0.3 Hz (so every fit has work
//! to do), a device pressing up to 5 mm in while sliding on a 2 cm circle,
//! and physics samples at 100 Hz (D = −|F|/k in contact, k = 500 N/m).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use echothigh_haptics::{
    handoff, ConfigError, FitConfig, HapticRenderer, LoopConfig, LoopRunner, ModelManager,
    Percentiles, RenderConfig, Sample, TimingSummary, Vec3,
};

/// What to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchOptions {
    /// Timed ticks (each timed alone). Default 200 000.
    pub ticks: usize,
    /// Timed model-manager updates. Default 20 000.
    pub fits: usize,
    /// Duration of the real-time loop run, s (0 skips it). Default 10.
    pub loop_seconds: f64,
    /// Loop settings for that run.
    pub loop_config: LoopConfig,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            ticks: 200_000,
            fits: 20_000,
            loop_seconds: 10.0,
            loop_config: LoopConfig::default(),
        }
    }
}

/// Percentiles in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Micros {
    /// Number of samples.
    pub count: usize,
    /// Median, µs.
    pub median_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// 99.9th percentile, µs.
    pub p999_us: f64,
    /// Maximum, µs.
    pub max_us: f64,
}

impl From<Percentiles> for Micros {
    fn from(p: Percentiles) -> Self {
        Micros {
            count: p.count,
            median_us: p.median * 1e6,
            p99_us: p.p99 * 1e6,
            p999_us: p.p999 * 1e6,
            max_us: p.max * 1e6,
        }
    }
}

/// The loop run's timing.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LoopReport {
    /// Run length, s.
    pub seconds: f64,
    /// Target rate, Hz.
    pub rate_hz: f64,
    /// Ticks run.
    pub ticks: u64,
    /// Compute time inside the loop (renderer tick), µs.
    pub compute: Micros,
    /// |start − deadline| per tick, µs.
    pub period_error: Micros,
    /// Deadlines missed in the run.
    pub missed_deadlines: u64,
    /// Missed deadlines per 10 000 ticks.
    pub missed_per_10k: f64,
    /// Whether real-time priority was granted.
    pub realtime_priority: bool,
}

impl LoopReport {
    fn new(s: &TimingSummary, seconds: f64) -> Self {
        LoopReport {
            seconds,
            rate_hz: 1.0 / s.period,
            ticks: s.ticks,
            compute: s.compute.into(),
            period_error: s.period_error.into(),
            missed_deadlines: s.missed_deadlines,
            missed_per_10k: s.missed_per_10k,
            realtime_priority: s.realtime_priority,
        }
    }
}

/// Everything `echothigh bench haptics` reports.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BenchReport {
    /// Compute time per haptic tick (model updates interleaved at 100 Hz), µs.
    pub tick: Micros,
    /// Compute time per model-manager update (window 8, sphere), µs.
    pub fit: Micros,
    /// Mean Gauss–Newton iterations per update.
    pub fit_mean_iterations: f64,
    /// Real-time loop run (absent when `loop_seconds = 0`).
    pub loop_run: Option<LoopReport>,
}

const RADIUS: f64 = 0.08;
const STIFFNESS: f64 = 500.0;

/// Device position at time `t` (s): slides on a 2 cm circle while pressing
/// 0–5 mm into the sphere's top.
pub fn device_path(t: f64) -> Vec3 {
    let w = std::f64::consts::TAU * 0.5;
    let depth = 0.0025 * (1.0 - (w * 0.7 * t).cos()) - 0.001;
    let lateral = Vec3::new(0.02 * (w * t).cos(), 0.0, 0.02 * (w * t).sin());
    let dir = (Vec3::new(0.0, RADIUS, 0.0) + lateral).normalize();
    dir * (RADIUS - depth)
}

/// The physics sample an analytic sphere at the origin, of radius
/// `0.08 + 0.01 sin(2π·0.3 t)` m, reports at `p` (m) and time `t` (s).
pub fn sphere_sample(p: Vec3, t: f64) -> Sample {
    let rho = p.norm();
    let radius = RADIUS + 0.01 * (std::f64::consts::TAU * 0.3 * t).sin();
    Sample {
        time: t,
        p,
        distance: rho - radius,
        gradient: p / rho,
        stiffness: STIFFNESS,
    }
}

/// Runs the measurements; fails only on an invalid `opts.loop_config` or
/// a negative/non-finite `loop_seconds`.
pub fn run(opts: &BenchOptions) -> Result<BenchReport, ConfigError> {
    opts.loop_config.validate("haptics.loop")?;
    if !(opts.loop_seconds.is_finite() && opts.loop_seconds >= 0.0) {
        return Err(ConfigError::Invalid {
            key: "bench.seconds".into(),
            reason: format!("must be finite and >= 0, got {}", opts.loop_seconds),
        });
    }
    let (tick, _) = measure_ticks(opts.ticks)?;
    let (fit, fit_mean_iterations) = measure_fits(opts.fits)?;
    let loop_run = if opts.loop_seconds > 0.0 {
        Some(measure_loop(opts)?)
    } else {
        None
    };
    Ok(BenchReport {
        tick: tick.into(),
        fit: fit.into(),
        fit_mean_iterations,
        loop_run,
    })
}

/// Times `n` ticks at 1 kHz virtual time with a model update every 10 ticks
/// (not timed); returns the percentiles and the checksum of the forces.
pub fn measure_ticks(n: usize) -> Result<(Percentiles, f64), ConfigError> {
    let (tx, rx) = handoff();
    let mut manager = ModelManager::new(&FitConfig::default(), tx)?;
    let mut renderer = HapticRenderer::new(&RenderConfig::default(), rx)?;
    let mut times = Vec::with_capacity(n);
    let mut checksum = 0.0;
    for i in 0..n {
        let t = i as f64 * 1e-3;
        let p = device_path(t);
        if i % 10 == 0 {
            manager.update(&sphere_sample(p, t));
        }
        let start = Instant::now();
        let f = renderer.tick(p, t);
        times.push(start.elapsed().as_secs_f64());
        checksum += f.y;
    }
    Ok((Percentiles::of(&mut times), checksum))
}

/// Times `n` model-manager updates along the device path at 100 Hz.
pub fn measure_fits(n: usize) -> Result<(Percentiles, f64), ConfigError> {
    let (tx, _rx) = handoff();
    let mut manager = ModelManager::new(&FitConfig::default(), tx)?;
    let mut times = Vec::with_capacity(n);
    let mut iterations = 0u64;
    for i in 0..n {
        let t = i as f64 * 1e-2;
        let s = sphere_sample(device_path(t), t);
        let start = Instant::now();
        let r = manager.update(&s);
        times.push(start.elapsed().as_secs_f64());
        iterations += u64::from(r.iterations);
    }
    Ok((
        Percentiles::of(&mut times),
        iterations as f64 / n.max(1) as f64,
    ))
}

/// Runs the real loop for `opts.loop_seconds` with a 100 Hz model manager
/// on another thread.
pub fn measure_loop(opts: &BenchOptions) -> Result<LoopReport, ConfigError> {
    let (tx, rx) = handoff();
    let mut manager = ModelManager::new(&FitConfig::default(), tx)?;
    let mut renderer = HapticRenderer::new(&RenderConfig::default(), rx)?;
    let mut runner = LoopRunner::new(&opts.loop_config)?;
    let stop = Arc::new(AtomicBool::new(false));
    let physics_stop = stop.clone();
    let epoch = Instant::now();
    let physics = std::thread::spawn(move || {
        while !physics_stop.load(Ordering::Relaxed) {
            let t = epoch.elapsed().as_secs_f64();
            manager.update(&sphere_sample(device_path(t), t));
            spin_sleep::sleep(Duration::from_millis(10));
        }
    });
    let ticks = (opts.loop_seconds * opts.loop_config.rate_hz).round() as u64;
    runner.run(&AtomicBool::new(false), Some(ticks), |_, _| {
        let t = epoch.elapsed().as_secs_f64();
        std::hint::black_box(renderer.tick(device_path(t), t));
    });
    stop.store(true, Ordering::Relaxed);
    let _ = physics.join();
    Ok(LoopReport::new(&runner.summary(), opts.loop_seconds))
}
