//! Stop time, settled time and runout of one scenario under grid refinement
//! (docs/validation.md, "Stop time and runout under refinement"):
//!
//!   cargo run --release --example refine_stop -- scenarios/collapse.toml 640 1280 2560 5120
//!
//! (docs/validation.md quotes it without `--release`, which CI's doc check adds).
//!
//! Arguments with an `=` are `--set` overrides for every run (e.g.
//! `time.stop_when_settled=false` to follow a μ(I) creep to t_end). For each number of
//! cells, one run as the scenario says, printing how it ended, the time of exact rest
//! (`stop_time`; "-" if not at rest when it ended), the settled time (`settled_time`:
//! the kinetic energy at or below `time.settle_fraction` of its peak from then on; "-"
//! if not settled), the runout at the end and the number of steps. With the μ(I) law a
//! deposit creeps on long after it has settled, so only the settled time converges.
use granflow::output::memory::MemorySink;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (file, rest) = args
        .split_first()
        .expect("usage: refine_stop FILE CELLS... [KEY=VALUE...]");
    let (overrides, grids): (Vec<&String>, Vec<&String>) =
        rest.iter().partition(|a| a.contains('='));
    println!("cells  status           exact rest (s)  settled (s)  runout (m)  steps");
    let time = |t: f64| {
        if t.is_nan() {
            "-".to_string()
        } else {
            format!("{t:.3}")
        }
    };
    for cells in grids {
        let mut sets = vec![format!("domain.cells={cells}")];
        sets.extend(overrides.iter().map(|s| s.to_string()));
        let scn = granflow::scenario::load_file(Path::new(file), &sets).expect("scenario");
        let mut sim = granflow::setup::build(&scn);
        let mut sink = MemorySink::default();
        sim.run(&mut sink, &mut |_| {}).expect("run");
        let s = sink.summary.as_ref().expect("summary");
        println!(
            "{cells:>5}  {:<15}  {:>14}  {:>11}  {:>10.4}  {:>5}",
            s.status,
            time(s.stop_time),
            time(s.settled_time),
            s.runout,
            s.steps
        );
    }
}
