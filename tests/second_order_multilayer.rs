//! The second-order scheme with N > 1 layers (`numerics.order = 2`, `model.layers` > 1:
//! the limited reconstruction of h, η and every layer's u_α in the N-layer face, Heun's
//! method around the hydrostatic step and the viscous columns; docs/numerics.md,
//! "Second order"): the properties of the first-order multilayer scheme (lake at rest,
//! rest below repose, positivity and mass at dry fronts), the monolayer's numbers for
//! identical layers, and the observed orders on a smooth sheared flow and at a front.

use crate::common::{l1, observed_order, run, tan_deg, Case};
use granflow::model::granular::Granular;
use granflow::output::memory::MemorySink;
use granflow::physics::GRAVITY as G;
use granflow::scenario::{load_file, FrictionLaw, Limiter, MonolayerShear, Numerics};
use granflow::setup::build_granular;
use granflow::simulation::Simulation;

use super::second_order::{
    both, lake_at_rest_over_a_random_bed, max_abs_diff, order_2, rand01, random_bed_mass_of,
    ORDER_1,
};

fn mu_i() -> FrictionLaw {
    FrictionLaw::MuI {
        mu_s: tan_deg(20.0),
        mu_2: tan_deg(36.0),
        i0: 0.279,
        shear: MonolayerShear::Bagnold,
    }
}

/// Sets layer α's velocity to ū(x) + `shear`(x) (α − (N − 1)/2) in every cell (ū is
/// the velocity the run was built with), ghosts filled.
fn shear_layers(sim: &mut Simulation<Granular>, shear: impl Fn(f64) -> f64) {
    let (n, nx) = (sim.state.layers, sim.grid.nx);
    for i in 1..=nx {
        let x = sim.grid.x_min + (i as f64 - 0.5) * sim.grid.dx;
        let h = sim.state.h[i];
        for a in 0..n {
            sim.state.hu[i * n + a] += h * shear(x) * (a as f64 - 0.5 * (n as f64 - 1.0));
        }
    }
    sim.state.fill_ghosts(&sim.grid);
}

#[test]
fn lake_at_rest_with_four_layers_over_a_random_bed_in_both_orders() {
    for numerics in both() {
        lake_at_rest_over_a_random_bed(numerics, 4);
    }
}

/// The μ(I) mass of `second_order.rs` (Escalante et al. 2023, §5.3: μ_s = tan 20° on a
/// random bed, free surface of slope `surface_deg`) with four layers.
fn random_bed_mass(numerics: Numerics, surface_deg: f64) -> (Vec<f64>, Simulation<Granular>) {
    random_bed_mass_of(numerics, surface_deg, 4)
}

/// Largest |u_α| and |h − h⁰| over the snapshots of a run of [`random_bed_mass`].
fn departures_from_rest(numerics: Numerics, surface_deg: f64) -> (f64, f64) {
    let (h0, mut sim) = random_bed_mass(numerics, surface_deg);
    let (sink, _) = run(&mut sim);
    assert!(sim.steps > 100);
    let mut worst = (0.0f64, 0.0f64);
    for snap in &sink.snapshots {
        let du = snap.u.iter().fold(0.0f64, |m, u| m.max(u.abs()));
        worst = (worst.0.max(du), worst.1.max(max_abs_diff(&snap.h, &h0)));
    }
    worst
}

/// Below repose the layers creep at a speed set by the regularisation δ of the viscous
/// columns (Escalante et al. 2023, Table 6; `multilayer.rs`), at order 1 as at order 2:
/// every cell that creeps is slower than its static friction's impulse per step, so
/// order 2 reconstructs it to first order and Heun's two stages repeat the
/// first-order step. Order 2 departs from rest as order 1 does (within 1 %); beyond repose the
/// mass moves.
#[test]
fn four_layer_mass_below_repose_creeps_no_more_than_at_order_1_and_beyond_it_moves() {
    let first = departures_from_rest(ORDER_1, 19.0);
    let second = departures_from_rest(order_2(Limiter::VanLeer), 19.0);
    eprintln!("below repose, max |u|, |Δh|: order 1 {first:?}, order 2 {second:?}");
    assert!(first.0 < 1e-4 && first.1 < 1e-3, "order 1 {first:?}");
    let within = |a: f64, b: f64| a <= 1.01 * b;
    assert!(
        within(second.0, first.0) && within(second.1, first.1),
        "{second:?} vs {first:?}"
    );
    for numerics in both() {
        let moved = departures_from_rest(numerics, 21.0);
        assert!(moved.1 > 1e-2, "order {}: {moved:?}", numerics.order);
    }
}

/// A dam break over a random bed with a dry patch, random velocities and sheared
/// layers, walls at both ends, five μ(I) layers: h ≥ 0 and finite
/// throughout, mass conserved to round-off.
#[test]
fn five_layer_dry_dam_break_stays_positive_and_conserves_mass_in_both_orders() {
    for law in [mu_i()] {
        for numerics in both() {
            let mut case = Case::new(0.0, 4.0, 200);
            case.numerics = numerics;
            case.layers = 5;
            case.law = law;
            case.t_end = 1.0;
            case.every = 0.05;
            let bed = |x: f64| 0.3 * (-(x - 2.5).powi(2) * 4.0).exp();
            let mut sim = case.build(
                bed,
                |x, b| if x < 1.5 { (0.6 - b).max(0.0) } else { 0.0 },
                |x| {
                    if x < 1.5 {
                        2.0 * (rand01(x + 7.0) - 0.5)
                    } else {
                        0.0
                    }
                },
            );
            shear_layers(&mut sim, |x| if x < 1.5 { 0.2 } else { 0.0 });
            let m0: f64 = sim.state.h_interior().iter().sum();
            let (sink, summary) = run(&mut sim);
            let what = format!("{law:?}, order {}", numerics.order);
            assert_eq!(summary.t_end, 1.0, "{what}: {}", summary.status);
            assert!(sink.snapshots.len() > 10);
            for snap in &sink.snapshots {
                assert!(snap.h.iter().all(|h| h.is_finite() && *h >= 0.0), "{what}");
                assert!(snap.u.iter().all(|u| u.is_finite()), "{what}");
                let m: f64 = snap.h.iter().sum();
                let dm = (m - m0) / m0;
                assert!(dm.abs() < 1e-13, "{what}: t = {}: mass {dm:e}", snap.t);
            }
        }
    }
}

/// A frictionless smooth wave (a hump over a bed bump, moving at up to 0.3 m/s), one
/// velocity in every layer, at order 2 with `layers` layers: (h, u of layer 1).
fn identical_layers(layers: usize, limiter: Limiter) -> (Vec<f64>, Vec<f64>) {
    let mut case = Case::new(0.0, 4.0, 160);
    case.numerics = order_2(limiter);
    case.layers = layers;
    case.t_end = 0.6;
    case.every = 0.6;
    let bed = |x: f64| 0.1 * (-(x - 2.5).powi(2)).exp();
    let mut sim = case.build(
        bed,
        |x, b| 0.5 + 0.1 * (-4.0 * (x - 1.5).powi(2)).exp() - b,
        |x| 0.3 * (-4.0 * (x - 1.5).powi(2)).exp(),
    );
    let (sink, summary) = run(&mut sim);
    assert_eq!(summary.t_end, 0.6);
    let last = sink.snapshots.last().unwrap();
    (last.h.clone(), last.u[..sim.grid.nx].to_vec())
}

/// With one velocity in every layer the exchange terms and the shear vanish and the
/// N-layer order-2 step is the monolayer's to round-off. (Beside dry cells it is not:
/// N > 1 keeps the cells two from a dry cell first order, docs/numerics.md.)
#[test]
fn identical_layers_give_the_monolayer_order_2_numbers() {
    for limiter in [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc] {
        let (h1, u1) = identical_layers(1, limiter);
        for n in [2, 3, 5] {
            let (h, u) = identical_layers(n, limiter);
            let (dh, du) = (max_abs_diff(&h, &h1), max_abs_diff(&u, &u1));
            eprintln!("{limiter:?}, N = {n}: |Δh| {dh:e}, |Δu| {du:e}");
            assert!(dh <= 1e-13 && du <= 1e-12, "{limiter:?}, N = {n}");
        }
    }
}

/// A smooth frictionless sheared flow with three layers: a hump (10 cm on 1 m) over a
/// smooth bed bump, the layers at ±0.2 m/s about ū = 0 where the hump is, on [0, 10] m
/// with walls, to t = 0.5 s. Returns h and the layers' discharges (layer-major).
fn sheared_wave(numerics: Numerics, cells: usize) -> (Vec<f64>, Vec<f64>) {
    let mut case = Case::new(0.0, 10.0, cells);
    case.numerics = numerics;
    case.layers = 3;
    case.t_end = 0.5;
    case.every = 0.5;
    let bed = |x: f64| 0.1 * (-(x - 6.0).powi(2)).exp();
    let mut sim = case.build(
        bed,
        move |x, b| 1.0 + 0.1 * (-2.0 * (x - 4.5).powi(2)).exp() - b,
        |_| 0.0,
    );
    shear_layers(&mut sim, |x| 0.2 * (-2.0 * (x - 4.5).powi(2)).exp());
    let (sink, summary): (MemorySink, _) = run(&mut sim);
    assert_eq!(summary.t_end, 0.5);
    let last = sink.snapshots.last().unwrap();
    let hu = (0..3)
        .flat_map(|a| (0..cells).map(move |i| (a, i)))
        .map(|(a, i)| last.h[i] * last.u[a * cells + i])
        .collect();
    (last.h.clone(), hu)
}

fn coarsen(fine: &[f64], factor: usize) -> Vec<f64> {
    fine.chunks(factor)
        .map(|c| c.iter().sum::<f64>() / factor as f64)
        .collect()
}

/// L1 errors of h and of the layer discharges on `cells` against the same scheme on
/// `reference` cells, and the observed orders.
fn sheared_convergence(
    numerics: Numerics,
    cells: &[usize],
    reference: usize,
) -> [(Vec<f64>, f64); 2] {
    let (h_ref, q_ref) = sheared_wave(numerics, reference);
    let (mut e_h, mut e_q) = (Vec::new(), Vec::new());
    for &n in cells {
        let (h, q) = sheared_wave(numerics, n);
        let f = reference / n;
        e_h.push(l1(&h, &coarsen(&h_ref, f), 10.0 / n as f64));
        e_q.push(l1(&q, &coarsen(&q_ref, f), 10.0 / n as f64));
    }
    let dx: Vec<f64> = cells.iter().map(|&n| 10.0 / n as f64).collect();
    let (o_h, o_q) = (observed_order(&dx, &e_h), observed_order(&dx, &e_q));
    [(e_h, o_h), (e_q, o_q)]
}

#[test]
fn sheared_smooth_flow_with_three_layers_converges_faster_at_order_2() {
    let [(e2, o2), (q2, oq2)] =
        sheared_convergence(order_2(Limiter::VanLeer), &[50, 100, 200], 800);
    let [(e1, o1), _] = sheared_convergence(ORDER_1, &[50, 100, 200], 800);
    eprintln!(
        "order 2: L1(h) {e2:?} ({o2:.3}), L1(hu) {q2:?} ({oq2:.3}); order 1: {e1:?} ({o1:.3})"
    );
    assert!(o2 >= 1.6 && oq2 >= 1.6, "order 2: {o2}, {oq2}");
    assert!(o1 < 1.3, "order 1: {o1}");
    assert!(e2[2] < 0.2 * e1[2]);
}

#[test]
#[ignore = "slow: refinement study"]
fn sheared_smooth_flow_with_three_layers_converges_at_second_order() {
    for limiter in [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc] {
        let [(e, o), (q, oq)] = sheared_convergence(order_2(limiter), &[100, 200, 400], 3200);
        eprintln!("order 2, {limiter:?}: L1(h) {e:?} ({o:.3}), L1(hu) {q:?} ({oq:.3})");
        assert!(o >= 1.8 && oq >= 1.8, "{limiter:?}: {o}, {oq}");
    }
    let [(e, o), (q, oq)] = sheared_convergence(ORDER_1, &[100, 200, 400], 3200);
    eprintln!("order 1: L1(h) {e:?} ({o:.3}), L1(hu) {q:?} ({oq:.3})");
    assert!((0.8..1.3).contains(&o), "order 1: {o}");
}

/// The Ritter dam break (h = 1 m | dry) with three layers: the front (largest x with
/// h > 1 mm) at t = 0.3 s and its lag behind the exact 1 mm contour, relative.
fn ritter_lag(numerics: Numerics, cells: usize) -> f64 {
    let mut case = Case::new(-2.0, 2.5, cells);
    case.numerics = numerics;
    case.layers = 3;
    case.t_end = 0.3;
    case.every = 0.3;
    let mut sim = case.build(|_| 0.0, |x, _| if x < 0.0 { 1.0 } else { 0.0 }, |_| 0.0);
    let (sink, _) = run(&mut sim);
    assert!(sink.snapshots.last().unwrap().h.iter().all(|&h| h >= 0.0));
    let exact = 0.3 * (2.0 * G.sqrt() - 3.0 * (G * 1e-3).sqrt());
    (exact - sim.diagnostics().front_x) / exact
}

#[test]
#[ignore = "slow: refinement study"]
fn ritter_front_with_three_layers_converges_at_order_one_with_order_2() {
    let cells = [256, 512, 1024, 2048];
    let lags: Vec<f64> = cells
        .iter()
        .map(|&n| ritter_lag(order_2(Limiter::VanLeer), n))
        .collect();
    let dx: Vec<f64> = cells.iter().map(|&n| 4.5 / n as f64).collect();
    let order = observed_order(&dx, &lags);
    eprintln!("Ritter, 3 layers, order 2: front lags {lags:?}, observed order {order:.3}");
    assert!(lags.iter().all(|l| *l > 0.0));
    assert!((0.7..1.3).contains(&order), "{order}");
}

/// The μ(I) collapse on 22° (`scenarios/collapse.toml`, to settling) with six layers
/// at `order` on `cells` cells: (runout = final front, wall time in s).
fn collapse_runout(order: u8, cells: usize) -> (f64, f64) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/collapse.toml");
    let sets: Vec<String> = [
        "model.layers=6".to_owned(),
        format!("domain.cells={cells}"),
        format!("numerics.order={order}"),
        "output.every=10".to_owned(),
    ]
    .into();
    let scn = load_file(&path, &sets).expect("collapse.toml loads");
    let mut sim = build_granular(&scn);
    let start = std::time::Instant::now();
    let (_, summary) = run(&mut sim);
    let seconds = start.elapsed().as_secs_f64();
    assert!(summary.t_end < 10.0, "settles: {}", summary.status);
    (sim.diagnostics().front_x, seconds)
}

/// Runout error (against order 2 on 2560 cells) against wall time, both orders, six
/// layers; the table of docs/validation.md ("Second order: error against CPU time").
#[test]
#[ignore = "slow: refinement study"]
fn six_layer_collapse_runout_converges_in_both_orders() {
    let (reference, t_ref) = collapse_runout(2, 2560);
    eprintln!("reference: order 2, 2560 cells: runout {reference:.4} m ({t_ref:.2} s)");
    let cells = [160, 320, 640, 1280];
    let mut errors = [[0.0; 4]; 2];
    for (k, order) in [1u8, 2].into_iter().enumerate() {
        for (c, &n) in cells.iter().enumerate() {
            let (runout, seconds) = collapse_runout(order, n);
            errors[k][c] = (runout - reference).abs();
            eprintln!(
                "| {order} | {n} | {runout:.4} | {:.2e} | {seconds:.2} |",
                errors[k][c]
            );
        }
    }
    for e in errors {
        assert!(e[3] < e[0], "{e:?}");
    }
    assert!(errors[1][3] < errors[0][3], "{errors:?}");
}

/// The collapse over an erodible bed with eight layers (`scenarios/erodible_bed.toml`,
/// the variants of `multilayer.rs`: the static bed is held by the viscous columns'
/// basal and internal friction): mass conserved, h ≥ 0, the column collapses.
#[test]
fn erodible_bed_collapse_with_eight_layers_at_order_2_conserves_mass() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/erodible_bed.toml");
    let variants: [&[&str]; 2] = [
        &["initial.erodible_bed=2e-3"],
        &["rheology.basal=no_slip", "initial.erodible_bed=2e-3"],
    ];
    for extra in variants {
        let sets: Vec<String> = [
            "domain.x_max=1.0",
            "domain.cells=200",
            "boundary.right=wall",
            "model.layers=8",
            "numerics.order=2",
            "time.t_end=1.0",
            "time.stop_at_rest=false",
            "output.every=0.05",
        ]
        .iter()
        .chain(extra)
        .map(|s| s.to_string())
        .collect();
        let scn = load_file(&path, &sets).expect("erodible_bed.toml loads");
        let mut sim = build_granular(&scn);
        let (sink, summary) = run(&mut sim);
        assert_eq!(summary.t_end, 1.0, "{extra:?}: {}", summary.status);
        let m0 = sink.steps[0].mass;
        for rec in &sink.steps {
            assert!(
                (rec.mass - m0).abs() <= 1e-13 * m0,
                "{extra:?} t = {}",
                rec.t
            );
        }
        for snap in &sink.snapshots {
            assert!(snap.h.iter().all(|&h| h >= 0.0), "{extra:?} t = {}", snap.t);
            assert!(
                snap.u.iter().all(|u| u.is_finite()),
                "{extra:?} t = {}",
                snap.t
            );
        }
        let max_u = sink.steps.iter().map(|r| r.max_speed).fold(0.0, f64::max);
        assert!(max_u > 0.5, "{extra:?}: max speed {max_u}");
    }
}

/// Order 2 converges to the solution order 1 converges to: the sheared wave at order 2
/// on 400 cells lies as close to order 1 on 3200 cells as order 1 on 1600 does (both
/// distances are order 1's own error on 3200 cells). Without the cells' interior
/// exchange terms order 2 converged, at second order, to another flow: its layer
/// discharges 6.5 times farther (5.9e-2 against 9.1e-3 m²/s·m).
#[test]
fn sheared_wave_at_order_2_converges_to_the_order_1_solution() {
    let (h2, q2) = sheared_wave(order_2(Limiter::VanLeer), 400);
    let (h1, q1) = sheared_wave(ORDER_1, 1600);
    let (h_ref, q_ref) = sheared_wave(ORDER_1, 3200);
    let dx = 10.0 / 400.0;
    let distance = |a: &[f64], f: usize, b: &[f64]| l1(&coarsen(a, f), &coarsen(b, 8), dx);
    let (d2, d1) = (distance(&h2, 1, &h_ref), distance(&h1, 4, &h_ref));
    let (e2, e1) = (distance(&q2, 1, &q_ref), distance(&q1, 4, &q_ref));
    eprintln!("to order 1 on 3200 cells: h {d2:e} (order 1 on 1600: {d1:e}), hu {e2:e} ({e1:e})");
    assert!(d2 <= 1.5 * d1 && e2 <= 1.5 * e1);
}
