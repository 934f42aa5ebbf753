//! `echothigh bench physics`: time per implicit step (median, p90), PCG and
//! Newton iterations per step and steps per second, for meshes of about 500,
//! 1 000 (the default), 2 000, 8 000, 10 000 and 32 000 nodes, in three
//! scenarios (free motion under gravity, a constant 10 N probe-patch load, a
//! 0–15 N press at 1 Hz; see [`super::physics_cases`]). One run's numbers on
//! one thread, as wall-clock time and as the thread's CPU time (the per-core
//! cost, which other processes on a shared machine do not inflate). Each
//! case also reports the median time of each stage of the step
//! (`stage_median_s`: `echothigh_model::StepTimings`, monotonic clock).
//!
//! The active window (issue 18): the 10 112-node press with and without
//! it, alternated `--window-rounds` times in the same run (rows `press`
//! and `window`; `window` in the JSON).
//!
//! `--compare` runs instead the same-run A/B of the default system (edge
//! form, SIMD kernels) against a baseline (`--baseline scalar`: the scalar
//! kernels; `block-sparse`: the block-sparse reference; `reference-queries`:
//! the haptic queries' previous implementation; issue 18, see
//! [`super::physics_compare`]): the press case at each size and the
//! contact case with its queries, reporting the ratio of the medians.

use std::path::PathBuf;

use super::physics_cases::{run_case, run_case_windowed, CaseReport, Scenario, SIZES};
use anyhow::Context;

/// Arguments of `echothigh bench physics`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the JSON report on stdout (the human table always goes to stderr).
    #[arg(long)]
    json: bool,
    /// Also write the JSON report to this file.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Skip meshes with more nodes than this.
    #[arg(long, default_value_t = usize::MAX)]
    max_nodes: usize,
    /// Multiply every case's number of measured steps by this (≥ 1 step each).
    #[arg(long, default_value_t = 1.0)]
    steps_scale: f64,
    /// Untimed steps before the measured ones.
    #[arg(long, default_value_t = 3)]
    warmup: usize,
    /// Steps of the contact case (default mesh, probe pressed 10 mm; 0 skips it).
    #[arg(long, default_value_t = 200)]
    contact_steps: usize,
    /// Run the contact case on this patient's leg (a preset: lean-male,
    /// average-female, obese; issue 12) instead of the elliptic cylinder.
    #[arg(long)]
    patient: Option<String>,
    /// Same-run A/B instead: a baseline (`--baseline`) against the default
    /// system, interleaved, medians of thread CPU time and their ratio.
    #[arg(long)]
    compare: bool,
    /// The baseline of `--compare`: the scalar kernels of the edge form
    /// (the implementation before the SIMD kernels), the block-sparse
    /// reference, or the haptic queries' previous implementation
    /// (`reference-queries`: only the contact case differs).
    #[arg(long, value_enum, default_value = "scalar")]
    baseline: super::physics_compare::Baseline,
    /// The probe in the contact case of `--compare`: held 10 mm in, or
    /// moving between 10 and 0 mm at 1 Hz.
    #[arg(long, value_enum, default_value = "held")]
    contact_motion: super::physics_compare::ContactMotion,
    /// Ticks of the `direct` tick's A/B instead (the built-in scenario's
    /// exam, the real-time force-only tick against the tick with the haptic
    /// queries, interleaved; 0: not run).
    #[arg(long, default_value_t = 0)]
    direct_ticks: usize,
    /// With `--direct-ticks`: the second tick is the force-only tick
    /// integrating only the active window of this radius (m), as `run
    /// --mode direct` does, instead of the tick with the queries (0).
    #[arg(long, default_value_t = 0.0)]
    direct_window: f64,
    /// Rounds of the active window's A/B (10k press with and without the
    /// window, alternated; 0 skips it).
    #[arg(long, default_value_t = 3)]
    window_rounds: usize,
    /// Radius of the active window (m) in its A/B.
    #[arg(long, default_value_t = 0.05)]
    window_radius: f64,
}

/// Runs the benchmark, prints the table on stderr, writes/prints the JSON.
pub fn run(args: Args) -> anyhow::Result<()> {
    if !(args.steps_scale.is_finite() && args.steps_scale > 0.0) {
        anyhow::bail!("--steps-scale must be > 0, got {}", args.steps_scale);
    }
    if args.direct_ticks > 0 {
        return run_direct(&args);
    }
    if args.compare {
        return run_compare(&args);
    }
    let mut cases = Vec::new();
    eprintln!(
        "{:<6} {:>6}  {:>11} {:>11} {:>10}  {:>11} {:>11} {:>10} {:>9} {:>7} {:>7}",
        "case",
        "nodes",
        "median µs",
        "p90 µs",
        "steps/s",
        "CPU med µs",
        "CPU p90 µs",
        "CPU st/s",
        "CG/step",
        "Newton",
        "limited"
    );
    for &(nt, nz, steps) in SIZES.iter().filter(|(nt, nz, _)| nt * nz <= args.max_nodes) {
        let steps = ((steps as f64 * args.steps_scale).round() as usize).max(1);
        for scenario in Scenario::ALL {
            let r = run_case(scenario, nt, nz, steps, args.warmup)
                .with_context(|| format!("building the {nt}×{nz} mesh"))?;
            print_row(&r);
            cases.push(r);
        }
    }
    let window = window_ab(&args)?;
    let contact = if args.contact_steps > 0 {
        let c = super::contact::contact_report(args.contact_steps, args.patient.as_deref())?;
        let on = args.patient.as_deref().unwrap_or("elliptic cylinder");
        eprintln!("contact (default mesh on {on}, 10 mm press): {c}");
        c
    } else {
        serde_json::Value::Null
    };
    let json = serde_json::json!({
        "bench": "physics",
        "contact": contact,
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "threads": 1,
        // Issue 18's goals, one core: 10k nodes press, and the default mesh
        // with the contact queries (see `contact.steps_per_second`).
        "goals": { "nodes_10k_press_steps_per_s": 250.0, "default_mesh_with_queries_steps_per_s": 3000.0 },
        "cases": cases,
        "window": window,
    });
    emit(&args, &json)
}

/// The active window's A/B: the 10k press without and with the window,
/// alternated `--window-rounds` times; the rows, and the medians over the
/// rounds of each side's thread-CPU median per step.
fn window_ab(args: &Args) -> anyhow::Result<serde_json::Value> {
    let (nt, nz, steps) = SIZES[4];
    if args.window_rounds == 0 || nt * nz > args.max_nodes {
        return Ok(serde_json::Value::Null);
    }
    let steps = ((steps as f64 * args.steps_scale).round() as usize).max(1);
    let mut rounds: Vec<[CaseReport; 2]> = Vec::new();
    for _ in 0..args.window_rounds {
        let run = |w| {
            run_case_windowed(Scenario::Press, (nt, nz), w, steps, args.warmup)
                .with_context(|| format!("the {nt}×{nz} press, window {w:?}"))
        };
        let (full, win) = (run(None)?, run(Some(args.window_radius))?);
        print_row(&full);
        print_named_row("window", &win);
        rounds.push([full, win]);
    }
    let median = |side: usize| {
        let mut v: Vec<f64> = rounds.iter().map(|r| r[side].cpu_median_us).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (full, win) = (median(0), median(1));
    eprintln!(
        "window A/B ({} nodes, radius {} m, {} rounds): CPU median µs full {full:.1}, window {win:.1} \
         ({:.0} against {:.0} steps/s, ×{:.2})",
        nt * nz,
        args.window_radius,
        rounds.len(),
        1e6 / win,
        1e6 / full,
        full / win
    );
    Ok(serde_json::json!({
        "nodes": nt * nz,
        "radius_m": args.window_radius,
        "goal_steps_per_s": 1000.0,
        "full_cpu_median_us": full,
        "window_cpu_median_us": win,
        "rounds": rounds,
    }))
}

/// `--compare`: the A/B per size (press) and the contact case.
fn run_compare(args: &Args) -> anyhow::Result<()> {
    use super::physics_compare::{compare_contact, compare_press, CompareReport};
    let mut cases: Vec<CompareReport> = Vec::new();
    eprintln!(
        "{:<8} {:>6} {:>6}  {:>12} {:>12} {:>7} {:>10} {:>11}",
        "case", "nodes", "steps", "old CPU µs", "new CPU µs", "ratio", "new st/s", "max gap m"
    );
    let print = |r: &CompareReport| {
        eprintln!(
            "{:<8} {:>6} {:>6}  {:>12.1} {:>12.1} {:>7.2} {:>10.1} {:>11.2e}",
            r.case,
            r.nodes,
            r.steps,
            r.old_cpu_median_us,
            r.new_cpu_median_us,
            r.ratio,
            r.new_cpu_steps_per_s,
            r.max_position_gap_m
        )
    };
    for &(nt, nz, steps) in SIZES.iter().filter(|(nt, nz, _)| nt * nz <= args.max_nodes) {
        let steps = ((steps as f64 * args.steps_scale).round() as usize).max(1);
        let r = compare_press(nt, nz, steps, args.warmup, args.baseline)
            .with_context(|| format!("building the {nt}×{nz} mesh"))?;
        print(&r);
        cases.push(r);
    }
    if args.contact_steps > 0 {
        let r = compare_contact(args.contact_steps, args.baseline, args.contact_motion)?;
        print(&r);
        if let Some([[ns, nq], [os, oq]]) = r.step_and_queries_cpu_median_us {
            eprintln!(
                "contact CPU medians µs: new step {ns:.1} + queries {nq:.1}, old step {os:.1} + queries {oq:.1}"
            );
        }
        if let Some([n, o]) = r.stiffness_unassembled {
            eprintln!(
                "stiffness queries with no assembly: new {n}, old {o} of {} ({:?} probe)",
                r.steps, args.contact_motion
            );
        }
        cases.push(r);
    }
    let json = serde_json::json!({
        "bench": "physics_compare",
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "threads": 1,
        "old": args.baseline,
        "new": "edge_simd",
        "cases": cases,
    });
    emit(args, &json)
}

fn run_direct(args: &Args) -> anyhow::Result<()> {
    let o = super::direct_compare::OtherTick {
        window_radius_m: args.direct_window,
    };
    let r = super::direct_compare::compare_direct(args.direct_ticks, o)?;
    let other = if o.queries() {
        "with queries".to_string()
    } else {
        format!("window {} mm", o.window_radius_m * 1e3)
    };
    for (name, c) in [
        ("force only", &r.force_only),
        (other.as_str(), &r.with_queries),
    ] {
        eprintln!(
            "direct tick, {name:<12} ({} nodes, {} ticks): thread-CPU median {:.1} µs, p99 {:.1}, max {:.1}; {} ticks over 1 ms",
            r.nodes, r.ticks, c.median_us, c.p99_us, c.max_us, c.over_period
        );
    }
    eprintln!(
        "median ratio ({other} / force only) {:.2}; largest force gap {:.1e} N; Newton iterations {} / {}",
        r.median_ratio,
        r.max_force_gap_n,
        r.other_newton_iterations,
        r.force_only_newton_iterations
    );
    let stages: Vec<String> = r
        .contact_stage_medians_us
        .iter()
        .filter(|(_, us)| *us > 0.0)
        .map(|(name, us)| format!("{name} {us:.1}"))
        .collect();
    eprintln!(
        "force-only ticks in contact, medians (µs): {}",
        stages.join(", ")
    );
    let json = serde_json::json!({
        "bench": "physics_direct_tick",
        "profile": if cfg!(debug_assertions) { "debug" } else { "release" },
        "threads": 1,
        "direct": r,
    });
    emit(args, &json)
}

fn print_row(r: &CaseReport) {
    let name = match r.scenario {
        Scenario::Free => "free",
        Scenario::Load => "load",
        Scenario::Press => "press",
    };
    print_named_row(name, r);
}

fn print_named_row(name: &str, r: &CaseReport) {
    eprintln!(
        "{name:<6} {:>6}  {:>11.1} {:>11.1} {:>10.1}  {:>11.1} {:>11.1} {:>10.1} {:>9.1} {:>7.2} {:>7}",
        r.nodes,
        r.median_us,
        r.p90_us,
        r.steps_per_s,
        r.cpu_median_us,
        r.cpu_p90_us,
        r.cpu_steps_per_s,
        r.cg_iterations_mean,
        r.newton_iterations_mean,
        r.limited_total
    );
}

/// Writes the JSON report to `--out` and prints it with `--json`.
fn emit(args: &Args, json: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(json)?;
    if let Some(path) = &args.out {
        std::fs::write(path, &text).with_context(|| format!("writing {}", path.display()))?;
    }
    if args.json {
        println!("{text}");
    }
    Ok(())
}
