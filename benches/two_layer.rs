//! Benchmarks of the two-layer submarine-avalanche kernels (seed 004; nothing is
//! asserted):
//!
//!   cargo bench --bench two_layer
//!
//! 1. Seed 004 §5.3: the 30 km tsunami, 500 cells, CFL 0.8, δ₀ = 12°, to 600 s (the
//!    issue's target: under 0.1 s), best of 5.
//! 2. Cost of one two-layer step per cell against one monolayer (hydrostatic Coulomb)
//!    step per cell, both whole steps (CFL + stages) on 2000 cells (target ≤ 2.5×).

use std::path::Path;
use std::time::Instant;

use granflow::numerics::two_layer::{TwoLayerGeometry, TwoLayerSolver, TwoLayerState};
use granflow::output::memory::MemorySink;
use granflow::physics::two_layer::TwoLayerParams;
use granflow::scenario::{load_file, BoundaryKind};
use granflow::setup::build_granular;

/// Seed 004 §5.3: water depth H(x) over the bed b = 2500 − H.
fn depth(x: f64) -> f64 {
    if x <= 10_000.0 {
        10.0 + 490.0 * (-6.1429e-4 * (10_000.0 - x)).exp()
    } else {
        2500.0 - 2000.0 * (-1.5050e-4 * (x - 10_000.0)).exp()
    }
}

fn tsunami(nx: usize) -> (TwoLayerGeometry, TwoLayerState) {
    let dx = 30_000.0 / nx as f64;
    let bed: Vec<f64> = (0..nx)
        .map(|i| 2500.0 - depth((i as f64 + 0.5) * dx))
        .collect();
    let g = TwoLayerGeometry::new(0.0, dx, &bed, BoundaryKind::Outflow, BoundaryKind::Outflow);
    let mut s = TwoLayerState::zeros(nx);
    for i in 1..=nx {
        let x = g.x(i);
        let slide = (depth(x) - (500.0 + (x - 10_000.0).powi(2) / 1.8e4)).max(0.0);
        s.h2[i] = slide / g.cos2[i];
        s.h1[i] = depth(x) / g.cos2[i] - s.h2[i];
    }
    (g, s)
}

/// Runs to `t_end`; returns (wall seconds, steps).
fn run(g: &TwoLayerGeometry, s0: &TwoLayerState, delta0: f64, t_end: f64) -> (f64, u64) {
    let mut s = s0.clone();
    let mut solver = TwoLayerSolver::new(TwoLayerParams::isotropic(0.2, delta0), 0.8, g.nx);
    let start = Instant::now();
    let (mut t, mut steps) = (0.0, 0u64);
    while t < t_end {
        t += solver.step(g, &mut s, t_end - t);
        steps += 1;
    }
    (start.elapsed().as_secs_f64(), steps)
}

fn main() {
    let (g, s0) = tsunami(500);
    let best = (0..5)
        .map(|_| run(&g, &s0, 12.0, 600.0))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    println!(
        "tsunami 30 km, 500 cells, 600 s: {} steps in {:.4} s ({:.1} ns per cell step)",
        best.1,
        best.0,
        best.0 / (best.1 as f64 * 500.0) * 1e9
    );

    // Per-cell step cost, 2000 cells: the tsunami refined vs the monolayer collapse.
    let n = 2000;
    let (g, s0) = tsunami(n);
    let (wall, steps) = (0..3)
        .map(|_| run(&g, &s0, 12.0, 60.0))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    let two_layer = wall / (steps as f64 * n as f64) * 1e9;

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let overrides: Vec<String> = [
        format!("domain.cells={n}"),
        "time.t_end=0.3".into(),
        "time.stop_at_rest=false".into(),
        "output.every=0.3".into(),
    ]
    .into();
    let scn = load_file(&path, &overrides).expect("valid scenario");
    let mono = (0..3)
        .map(|_| {
            let mut sim = build_granular(&scn);
            let mut sink = MemorySink::default();
            let start = Instant::now();
            let summary = sim.run(&mut sink, &mut |_| {}).unwrap();
            start.elapsed().as_secs_f64() / (summary.steps as f64 * n as f64) * 1e9
        })
        .fold(f64::INFINITY, f64::min);
    println!(
        "per cell step at {n} cells: two-layer {two_layer:.1} ns, monolayer (collapse.toml, whole run) {mono:.1} ns, ratio {:.2}",
        two_layer / mono
    );
}
