//! Driver for instruction counts of the multilayer non-hydrostatic step against the
//! hydrostatic one (docs/performance.md, "Multilayer non-hydrostatic"): the §5.1 collapse (640 cells,
//! 20 layers, h_i = 1.82 mm) advanced to t = 0.3 s, then `steps` more steps.
//!
//!   valgrind --tool=callgrind target/release/examples/nh_step_cost nonhydrostatic 60
//!
//! Optional arguments: the layers (default 20) and `rheology.viscosity` ("frozen", this
//! driver's default, the paper's step 2; "lagged", the
//! scenarios' default, the same step plus one copy of h u_α, or "implicit"), e.g.
//! `nh_step_cost hydrostatic 60 20 implicit`.
//!
//! Run it twice with different `steps` and difference the totals, or read the stages'
//! inclusive counts (`callgrind_annotate --inclusive=yes`) divided by their calls.
use granflow::scenario::load_file;
use granflow::setup::build_granular;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let pressure = args.get(1).map(String::as_str).unwrap_or("nonhydrostatic");
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(40);
    let layers = args.get(3).map(String::as_str).unwrap_or("20");
    let viscosity = args.get(4).map(String::as_str).unwrap_or("frozen");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/nh_multilayer_collapse.toml");
    let sets = vec![
        format!("model.pressure={pressure}"),
        format!("model.layers={layers}"),
        "time.stop_at_rest=false".to_string(),
        format!("rheology.viscosity={viscosity}"),
    ];
    let scn = load_file(&path, &sets).expect("scenario");
    let mut sim = build_granular(&scn);
    while sim.t < 0.3 {
        let dt = sim.step(0.3 - sim.t).expect("step");
        sim.t += dt;
    }
    let warm = sim.steps;
    for _ in 0..steps {
        let dt = sim.step(f64::INFINITY).expect("step");
        sim.t += dt;
    }
    // Faces whose two cells are thicker than the projection's wet threshold
    // (NH_FILM_FRACTION Δx): the ones that carry pressure unknowns.
    let h_min = granflow::numerics::projection::monolayer::NH_FILM_FRACTION * sim.grid.dx;
    let h = &sim.state.h;
    let nx = sim.grid.nx;
    let wet = (0..=nx)
        .filter(|&f| h[f] > h_min && h[f + 1] > h_min)
        .count();
    // FNV-1a of the state (t, h, h u_α, tracers, pressure), to check that a change
    // keeps the results bit for bit.
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let s = &sim.state;
    let nh = s.nh.as_ref().map(|nh| nh.p.as_slice()).unwrap_or(&[]);
    let tracers = s.tracers.iter().flat_map(|t| t.q.iter());
    for v in std::iter::once(&sim.t)
        .chain(h)
        .chain(&s.hu)
        .chain(tracers)
        .chain(nh)
    {
        for b in v.to_bits().to_le_bytes() {
            hash = (hash ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    println!(
        "{pressure}: {warm} warm-up steps, then {steps} (t = {:.4}); wet faces {wet} of {}; \
         state hash {hash:#018x}",
        sim.t,
        nx + 1
    );
}
