//! Cost of a non-hydrostatic time step relative to a hydrostatic one on the same grid
//! (Garres-Díaz et al. 2021, §3 reports about 2.4×, the target is ≤ 1.6×). Results and
//! machine: docs/performance.md, "Non-hydrostatic monolayer".
//!
//!     CARGO_TARGET_DIR=... cargo bench --bench nonhydrostatic [-- --quick] [-- --hydrostatic-only]
//!     cargo bench --bench nonhydrostatic -- --multilayer-only   # the 20-layer case (target ≤ 3×)
//!
//! Each case is `scenarios/collapse.toml` run with `model.pressure` hydrostatic and
//! non-hydrostatic: both are advanced (untimed) to `t0`, then `steps` steps are timed,
//! each with its own CFL Δt (the cost of a step does not depend on Δt), in bursts that
//! alternate between the two models; the best burst of each is kept, which filters out
//! other processes on a shared machine. `--hydrostatic-only` times the hydrostatic model alone, to
//! compare builds (the architecture rule: a hydrostatic run costs the same whether or
//! not the non-hydrostatic code exists).

use std::path::Path;
use std::time::Instant;

use granflow::model::granular::Granular;
use granflow::scenario::load_file;
use granflow::setup::build_granular;
use granflow::simulation::Simulation;

type Sim = Simulation<Granular>;

struct Case {
    name: &'static str,
    sets: &'static [&'static str],
    t0: f64,
    steps: usize,
}

const CASES: &[Case] = &[
    Case {
        name: "collapse 22°, 640 cells, 20 layers (Escalante et al. 2023, Table 2 grid), h_i = 1.82 mm, from t = 0.3 s",
        sets: &["model.layers=20", "initial.erodible_bed=1.82e-3"],
        t0: 0.3,
        steps: 200,
    },
    Case {
        name: "collapse 22°, 640 cells (the grid of Garres-Díaz et al. 2021), from t = 0.3 s",
        sets: &[],
        t0: 0.3,
        steps: 800,
    },
    Case {
        name: "same on a 1 cm erodible bed (every cell wet), 640 cells",
        sets: &["initial.erodible_bed=0.01"],
        t0: 0.3,
        steps: 800,
    },
    Case {
        name: "same, every cell wet, 64 000 cells",
        sets: &["initial.erodible_bed=0.01", "domain.cells=64000"],
        t0: 0.002,
        steps: 400,
    },
];

fn build(case: &Case, pressure: &str) -> Sim {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let mut sets: Vec<String> = case.sets.iter().map(|s| s.to_string()).collect();
    sets.push(format!("model.pressure={pressure}"));
    sets.push("time.stop_at_rest=false".into());
    let scn = load_file(&path, &sets).expect("scenario");
    build_granular(&scn)
}

/// A run advanced to the case's `t0`.
fn warmed_up(case: &Case, pressure: &str) -> Sim {
    let mut sim = build(case, pressure);
    while sim.t < case.t0 {
        let dt = sim.step(case.t0 - sim.t).expect("step");
        sim.t += dt;
    }
    sim
}

/// Wall time per step of `steps` steps.
fn burst(sim: &mut Sim, steps: usize) -> f64 {
    let start = Instant::now();
    for _ in 0..steps {
        let dt = sim.step(f64::INFINITY).expect("step");
        sim.t += dt;
    }
    start.elapsed().as_secs_f64() / steps as f64
}

/// Per model: best time per step over `bursts` bursts and the mean stage times. The
/// models take turns, burst by burst, so that a busy moment of the machine hits both
/// alike; the minimum keeps the least disturbed burst.
fn time_models(case: &Case, models: &[&str], bursts: usize) -> Vec<(f64, Vec<(String, f64)>)> {
    let mut sims: Vec<Sim> = models.iter().map(|m| warmed_up(case, m)).collect();
    let before: Vec<_> = sims.iter().map(|s| s.stage_times()).collect();
    let per_burst = (case.steps / bursts).max(1);
    let mut best = vec![f64::INFINITY; models.len()];
    for _ in 0..bursts {
        for (sim, best) in sims.iter_mut().zip(&mut best) {
            *best = best.min(burst(sim, per_burst));
        }
    }
    let n = (per_burst * bursts) as f64;
    sims.iter()
        .zip(before)
        .zip(best)
        .map(|((sim, before), best)| {
            let stages = sim
                .stage_times()
                .into_iter()
                .zip(before)
                .map(|((name, t), (_, t0))| (name, (t - t0) / n))
                .collect();
            (best, stages)
        })
        .collect()
}

fn micros(s: f64) -> String {
    format!("{:.2} µs", s * 1e6)
}

fn stages(list: &[(String, f64)]) -> String {
    list.iter()
        .map(|(name, t)| format!("{name} {}", micros(*t)))
        .collect::<Vec<_>>()
        .join(", ")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let hydrostatic_only = args.iter().any(|a| a == "--hydrostatic-only");
    let multilayer_only = args.iter().any(|a| a == "--multilayer-only");
    let cases: Vec<&Case> = CASES
        .iter()
        .filter(|c| !multilayer_only || c.sets.iter().any(|s| s.starts_with("model.layers")))
        .collect();
    let bursts = if quick { 5 } else { 40 };
    if hydrostatic_only {
        println!("| case | hydrostatic step |");
        println!("|---|---|");
        for case in cases.iter().copied() {
            let (h, _) = time_models(case, &["hydrostatic"], bursts).remove(0);
            println!("| {} | {} |", case.name, micros(h));
        }
        return;
    }
    println!("| case | hydrostatic step | non-hydrostatic step | NH/H |");
    println!("|---|---|---|---|");
    let mut breakdown = Vec::new();
    for case in cases.iter().copied() {
        let mut t = time_models(case, &["hydrostatic", "nonhydrostatic"], bursts);
        let (nh, h) = (t.pop().unwrap(), t.pop().unwrap());
        println!(
            "| {} | {} | {} | {:.2}× |",
            case.name,
            micros(h.0),
            micros(nh.0),
            nh.0 / h.0
        );
        breakdown.push((case.name, h.1, nh.1));
    }
    println!("\nMean stage times per step (wall clock, same runs):\n");
    for (name, h, nh) in breakdown {
        println!(
            "- {name}: hydrostatic {}; non-hydrostatic {}",
            stages(&h),
            stages(&nh)
        );
    }
}
