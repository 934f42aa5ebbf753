//! Physics step benchmark of this crate alone (builds only the model's
//! dependencies): `cargo run --release -p echothigh-model --example
//! bench_physics [max_nodes] [min_nodes]` prints the JSON report on stdout and a table on
//! stderr. `echothigh bench physics` runs the same cases.

use echothigh_model::bench::{run_case, Scenario, SIZES};

fn main() {
    let max_nodes: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(usize::MAX);
    let min_nodes: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(0);
    let mut reports = Vec::new();
    for &(nt, nz, steps) in SIZES
        .iter()
        .filter(|(nt, nz, _)| (min_nodes..=max_nodes).contains(&(nt * nz)))
    {
        for scenario in Scenario::ALL {
            match run_case(scenario, nt, nz, steps, 3) {
                Ok(r) => {
                    eprintln!(
                        "{:<6} {:>6} nodes  wall median {:>8.1} µs p90 {:>8.1} µs {:>7.1} steps/s | CPU median {:>8.1} µs p90 {:>8.1} µs {:>7.1} steps/s | CG/step {:>5.1} Newton/step {:.2} limited {}",
                        format!("{:?}", r.scenario), r.nodes, r.median_us, r.p90_us, r.steps_per_s,
                        r.cpu_median_us, r.cpu_p90_us, r.cpu_steps_per_s,
                        r.cg_iterations_mean, r.newton_iterations_mean, r.limited_total
                    );
                    reports.push(r);
                }
                Err(e) => eprintln!("case {nt}x{nz}: {e}"),
            }
        }
    }
    match serde_json::to_string_pretty(&reports) {
        Ok(text) => println!("{text}"),
        Err(e) => eprintln!("cannot serialize the report: {e}"),
    }
}
