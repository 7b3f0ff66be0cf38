//! Stop time, settling time and runout of one scenario under grid refinement (issue 13
//! item 1, docs/validation.md "Stop time and runout under refinement"):
//!
//!   cargo run --release --example refine_stop -- scenarios/collapse.toml 640 1280 2560 5120
//!
//! (docs/validation.md quotes it without `--release`, which CI's doc check adds).
//!
//! Arguments with an `=` are `--set` overrides for every run (e.g. `time.t_end=4`).
//! For each number of cells, one run to the scenario's t_end (or its rest), printing
//! the time of exact rest (the run's stop time; "-" if not at rest by t_end), the
//! settling time (the last time the kinetic energy is at least 1e-6 of its peak; with
//! the μ(I) law a deposit creeps on long after it has settled, so only this one
//! converges), the runout at the end, and the number of steps.
use granflow::output::memory::MemorySink;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (file, rest) = args
        .split_first()
        .expect("usage: refine_stop FILE CELLS... [KEY=VALUE...]");
    let (overrides, grids): (Vec<&String>, Vec<&String>) =
        rest.iter().partition(|a| a.contains('='));
    println!("cells  exact rest (s)  settled (s)  runout (m)  steps");
    for cells in grids {
        let mut sets = vec![format!("domain.cells={cells}")];
        sets.extend(overrides.iter().map(|s| s.to_string()));
        let scn = granflow::scenario::load_file(Path::new(file), &sets).expect("scenario");
        let mut sim = granflow::setup::build(&scn);
        let mut sink = MemorySink::default();
        sim.run(&mut sink, &mut |_| {}).expect("run");
        let summary = sink.summary.as_ref().expect("summary");
        let energy = |r: &granflow::output::StepRecord| r.kinetic_energy;
        let peak = sink.steps.iter().map(energy).fold(0.0, f64::max);
        let settled = sink
            .steps
            .iter()
            .filter(|r| energy(r) >= 1e-6 * peak)
            .map(|r| r.t)
            .fold(0.0, f64::max);
        let rest = if summary.stop_time.is_nan() {
            "-".to_string()
        } else {
            format!("{:.3}", summary.stop_time)
        };
        println!(
            "{cells:>5}  {rest:>14}  {settled:>11.3}  {:>10.4}  {:>5}",
            summary.runout, summary.steps
        );
    }
}
