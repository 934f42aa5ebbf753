//! Contact part of `echothigh bench physics`: the step rate of the default
//! mesh with the probe pressed 10 mm into the mid-thigh, and the cost of the
//! haptic queries (distance, gradient, stiffness) per step. The physics
//! bench calls [`contact_report`] and merges its JSON.

use super::clock::thread_cpu_us;
use super::physics_cases::stage_medians;
use anyhow::{Context, Result};
use echothigh_contact::{ContactParams, Probe, ProbeContact};
use echothigh_model::{ModelConfig, StepTimings, ThighModel, Vec3};
use serde_json::{json, Value};
use std::time::Instant;

/// Median, 90th and 99th percentiles and maximum of durations (ms).
fn summary(mut ms: Vec<f64>) -> Value {
    ms.sort_by(|a, b| a.total_cmp(b));
    let q = |p: f64| ms[((ms.len() - 1) as f64 * p).round() as usize];
    json!({ "median_ms": q(0.5), "p90_ms": q(0.9), "p99_ms": q(0.99), "max_ms": q(1.0), "samples": ms.len() })
}

/// Times `steps` physics steps (after a 0.5 s ramp to 10 mm) and the
/// queries after each, on the default model at its default step; also the
/// queries out of contact (probe 5 mm above the skin).
///
/// With `patient` (a preset), the mesh follows that patient's leg
/// (`thigh.patient`, issue 12) and the probe presses its anterior line at
/// the segment's centre.
pub fn contact_report(steps: usize, patient: Option<&str>) -> Result<Value> {
    let steps = steps.max(10);
    let mut config = ModelConfig::default();
    if let Some(p) = patient {
        config.thigh.patient = p.to_string();
    }
    let h = config.integrator.time_step;
    let mut model = ThighModel::new(&config).context("default model")?;
    let top = match patient {
        None => config.thigh.semi_axis_y,
        Some(_) => {
            let mesh = model.mesh();
            mesh.rest_positions()[mesh.node_at(std::f64::consts::FRAC_PI_2, 0.0)].y
        }
    };
    let mut pc = ProbeContact::new(&model, Probe::default(), ContactParams::default())
        .context("default contact")?;
    let pose = |d: f64| Probe::exam_pose(Vec3::new(0.0, top - d, 0.0));
    for i in 1..=50 {
        pc.step(&mut model, &pose(0.010 * i as f64 / 50.0), h);
    }
    let (mut step_ms, mut query_ms) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let (mut step_cpu_ms, mut query_cpu_ms) =
        (Vec::with_capacity(steps), Vec::with_capacity(steps));
    let mut stages: Vec<StepTimings> = Vec::with_capacity(steps);
    let (mut cg, mut newton, mut schur_cg, mut force) = (0u64, 0u64, 0u64, 0.0);
    for _ in 0..steps {
        let (t0, c0) = (Instant::now(), thread_cpu_us());
        let (stats, _) = pc.advance(&mut model, &pose(0.010), h);
        let (t1, c1) = (Instant::now(), thread_cpu_us());
        let (sample, q) = pc.sample(&mut model);
        let (t2, c2) = (Instant::now(), thread_cpu_us());
        step_ms.push((t1 - t0).as_secs_f64() * 1e3);
        query_ms.push((t2 - t1).as_secs_f64() * 1e3);
        step_cpu_ms.push((c1 - c0) * 1e-3);
        query_cpu_ms.push((c2 - c1) * 1e-3);
        let mut t = stats.timings;
        t.accumulate(&q.timings);
        stages.push(t);
        cg += stats.cg_iterations as u64;
        newton += stats.newton_iterations as u64;
        schur_cg += q.stiffness_solve.iterations as u64;
        force = sample.force.norm();
    }
    let total: Vec<f64> = step_ms.iter().zip(&query_ms).map(|(a, b)| a + b).collect();
    let mut sorted = total.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let median_total = sorted[sorted.len() / 2];
    // Out of contact: the probe 5 mm above the skin.
    let mut free_ms = Vec::with_capacity(steps);
    for _ in 0..20 {
        pc.step(&mut model, &pose(-0.005), h);
    }
    for _ in 0..steps {
        pc.advance(&mut model, &pose(-0.005), h);
        let t0 = Instant::now();
        pc.sample(&mut model);
        free_ms.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok(json!({
        "nodes": model.node_count(),
        "time_step_s": h,
        "depth_m": 0.010,
        "force_n": force,
        "step_with_contact": summary(step_ms),
        "queries_in_contact": summary(query_ms),
        "step_with_contact_thread_cpu": summary(step_cpu_ms),
        "queries_in_contact_thread_cpu": summary(query_cpu_ms),
        "stage_median_s": stage_medians(&stages),
        "step_plus_queries": summary(total),
        "steps_per_second": 1e3 / median_total,
        "mean_newton_iterations": newton as f64 / steps as f64,
        "mean_cg_iterations": cg as f64 / steps as f64,
        "mean_stiffness_cg_iterations": schur_cg as f64 / steps as f64,
        "queries_out_of_contact": summary(free_ms),
    }))
}
