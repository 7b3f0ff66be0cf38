//! Benchmarks of the hydrostatic monolayer model (not tests: nothing is asserted).
//!
//!   cargo bench --bench hydrostatic
//!
//! 1. Throughput of each stage in cell updates per second, single thread, on the
//!    Garres-Díaz et al. 2021, §4.3 collapse at 640 and 20 000 cells.
//! 2. Escalante et al. 2023, Table 9 "H-1 l.": θ = 0°, h_i = 1 mm, 640 cells, CFL 0.1, to 1.5 s
//!    (4.7 s in the paper), whole run with the in-memory sink and with HDF5 output.

use std::path::Path;
use std::time::Instant;

use granflow::output::memory::MemorySink;
use granflow::runner::run_to_files;
use granflow::scenario::{load_file, Scenario};
use granflow::setup::build_granular;

fn collapse(overrides: &[&str]) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_file(&path, &overrides).expect("valid scenario")
}

/// Wall seconds, steps and per-stage seconds of one run.
type Timing = (f64, u64, Vec<(String, f64)>);

/// Best of `repeats` runs.
fn best_run(scn: &Scenario, repeats: usize) -> Timing {
    let mut best: Option<Timing> = None;
    for _ in 0..repeats {
        let mut sim = build_granular(scn);
        let mut sink = MemorySink::default();
        let start = Instant::now();
        let summary = sim.run(&mut sink, &mut |_| {}).unwrap();
        let wall = start.elapsed().as_secs_f64();
        if best.as_ref().is_none_or(|b| wall < b.0) {
            best = Some((wall, summary.steps, summary.stage_times));
        }
    }
    best.unwrap()
}

fn throughput(cells: usize, t_end: f64) {
    let scn = collapse(&[
        &format!("domain.cells={cells}"),
        &format!("time.t_end={t_end}"),
        "time.stop_at_rest=false",
        &format!("output.every={t_end}"),
    ]);
    let (wall, steps, stages) = best_run(&scn, 3);
    let updates = steps as f64 * cells as f64;
    println!(
        "collapse {cells:>6} cells, {steps:>6} steps: {:>7.2} M cell updates/s (whole step, incl. CFL and diagnostics)",
        updates / wall / 1e6
    );
    for (name, secs) in stages {
        println!(
            "    {name:<12} {:>7.2} M cell updates/s  ({:.1} ns/cell)",
            updates / secs / 1e6,
            secs / updates * 1e9
        );
    }
}

fn table9_h1() {
    let h_i = 1e-3;
    let scn = collapse(&[
        "domain.slope_deg=0",
        &format!("initial.erodible_bed={h_i}"),
        "time.cfl=0.1",
        "time.t_end=1.5",
        "time.stop_at_rest=false",
        "output.every=0.05",
        // Escalante et al. 2023, Table 1, μ(I) coefficients + 0.1 for sidewall friction (its §5)
        "rheology.mu_s_deg=29.983894",
        "rheology.mu_2_deg=39.575179",
    ]);
    let (wall, steps, _) = best_run(&scn, 5);
    println!("Table 9 H-1 l. (in-memory output): {wall:.3} s wall, {steps} steps (paper: 4.7 s)");
    let dir = std::env::temp_dir().join("granflow-bench");
    let h5 = dir.join("table9_h1.h5");
    let start = Instant::now();
    run_to_files(&scn, &h5, &mut |_| {}).unwrap();
    println!(
        "Table 9 H-1 l. (HDF5 + CSV output, 31 snapshots): {:.3} s wall",
        start.elapsed().as_secs_f64()
    );
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --benches` would pass nothing useful.
    println!("granflow hydrostatic benchmarks (single thread)");
    throughput(640, 1.0);
    throughput(20_000, 0.05);
    table9_h1();
}
