//! Benchmarks of the 2-D Savage–Hutter solver on a raster (not tests: nothing is
//! asserted).
//!
//!   cargo bench --bench terrain_2d
//!
//! 1. Cell updates per second of the 2-D hydrostatic step (step 1) and of the friction
//!    step, one thread, at 256² and 1024² cells: a Coulomb cone (μ = tan 24°) on a
//!    30° plane in local coordinates, half the raster wet, fixed Δt (CFL ≈ 0.4).
//! 2. Thread speed-up at 1024² cells, 1, 2 and 4 threads: of the stages alone, and of
//!    a run's step (the run loop's copy of the state of t^n, the stages, the
//!    diagnostics and the maps tracker, each timed).
//! 3. Memory per cell: the state and the run loop's backup, the raster, the step's
//!    scratch.
//! 4. The maps tracker (largest thickness and speed, arrival time, area reached; the
//!    peak pressure is formed only when the maps are written) on the run's pool, 1 and
//!    2 threads: its share of a run's step, and the cost of forming the maps for a
//!    snapshot.

use std::time::Instant;

use granflow::grid::{BoundaryKind, Coordinates, Raster2d, RasterSpec, Sides};
use granflow::model::granular_2d::{self, Granular2d};
use granflow::model::raster_maps::RasterMaps;
use granflow::model::tracker::Tracker;
use granflow::model::Model;
use granflow::numerics::hydrostatic_2d::HydrostaticStep2d;
use granflow::numerics::workers::Workers;
use granflow::numerics::{Stage, StepClock};
use granflow::output::memory::MemorySink;
use granflow::physics::rheology::{Coulomb, FrictionLaw};
use granflow::physics::Material;
use granflow::state::State2d;

fn setup(n: usize) -> (Raster2d, State2d) {
    let spec = RasterSpec {
        nx: n,
        ny: n,
        x_min: 0.0,
        x_max: 4.0,
        y_min: -2.0,
        y_max: 2.0,
        sides: Sides::all(BoundaryKind::Outflow),
        coordinates: Coordinates::Local,
        slope_deg: 30.0,
    };
    let bed = (0..n * n)
        .map(|k| 0.05 * (2.0 * spec.x(k % n)).sin() * spec.y(k / n).cos())
        .collect();
    let r = Raster2d::new(spec, bed).unwrap();
    let h: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = (r.x(k % n) - 1.5, r.y(k / n));
            (0.5 - 0.3 * (x * x + y * y).sqrt()).max(0.0)
        })
        .collect();
    let zeros = vec![0.0; n * n];
    (r, State2d::from_velocities(h, &zeros, &zeros))
}

fn dt(r: &Raster2d) -> f64 {
    // Signal speed ≈ √(g 0.5) + 1 m/s.
    0.4 * r.dx() / ((9.81f64 * 0.5).sqrt() + 1.0)
}

/// Step `k` of Δt = [`dt`].
fn step_clock(r: &Raster2d, k: usize) -> StepClock {
    StepClock::at(k as f64 * dt(r), dt(r))
}

/// Seconds per step of `stage` (best of three blocks of `steps` steps from a state
/// that has flowed 10 steps).
fn time_stage(
    stage: &mut dyn Stage<Raster2d, State2d>,
    r: &Raster2d,
    s0: &State2d,
    steps: usize,
) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let mut s = s0.clone();
        let start = Instant::now();
        for k in 0..steps {
            stage.apply(r, step_clock(r, k), &mut s).unwrap();
        }
        best = best.min(start.elapsed().as_secs_f64() / steps as f64);
    }
    best
}

/// Seconds per step of the parts of a run's step (best of three blocks).
#[derive(Debug, Clone, Copy)]
struct RunStep {
    copy: f64,
    stages: f64,
    diagnostics: f64,
    maps: f64,
}

impl RunStep {
    fn total(&self) -> f64 {
        self.copy + self.stages + self.diagnostics + self.maps
    }
}

/// Seconds per step of the stages alone (`Pipeline::advance`), and of each part of
/// the run loop's step on `threads` threads: the copy of the state of t^n, the stages,
/// the diagnostics (a pass over the cells: mass, energy, signal speed, front) and the
/// maps tracker (best of three blocks of `steps` steps each).
fn time_run_step(
    friction: &FrictionLaw,
    material: &Material,
    r: &Raster2d,
    s0: &State2d,
    threads: usize,
    steps: usize,
) -> (f64, RunStep) {
    let workers = Workers::new(threads).unwrap();
    let mut pipe = granular_2d::pipeline_on(friction, material, r, workers.clone());
    let model = Granular2d::new(r, 1e-3).with_workers(workers.clone());
    let mut stages_only = f64::INFINITY;
    let mut best = RunStep {
        copy: f64::INFINITY,
        stages: f64::INFINITY,
        diagnostics: f64::INFINITY,
        maps: f64::INFINITY,
    };
    for _ in 0..3 {
        let mut s = s0.clone();
        let start = Instant::now();
        for k in 0..steps {
            pipe.advance(r, step_clock(r, k), &mut s).unwrap();
        }
        stages_only = stages_only.min(start.elapsed().as_secs_f64() / steps as f64);
        let mut s = s0.clone();
        let mut backup = s0.clone();
        let mut maps = RasterMaps::new(s.h.len(), 1e-3, 1550.0).with_workers(workers.clone());
        maps.observe(r, &s, 0.0);
        let mut t = [0.0; 4];
        for k in 0..steps {
            let clock = Instant::now();
            model.save_state(&mut backup, &s);
            t[0] += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            pipe.advance(r, step_clock(r, k), &mut s).unwrap();
            t[1] += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            let d = model.diagnose(r, &s);
            t[2] += clock.elapsed().as_secs_f64();
            assert!(d.mass > 0.0);
            let clock = Instant::now();
            maps.observe(r, &s, (k + 1) as f64 * dt(r));
            t[3] += clock.elapsed().as_secs_f64();
        }
        let n = steps as f64;
        best.copy = best.copy.min(t[0] / n);
        best.stages = best.stages.min(t[1] / n);
        best.diagnostics = best.diagnostics.min(t[2] / n);
        best.maps = best.maps.min(t[3] / n);
    }
    (stages_only, best)
}

fn main() {
    let law = Coulomb {
        mu: 24f64.to_radians().tan(),
    };
    let material = Material {
        rho_s: 2500.0,
        phi: 0.62,
        d_s: 0.7e-3,
    };
    let friction = FrictionLaw::Coulomb { mu: law.mu };
    println!("1. Single thread, cell updates per second");
    for n in [256, 1024] {
        let (r, mut s) = setup(n);
        let mut pipe = granular_2d::pipeline(&friction, &material, &r, 1).unwrap();
        for k in 0..10 {
            pipe.advance(&r, step_clock(&r, k), &mut s).unwrap();
        }
        let steps = if n > 512 { 10 } else { 100 };
        let mut step1 = HydrostaticStep2d::new(law, &r, Workers::serial());
        let t1 = time_stage(&mut step1, &r, &s, steps);
        let mut fr = granflow::numerics::friction_2d::FrictionStep2d::new(law, Workers::serial());
        let t2 = time_stage(&mut fr, &r, &s, steps);
        let cells = (n * n) as f64;
        println!(
            "  {n}²: hyperbolic {:.3e} cell updates/s ({:.1} ns/cell), friction {:.3e} cell updates/s",
            cells / t1,
            1e9 * t1 / cells,
            cells / t2
        );
        if n == 1024 {
            let scratch = step1.bytes_per_cell();
            // State + backup (2 × 3 values), raster (x, y, b, bed and potential with
            // the ghost ring: 5 values).
            let total = 6.0 * 8.0 + 5.0 * 8.0 + scratch;
            println!(
                "3. Memory per cell at 1024²: state and backup 48 B, raster 40 B, step scratch {scratch:.1} B: {total:.1} B"
            );
        }
    }
    println!("2. Thread speed-up at 1024² cells: the stages, and a run's step");
    let (r, s0) = setup(1024);
    let mut base = (0.0, 0.0);
    for threads in [1, 2, 4] {
        let (stages, run) = time_run_step(&friction, &material, &r, &s0, threads, 10);
        if threads == 1 {
            base = (stages, run.total());
        }
        println!(
            "  {threads} thread(s): stages {:.1} ms/step (speed-up {:.2}); run step {:.1} ms (speed-up {:.2}: copy of t^n {:.1}, stages {:.1}, diagnostics {:.1}, maps {:.1})",
            1e3 * stages,
            base.0 / stages,
            1e3 * run.total(),
            base.1 / run.total(),
            1e3 * run.copy,
            1e3 * run.stages,
            1e3 * run.diagnostics,
            1e3 * run.maps,
        );
    }
    println!("4. The maps tracker on the run's pool: its share of a run's step, 1 and 2 threads");
    for (n, threads) in [(256, 1), (1024, 1), (256, 2), (1024, 2)] {
        let (r, mut s) = setup(n);
        let steps = if n > 512 { 10 } else { 50 };
        let (_, run) = time_run_step(&friction, &material, &r, &s, threads, steps);
        let workers = Workers::new(threads).unwrap();
        let mut pipe = granular_2d::pipeline_on(&friction, &material, &r, workers.clone());
        let mut maps = RasterMaps::new(n * n, 1e-3, 1550.0).with_workers(workers);
        maps.observe(&r, &s, 0.0);
        for k in 0..steps {
            pipe.advance(&r, step_clock(&r, k), &mut s).unwrap();
            maps.observe(&r, &s, (k + 1) as f64 * dt(&r));
        }
        let mut t_write = f64::INFINITY;
        for _ in 0..3 {
            let mut sink = MemorySink::default();
            let start = Instant::now();
            maps.write_so_far(&r, &s, &mut sink).unwrap();
            t_write = t_write.min(start.elapsed().as_secs_f64());
        }
        println!(
            "  {n}², {threads} thread(s): run step {:.2} ms, tracker {:.3} ms per step ({:.2} % of the run step), maps formed for a snapshot in {:.2} ms",
            1e3 * run.total(),
            1e3 * run.maps,
            100.0 * run.maps / run.total(),
            1e3 * t_write
        );
    }
}
