//! Benchmarks of the two-layer submarine-avalanche model (Fernández-Nieto et al. 2008; nothing is
//! asserted):
//!
//!   cargo bench --bench two_layer
//!
//! 1. Fernández-Nieto et al. 2008, §5.3: the 30 km tsunami, 500 cells, CFL 0.8, δ₀ = 12°, to 600 s (the
//!    target: under 0.1 s), kernels only ([`TwoLayerSolver::step`]) and the
//!    whole simulation (CFL, stages, diagnostics, in-memory output), best of 5.
//! 2. Cost of one two-layer step per cell against one monolayer Savage–Hutter Coulomb
//!    step per cell (target ≤ 2.5×), both whole steps through `Simulation::step`
//!    (signal speed and diagnostics, hyperbolic stage, Coulomb friction), on the same
//!    grid of 2000 cells with the same grains:
//!    - `wet`: a 10 m channel with the bed b = 0.2 x of §5.1, grains of vertical
//!      thickness 0.3 + 0.2 exp(−(x − 5)²) everywhere, δ₀ = 10° (below the slope's
//!      11.31°: they slide the whole time); the two-layer run has water up to η = 4
//!      over them, so both layers are present in every cell;
//!    - `partly_dry`: the tsunami of §5.3 on 2000 cells: grains on a fifth of the
//!      domain, water everywhere; the monolayer run has the same grains, no water.
//!
//!    Interleaved bursts of `STEPS` steps after a warm-up, best of `BURSTS` each.
//!
//! Instruction counts (repeatable on a loaded machine): the binary also runs one case
//! alone, `two_layer --case wet|partly_dry --model two|mono --steps N`, with the steps
//! inside `run_steps`, so that
//! `valgrind --tool=callgrind --toggle-collect='*run_steps*' BINARY --case …` counts
//! the steps only (the bench binary: `cargo bench --bench two_layer --no-run`).

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use granflow::grid::line::cell_centre;
use granflow::grid::{CurvedLine, Line};
use granflow::model::Model;
use granflow::numerics::two_layer::TwoLayerSolver;
use granflow::output::memory::MemorySink;
use granflow::physics::two_layer::TwoLayerParams;
use granflow::scenario::{load_file, load_str, BoundaryKind, Scenario};
use granflow::setup::{build_granular, build_submarine};
use granflow::simulation::Simulation;
use granflow::state::TwoLayerState;

const CELLS: usize = 2000;
const STEPS: usize = 200;
const BURSTS: usize = 7;

/// Fernández-Nieto et al. 2008, §5.3: water depth H(x) over the bed b = 2500 − H.
fn depth(x: f64) -> f64 {
    if x <= 10_000.0 {
        10.0 + 490.0 * (-6.1429e-4 * (10_000.0 - x)).exp()
    } else {
        2500.0 - 2000.0 * (-1.5050e-4 * (x - 10_000.0)).exp()
    }
}

fn tsunami(nx: usize) -> (CurvedLine, TwoLayerState) {
    let dx = 30_000.0 / nx as f64;
    let bed: Vec<f64> = (0..nx)
        .map(|i| 2500.0 - depth(cell_centre(0.0, dx, i)))
        .collect();
    let free = BoundaryKind::Outflow;
    let g = CurvedLine::new(Line::cartesian(0.0, dx, &bed, free, free));
    let mut s = TwoLayerState::zeros(nx);
    for i in 1..=nx {
        let x = g.x(i);
        let slide = (depth(x) - (500.0 + (x - 10_000.0).powi(2) / 1.8e4)).max(0.0);
        s.h2[i] = slide / g.cos2[i];
        s.h1[i] = depth(x) / g.cos2[i] - s.h2[i];
    }
    (g, s)
}

/// Kernels only: runs to `t_end`; returns (wall seconds, steps).
fn run_kernels(g: &CurvedLine, s0: &TwoLayerState, t_end: f64) -> (f64, u64) {
    let mut s = s0.clone();
    let mut solver = TwoLayerSolver::new(TwoLayerParams::isotropic(0.2, 12.0), 0.8, g.line.nx);
    let start = Instant::now();
    let (mut t, mut steps) = (0.0, 0u64);
    while t < t_end {
        t += solver.step(g, &mut s, t_end - t);
        steps += 1;
    }
    (start.elapsed().as_secs_f64(), steps)
}

fn scenario_path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

const WET: &str = r#"
[domain]
x_min = 0.0
x_max = 10.0
cells = 2000
coordinates = "cartesian"

[bed]
b = "0.2 * x"

[rheology]
law = "coulomb"
mu_deg = 10.0

[model]
kind = "submarine"

[submarine]
r = 0.2

[initial]
h = "0.3 + 0.2 * exp(-(x - 5)^2)"
eta = 4.0

[boundary]
left = "outflow"
right = "outflow"

[time]
t_end = 100.0
cfl = 0.8
stop_at_rest = false

[output]
every = 100.0
"#;

/// The scenario of a comparison case, for the two-layer model or, without the water,
/// for the monolayer granular model.
fn case(name: &str, two_layer: bool) -> Scenario {
    let text = match name {
        "wet" => WET.to_string(),
        "partly_dry" => std::fs::read_to_string(scenario_path("tsunami_30km.toml"))
            .expect("bundled scenario")
            .replace("cells = 500", &format!("cells = {CELLS}")),
        _ => panic!("unknown case {name} (wet, partly_dry)"),
    };
    let text = if two_layer {
        text
    } else {
        text.replace("kind = \"submarine\"", "kind = \"granular\"")
            .replace("[submarine]\nr = 0.2\n", "")
            .lines()
            .filter(|l| !l.starts_with("eta ="))
            .collect::<Vec<_>>()
            .join("\n")
    };
    let scn = load_str(&text, &scenario_path(""), &[]).expect("valid scenario");
    assert_eq!(scn.domain.cells, CELLS);
    scn
}

/// `n` whole steps (CFL from the diagnostics of the state, stages): what callgrind's
/// `--toggle-collect='*run_steps*'` counts.
#[inline(never)]
fn run_steps<M: Model>(sim: &mut Simulation<M>, n: usize) {
    for _ in 0..n {
        black_box(sim.step(f64::INFINITY).expect("step"));
    }
}

/// A simulation of the case after `warm` steps.
enum Sim {
    Two(Box<Simulation<granflow::model::submarine::Submarine>>),
    Mono(Box<Simulation<granflow::model::granular::Granular>>),
}

impl Sim {
    fn new(name: &str, two_layer: bool) -> Sim {
        let scn = case(name, two_layer);
        if two_layer {
            Sim::Two(Box::new(build_submarine(&scn)))
        } else {
            Sim::Mono(Box::new(build_granular(&scn)))
        }
    }

    fn steps(&mut self, n: usize) {
        match self {
            Sim::Two(s) => run_steps(s, n),
            Sim::Mono(s) => run_steps(s, n),
        }
    }

    /// ns per cell step of a burst of `n` steps.
    fn burst(&mut self, n: usize) -> f64 {
        let start = Instant::now();
        self.steps(n);
        start.elapsed().as_secs_f64() / (n * CELLS) as f64 * 1e9
    }
}

fn compare(name: &str) {
    let mut two = Sim::new(name, true);
    let mut mono = Sim::new(name, false);
    two.steps(20);
    mono.steps(20);
    let (mut best_two, mut best_mono) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..BURSTS {
        best_two = best_two.min(two.burst(STEPS));
        best_mono = best_mono.min(mono.burst(STEPS));
    }
    println!(
        "{name:<10} {CELLS} cells: two-layer {best_two:.1} ns, monolayer {best_mono:.1} ns per cell step (best of {BURSTS} bursts of {STEPS}); ratio {:.2}",
        best_two / best_mono
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |key: &str| {
        args.iter()
            .position(|a| a == key)
            .map(|i| args[i + 1].clone())
    };
    if let Some(name) = value("--case") {
        // One case alone, for callgrind.
        let two_layer = match value("--model").as_deref() {
            Some("two") => true,
            Some("mono") => false,
            m => panic!("--model two|mono, not {m:?}"),
        };
        let steps: usize = value("--steps").map_or(STEPS, |s| s.parse().expect("--steps N"));
        let mut sim = Sim::new(&name, two_layer);
        sim.steps(20);
        sim.steps(steps);
        return;
    }

    let (g, s0) = tsunami(500);
    let best = (0..5)
        .map(|_| run_kernels(&g, &s0, 600.0))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    println!(
        "tsunami 30 km, 500 cells, 600 s, kernels: {} steps in {:.4} s ({:.1} ns per cell step)",
        best.1,
        best.0,
        best.0 / (best.1 as f64 * 500.0) * 1e9
    );
    let scn = load_file(&scenario_path("tsunami_30km.toml"), &[]).expect("valid scenario");
    let (wall, steps) = (0..5)
        .map(|_| {
            let mut sim = build_submarine(&scn);
            let mut sink = MemorySink::default();
            let start = Instant::now();
            let summary = sim.run(&mut sink, &mut |_| {}).unwrap();
            (start.elapsed().as_secs_f64(), summary.steps)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    println!("tsunami 30 km, whole simulation (in-memory output): {steps} steps in {wall:.4} s");

    compare("wet");
    compare("partly_dry");
}
