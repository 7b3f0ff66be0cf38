//! Driver for the cost per cell update of the 2-D hydrostatic step
//! (docs/performance.md, "2-D Savage–Hutter model on a raster"): `steps` steps of the
//! hyperbolic stage alone (no friction stage) from rest, Δt = CFL min(Δx, Δy)/s with
//! CFL = 0.5 and s the largest signal speed max(|u|, |v|) + √(g_n h) of the state.
//!
//!   cargo run --release --example hydrostatic_2d_cost -- 64 5
//!
//! Arguments: `n` (n × n cells), `steps`, the set-up, the number of threads (default 1)
//! and the stages (`hyperbolic`, the default, or `both`: the whole step of a run, the
//! hyperbolic and the friction stage of `model::granular_2d::pipeline`). The set-ups:
//! - `cartesian` (default): the side-by-side case with Basilisk's `saint-venant.h`
//!   (`benches/basilisk/saint_venant_cone.c`): Cartesian coordinates on
//!   [0, 4] × [−2, 2], the bed b = 0.05 sin(2x) cos(y), a cone of thickness
//!   max(0, 0.5 − 0.3 r) at rest around (2, 0) (about 55 % of the cells wet), no
//!   basal friction (μ = 0 in ΔC), outflow on every side;
//! - `local`: the set-up of `benches/terrain_2d.rs` (a Coulomb cone, μ = tan 24°, on a
//!   30° plane in local coordinates, whose fronts run the draining limiter);
//! - `bed_normal`: the same cone on the same wavy 30° plane given as a DEM (the plane
//!   in the bed, x horizontal), in the bed-normal frame.
//!
//! For instruction counts run it under `valgrind --tool=callgrind` with two step
//! counts and difference the totals. The last line is an FNV-1a hash of the final
//! state, to check that a change of the step keeps the results bit for bit.
use granflow::grid::{BoundaryKind, Coordinates, Raster2d, RasterSpec, Sides};
use granflow::model::granular_2d;
use granflow::numerics::hydrostatic_2d::HydrostaticStep2d;
use granflow::numerics::workers::Workers;
use granflow::numerics::{Stage, StepClock};
use granflow::physics::rheology::{Coulomb, FrictionLaw};
use granflow::physics::Material;
use granflow::state::State2d;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let bed_normal = args.get(3).is_some_and(|s| s == "bed_normal");
    let local = bed_normal || args.get(3).is_some_and(|s| s == "local");
    let threads: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1);
    let both = args.get(5).is_some_and(|s| s == "both");
    // The bench's cone touches the west edge; the side-by-side one is inside.
    let (x_min, y_min, centre) = (0.0, -2.0, if local { 1.5 } else { 2.0 });
    let spec = RasterSpec {
        nx: n,
        ny: n,
        x_min,
        x_max: x_min + 4.0,
        y_min,
        y_max: y_min + 4.0,
        sides: Sides::all(BoundaryKind::Outflow),
        coordinates: if bed_normal {
            Coordinates::BedNormal
        } else if local {
            Coordinates::Local
        } else {
            Coordinates::Cartesian
        },
        slope_deg: if local && !bed_normal { 30.0 } else { 0.0 },
    };
    let bed = (0..n * n)
        .map(|k| {
            let (x, y) = (spec.x(k % n), spec.y(k / n));
            let plane = if bed_normal {
                -x * 30f64.to_radians().tan()
            } else {
                0.0
            };
            0.05 * (2.0 * x).sin() * y.cos() + plane
        })
        .collect();
    let raster = Raster2d::new(spec, bed).expect("raster");
    let h: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = (raster.x(k % n) - centre, raster.y(k / n));
            (0.5 - 0.3 * (x * x + y * y).sqrt()).max(0.0)
        })
        .collect();
    let zeros = vec![0.0; n * n];
    let mut state = State2d::from_velocities(h, &zeros, &zeros);
    let mu = if local { 24f64.to_radians().tan() } else { 0.0 };
    let workers = Workers::new(if both { 1 } else { threads }).expect("threads");
    let mut hyperbolic = HydrostaticStep2d::new(Coulomb { mu }, &raster, workers);
    let material = Material {
        rho_s: 2500.0,
        phi: 0.62,
        d_s: 0.7e-3,
    };
    let mut pipeline = both.then(|| {
        granular_2d::pipeline(&FrictionLaw::Coulomb { mu }, &material, &raster, threads)
            .expect("threads")
    });
    let g_n = raster.g_n;
    let length = raster.dx().min(raster.dy());
    let mut t = 0.0;
    for _ in 0..steps {
        let mut signal = 0.0f64;
        for ((&h, &hu), &hv) in state.h.iter().zip(&state.hu).zip(&state.hv) {
            let (u, v) = if h > 1e-10 {
                (hu / h, hv / h)
            } else {
                (0.0, 0.0)
            };
            signal = signal.max(u.abs().max(v.abs()) + (g_n * h.max(0.0)).sqrt());
        }
        let dt = 0.5 * length / signal;
        let clock = StepClock::at(t, dt);
        if let Some(pipeline) = pipeline.as_mut() {
            pipeline.advance(&raster, clock, &mut state).expect("step");
        } else {
            hyperbolic.apply(&raster, clock, &mut state).expect("step");
        }
        t += dt;
    }
    let mass: f64 = state.h.iter().sum::<f64>() * raster.cell_area();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for v in std::iter::once(&t)
        .chain(&state.h)
        .chain(&state.hu)
        .chain(&state.hv)
    {
        for byte in v.to_bits().to_le_bytes() {
            hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    println!("{n}² cells, {steps} steps, t = {t:.6} s, mass {mass:.12}");
    println!("state hash {hash:#018x}");
}
