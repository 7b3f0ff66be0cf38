//! Cost and memory per cell of the N-layer raster step (`numerics/layers_2d.rs`,
//! `numerics/viscous_2d.rs`) against the monolayer's hyperbolic step
//! (`numerics/hydrostatic_2d.rs`), docs/numerics.md ("Layers on a raster"):
//!
//!   cargo run --release --example layers_2d_cost -- 96 20
//!
//! Arguments: `n` (n × n cells), `steps`. The set-up: a layer 5 cm thick on a 30°
//! plane in the local frame over the bed 0.01 sin(3x) cos(2y), flowing at 1 m/s down
//! the plane with a sheared profile (layer α at (0.5 + α/N) m/s), μ(I) (the bench law
//! of `tests/multilayer_2d.rs`), every cell wet so that every tile of the monolayer is
//! stepped; outflow on every side; Δt = 1e-4 s fixed. Each step is timed alone by the
//! calling thread's CPU time (one thread), the best of three passes. Printed per N:
//! the hyperbolic step's CPU time per cell, its ratio to N × the monolayer's, the
//! viscous columns' time per cell, and the bytes per cell of the state and the steps.
use granflow::grid::{BoundaryKind, Coordinates, Raster2d, RasterSpec, Sides};
use granflow::numerics::hydrostatic_2d::HydrostaticStep2d;
use granflow::numerics::layers_2d::LayersStep2d;
use granflow::numerics::viscous::{BasalCondition, Regularization, ViscosityTime, ViscousOptions};
use granflow::numerics::viscous_2d::ViscousColumns2d;
use granflow::numerics::workers::Workers;
use granflow::numerics::{Stage, StepClock};
use granflow::physics::rheology::{MonolayerShear, MuI};
use granflow::state::layered_raster::LayeredRaster;
use granflow::state::State2d;

/// CPU time of the calling thread in seconds (Linux).
fn thread_cpu_time() -> f64 {
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
    unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}

/// The best of three passes of `steps` calls of `f`, in CPU seconds per call.
fn best_of_three(steps: usize, mut f: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let t0 = thread_cpu_time();
            for _ in 0..steps {
                f();
            }
            (thread_cpu_time() - t0) / steps as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(96);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    let spec = RasterSpec {
        nx: n,
        ny: n,
        x_min: 0.0,
        x_max: 2.0,
        y_min: 0.0,
        y_max: 2.0,
        sides: Sides::all(BoundaryKind::Outflow),
        coordinates: Coordinates::Local,
        slope_deg: 30.0,
    };
    let bed = (0..n * n)
        .map(|k| 0.01 * (3.0 * spec.x(k % n)).sin() * (2.0 * spec.y(k / n)).cos())
        .collect();
    let raster = Raster2d::new(spec, bed).unwrap();
    let law = MuI {
        mu_s: 20.9f64.to_radians().tan(),
        mu_2: 32.76f64.to_radians().tan(),
        i0: 0.279,
        d_s: 0.7e-3,
        phi: 0.62,
        shear: MonolayerShear::Bagnold,
    };
    let cells = (n * n) as f64;
    // One step of 0.1 ms from the initial state, repeated.
    let clock = StepClock::at(0.0, 1e-4);
    let h = vec![0.05; n * n];

    let mut mono = HydrostaticStep2d::new(law, &raster, Workers::serial());
    let mut state = State2d::from_velocities(h.clone(), &vec![1.0; n * n], &vec![0.2; n * n]);
    let initial = state.clone();
    let mono_time = best_of_three(steps, || {
        state.clone_from(&initial);
        state.touch();
        mono.apply(&raster, clock, &mut state).unwrap();
    }) / cells;
    let mono_bytes = 24.0 + mono.bytes_per_cell();
    println!("{n} × {n} cells, {steps} steps, one thread");
    println!(
        "monolayer hyperbolic (hydrostatic_2d): {:.1} ns/cell, {mono_bytes:.0} B/cell (state + step)",
        1e9 * mono_time
    );
    println!(
        "N, hyperbolic ns/cell, ratio to N × monolayer, viscous ns/cell, B/cell (state + steps)"
    );
    for layers in [1, 2, 4, 10, 20] {
        let l = vec![1.0 / layers as f64; layers];
        let zeros = vec![0.0; n * n];
        let mut initial = LayeredRaster::from_velocities((n, n), &l, h.clone(), &zeros, &zeros);
        for k in 0..n * n {
            for a in 0..layers {
                initial.hu[k * layers + a] = 0.05 * (0.5 + a as f64 / layers as f64);
                initial.hv[k * layers + a] = 0.05 * 0.2;
            }
        }
        let mut state = initial.clone();
        let mut step = LayersStep2d::new(law, &raster, &l, Workers::serial());
        let hyp = best_of_three(steps, || {
            state.clone_from(&initial);
            step.apply(&raster, clock, &mut state).unwrap();
        }) / cells;
        let mut bytes = 8.0 * (1 + 2 * layers) as f64 + step.bytes_per_cell();
        let visc = if layers > 1 {
            let opts = ViscousOptions {
                basal: BasalCondition::Coulomb,
                regularization: Regularization::Bound,
                sidewall: None,
                c_msm: false,
                viscosity: ViscosityTime::Frozen,
            };
            let mut visc = ViscousColumns2d::new(law, &raster, &l, opts, Workers::serial());
            bytes += visc.bytes_per_cell();
            best_of_three(steps, || {
                state.clone_from(&initial);
                visc.prepare(&raster, clock, &state);
                visc.apply(&raster, clock, &mut state).unwrap();
            }) / cells
        } else {
            0.0
        };
        println!(
            "{layers:3} {:8.1} {:6.2} {:8.1} {bytes:8.0}",
            1e9 * hyp,
            hyp / (layers as f64 * mono_time),
            1e9 * visc
        );
    }
}
