//! Benchmark of the hydrostatic multilayer model: Escalante et al. 2023, Table 9, θ = 22° — the
//! collapse of §5.1 (domain [−0.2, 3] m, 640 cells, h_i = 1.82 mm, Table 1 material,
//! δ = 1e-5) with CFL 0.1 to t = 3 s, for 1, 10 and 20 layers ("H-1 l.", "H-10 l.",
//! "H-20 l."; the paper took 7.1, 41.0 and 79.4 s). Single thread.
//!
//!     cargo bench --bench multilayer            # best of 3 runs each
//!     GRANFLOW_BENCH_REPS=1 cargo bench --bench multilayer
//!
//! Prints the wall time of each run and, per stage, the cost per cell and layer of one
//! time step (stage time / (steps · cells · layers)); the viscous stage's time includes
//! freezing its coefficients at t^n. Results: docs/performance.md, "Hydrostatic multilayer".

use std::path::Path;
use std::time::Instant;

use granflow::output::memory::SummarySink;
use granflow::scenario::load_file;
use granflow::setup::build_granular;

/// Escalante et al. 2023, Table 9 settings on top of `scenarios/erodible_bed.toml` (Fernández-Nieto et al. 2016, §4.2,
/// the same collapse): μ_2 = tan 36° (Escalante et al. 2023, Table 1), δ regularisation, CFL 0.1.
fn settings(layers: usize) -> Vec<String> {
    [
        format!("model.layers={layers}"),
        "rheology.mu_2_deg=36".into(),
        "rheology.regularization=delta".into(),
        "rheology.delta=1e-5".into(),
        "time.cfl=0.1".into(),
        "time.t_end=3".into(),
        "time.stop_at_rest=false".into(),
        "output.every=3".into(),
    ]
    .to_vec()
}

fn main() {
    let reps: usize = std::env::var("GRANFLOW_BENCH_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/erodible_bed.toml");
    println!(
        "Escalante et al. 2023, Table 9, θ = 22°, 640 cells, CFL 0.1, t = 3 s; best of {reps}"
    );
    for (label, layers, paper) in [
        ("H-1 l.", 1, 7.1),
        ("H-10 l.", 10, 41.0),
        ("H-20 l.", 20, 79.4),
    ] {
        let scn = load_file(&path, &settings(layers)).expect("scenario");
        // (wall time, steps, stage times) of the fastest run.
        type Run = (f64, u64, Vec<(String, f64)>);
        let mut best: Option<Run> = None;
        for _ in 0..reps {
            let mut sim = build_granular(&scn);
            let start = Instant::now();
            let summary = sim
                .run(&mut SummarySink::default(), &mut |_| {})
                .expect("run");
            let wall = start.elapsed().as_secs_f64();
            assert_eq!(summary.status, "completed");
            if best.as_ref().is_none_or(|b| wall < b.0) {
                best = Some((wall, summary.steps, sim.stage_times()));
            }
        }
        let (wall, steps, stages) = best.unwrap();
        let work = steps as f64 * scn.domain.cells as f64 * layers as f64;
        let per: Vec<String> = stages
            .iter()
            .map(|(name, t)| format!("{name} {:.1} ns", t / work * 1e9))
            .collect();
        println!(
            "{label:8} {wall:6.2} s wall (paper {paper} s), {steps} steps; per cell and layer: {}",
            per.join(", ")
        );
    }
}
