//! Benchmarks of the submarine model's non-hydrostatic water (`numerics::water_nh`;
//! nothing is asserted):
//!
//!   cargo bench --bench water_nh
//!
//! 1. The 30 km tsunami of Fernández-Nieto et al. 2008, §5.3 (`scenarios/tsunami_30km.toml`, 500
//!    cells, to 600 s) with hydrostatic water and with M = 1, 2, 3 non-hydrostatic
//!    water layers: the whole simulation (CFL, stages, diagnostics, in-memory output),
//!    best of 5 (the target with M = 2: under 1 s).
//! 2. The cost of one step with M water layers against one hydrostatic two-layer step
//!    on the same grid (the tsunami's, target ≤ 3× with M = 2): interleaved bursts of
//!    `STEPS` whole steps (`Simulation::step`) from t = 60 s, best of `BURSTS` each, in
//!    wall time and in the CPU time of the thread (Linux: `CLOCK_THREAD_CPUTIME_ID`;
//!    on a machine shared with other jobs the CPU time is the figure to compare).
//!
//! Instruction counts (repeatable on a loaded machine): the binary also runs one case
//! alone, `water_nh --layers M --steps N` (M = 0: hydrostatic), with the steps inside
//! `run_steps`, so that
//! `valgrind --tool=callgrind --toggle-collect='*run_steps*' BINARY --layers 2 --steps 500`
//! counts the steps only (the bench binary: `cargo bench --bench water_nh --no-run`).

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use granflow::model::submarine::Submarine;
use granflow::output::memory::MemorySink;
use granflow::scenario::load_file;
use granflow::setup::build_submarine;
use granflow::simulation::Simulation;

const STEPS: usize = 200;
const BURSTS: usize = 7;

/// CPU time of the calling thread in seconds (Linux; `None` elsewhere).
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn thread_cpu_time() -> Option<f64> {
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to write.
    let ok = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0;
    ok.then_some(t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64)
}

#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn thread_cpu_time() -> Option<f64> {
    None
}

/// The tsunami with `layers` non-hydrostatic water layers (0: hydrostatic).
fn tsunami(layers: usize) -> Simulation<Submarine> {
    let mut sets = vec!["output.file=\"bench_water_nh.h5\"".to_string()];
    if layers > 0 {
        sets.push("submarine.water_pressure=\"nonhydrostatic\"".into());
        sets.push(format!("submarine.water_layers={layers}"));
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scn = load_file(&root.join("scenarios/tsunami_30km.toml"), &sets).expect("scenario");
    build_submarine(&scn)
}

#[inline(never)]
fn run_steps(sim: &mut Simulation<Submarine>, n: usize) {
    for _ in 0..n {
        black_box(sim.step(f64::INFINITY).expect("step"));
    }
}

/// The tsunami after its first 60 s (the slide moving, the waves out).
fn warm(layers: usize) -> Simulation<Submarine> {
    let mut sim = tsunami(layers);
    let mut t = 0.0;
    while t < 60.0 {
        t += sim.step(f64::INFINITY).expect("step");
    }
    sim
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .map(|v| v.parse::<usize>().expect("a number"))
    };
    if let (Some(layers), Some(steps)) = (value("--layers"), value("--steps")) {
        let mut sim = warm(layers);
        run_steps(&mut sim, steps);
        return;
    }
    println!("30 km tsunami (500 cells, 600 s), whole simulation, best of 5:");
    for layers in [0, 1, 2, 3] {
        let (mut best, mut best_cpu) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..5 {
            let mut sim = tsunami(layers);
            let mut sink = MemorySink::default();
            let (t0, c0) = (Instant::now(), thread_cpu_time());
            sim.run(&mut sink, &mut |_| {}).expect("run");
            best = best.min(t0.elapsed().as_secs_f64());
            if let (Some(c0), Some(c1)) = (c0, thread_cpu_time()) {
                best_cpu = best_cpu.min(c1 - c0);
            }
        }
        let name = if layers == 0 {
            "hydrostatic".to_string()
        } else {
            format!("M = {layers}")
        };
        if best_cpu.is_finite() {
            println!("  {name:12} wall {best:.3} s, CPU {best_cpu:.3} s");
        } else {
            println!("  {name:12} wall {best:.3} s");
        }
    }
    println!(
        "one step against a hydrostatic step ({STEPS} steps from t = 60 s, best of {BURSTS}):"
    );
    let mut sims: Vec<_> = [0, 1, 2, 3].iter().map(|&m| warm(m)).collect();
    let mut best = [f64::INFINITY; 4];
    let mut best_cpu = [f64::INFINITY; 4];
    for _ in 0..BURSTS {
        for ((sim, best), best_cpu) in sims.iter_mut().zip(&mut best).zip(&mut best_cpu) {
            let (t0, c0) = (Instant::now(), thread_cpu_time());
            run_steps(sim, STEPS);
            *best = best.min(t0.elapsed().as_secs_f64() / STEPS as f64);
            if let (Some(c0), Some(c1)) = (c0, thread_cpu_time()) {
                *best_cpu = best_cpu.min((c1 - c0) / STEPS as f64);
            }
        }
    }
    for m in 0..4 {
        let name = if m == 0 {
            "hydrostatic".to_string()
        } else {
            format!("M = {m}")
        };
        let (b, c) = (best[m], best_cpu[m]);
        print!(
            "  {name:12} wall {:.2} µs/step ({:.2}× hydrostatic)",
            b * 1e6,
            b / best[0]
        );
        if c.is_finite() {
            print!(", CPU {:.2} µs/step ({:.2}×)", c * 1e6, c / best_cpu[0]);
        }
        println!();
    }
}
