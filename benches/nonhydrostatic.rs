//! Cost of a non-hydrostatic time step relative to a hydrostatic one on the same grid
//! (issue 3; seed 000 §3 reports about 2.4×). Results: docs/performance.md.
//!
//!     CARGO_TARGET_DIR=... cargo bench --bench nonhydrostatic [-- --quick]
//!
//! Each case is a scenario run with `model.pressure` hydrostatic and non-hydrostatic:
//! both are advanced (untimed) to `t0`, then `steps` steps are timed. The best of
//! several repetitions is kept (the least disturbed by the machine). Δt is each run's
//! own CFL step; the cost of a step does not depend on it.

use std::path::Path;
use std::time::Instant;

use granflow::scenario::load_file;
use granflow::setup::build_simulation;
use granflow::simulation::Simulation;

struct Case {
    name: &'static str,
    file: &'static str,
    sets: &'static [&'static str],
    t0: f64,
    steps: usize,
}

const CASES: &[Case] = &[
    Case {
        name: "collapse 22°, 640 cells (paper grid), t = 0.3 s",
        file: "collapse_nh.toml",
        sets: &[],
        t0: 0.3,
        steps: 2000,
    },
    Case {
        name: "collapse 22° on a 1 cm erodible bed (all wet), 640 cells",
        file: "collapse_nh.toml",
        sets: &["initial.erodible_bed=0.01"],
        t0: 0.3,
        steps: 2000,
    },
    Case {
        name: "collapse 22° on a 1 cm erodible bed (all wet), 64 000 cells",
        file: "collapse_nh.toml",
        sets: &["initial.erodible_bed=0.01", "domain.cells=64000"],
        t0: 0.01,
        steps: 100,
    },
];

fn build(case: &Case, pressure: &str) -> Simulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(case.file);
    let mut sets: Vec<String> = case.sets.iter().map(|s| s.to_string()).collect();
    sets.push(format!("model.pressure={pressure}"));
    sets.push("time.stop_at_rest=false".into());
    let scn = load_file(&path, &sets).expect("scenario");
    build_simulation(&scn).expect("builds")
}

/// Best time per step (s) over `reps` repetitions, and the stage times of that one.
fn time_per_step(case: &Case, pressure: &str, reps: usize) -> (f64, Vec<(String, f64)>) {
    let mut best = (f64::INFINITY, Vec::new());
    for _ in 0..reps {
        let mut sim = build(case, pressure);
        while sim.t < case.t0 {
            let dt = sim.step(case.t0 - sim.t).expect("step");
            sim.t += dt;
        }
        let before = sim.stage_times();
        let start = Instant::now();
        for _ in 0..case.steps {
            let dt = sim.step(f64::INFINITY).expect("step");
            sim.t += dt;
        }
        let per_step = start.elapsed().as_secs_f64() / case.steps as f64;
        if per_step < best.0 {
            let stages = sim
                .stage_times()
                .into_iter()
                .zip(before)
                .map(|((name, t), (_, t0))| (name, (t - t0) / case.steps as f64))
                .collect();
            best = (per_step, stages);
        }
    }
    best
}

fn micros(s: f64) -> String {
    format!("{:.2} µs", s * 1e6)
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let reps = if quick { 2 } else { 7 };
    println!("| case | hydrostatic step | non-hydrostatic step | ratio | H stages (hyperbolic / friction) | NH stages (hyperbolic / friction / projection) |");
    println!("|---|---|---|---|---|---|");
    for case in CASES {
        // Interleave the two models so that both see the same machine state.
        let (h1, h_stages1) = time_per_step(case, "hydrostatic", reps);
        let (nh, nh_stages) = time_per_step(case, "nonhydrostatic", reps);
        let (h2, h_stages2) = time_per_step(case, "hydrostatic", reps);
        let (h, h_stages) = if h1 <= h2 {
            (h1, h_stages1)
        } else {
            (h2, h_stages2)
        };
        let list = |stages: &[(String, f64)]| {
            stages
                .iter()
                .map(|(_, t)| micros(*t))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        println!(
            "| {} | {} | {} | {:.2}× | {} | {} |",
            case.name,
            micros(h),
            micros(nh),
            nh / h,
            list(&h_stages),
            list(&nh_stages)
        );
    }
}
