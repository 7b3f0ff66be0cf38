//! The second-order scheme on a raster (`numerics.order = 2`: the dimension-by-dimension
//! MUSCL reconstruction of `numerics/muscl_2d.rs` in the 2-D hydrostatic step, Heun's
//! method around the splitting; docs/numerics.md, "Second order"): a run invariant in y
//! is the order-2 line per row, lakes and masses below repose stay at rest, thicknesses
//! stay non-negative at dry fronts, a radial collapse stays symmetric under x ↔ y, the
//! bits do not depend on the threads nor on the tiles, and the observed order on
//! Thacker's paraboloid is 2 away from the shoreline.

use super::terrain_2d::{material, raster, tan_deg};
use super::terrain_2d_tiles::cone_across_tiles;
use granflow::grid::{BoundaryKind, Coordinates, Grid, Line, LineSpec, Raster2d, Sides};
use granflow::model::granular::Granular;
use granflow::model::granular_2d::{self, Granular2d};
use granflow::model::Model;
use granflow::numerics::muscl::Limiter;
use granflow::numerics::ssp_rk2::HeunSplitting;
use granflow::numerics::{Stage, StepClock};
use granflow::physics::rheology::{Coulomb, FrictionLaw};
use granflow::pipeline::Pipeline;
use granflow::state::{LayeredState, State2d};

const WALL: BoundaryKind = BoundaryKind::Wall;
const OUTFLOW: BoundaryKind = BoundaryKind::Outflow;
const LIMITERS: [Limiter; 3] = [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc];

/// The order-2 pipeline of a raster on `threads` threads.
fn order_2(
    law: &FrictionLaw,
    r: &Raster2d,
    threads: usize,
    limiter: Limiter,
) -> Pipeline<Raster2d, State2d> {
    granular_2d::second_order_pipeline(law, &material(), r, threads, limiter).unwrap()
}

/// Advances to exactly `t_end` with Courant number `cfl`; returns the steps taken.
fn run_to(
    r: &Raster2d,
    s: &mut State2d,
    p: &mut Pipeline<Raster2d, State2d>,
    t_end: f64,
    cfl: f64,
) -> usize {
    let model = Granular2d::new(r, 1e-3);
    let (mut t, mut steps) = (0.0, 0);
    while t < t_end {
        let speed = model.diagnose(r, s).signal_speed;
        let dt = (cfl * r.cfl_length() / speed).min(t_end - t);
        p.advance(r, StepClock::at(t, dt), s).unwrap();
        t += dt;
        steps += 1;
    }
    steps
}

/// A dam break on a 25° plane (local frame, Coulomb δ = 20°, bumpy bed) and a collapse
/// on a Cartesian slope: on 80 × 3 cells with walls along x (y-invariant), each row is
/// the order-2 line's state at every step, to round-off (the y-faces carry nothing;
/// the x and y parts of an update are summed with an exact zero).
#[test]
fn order_2_runs_invariant_in_y_are_the_order_2_line_per_row() {
    type Case = (Coordinates, f64, f64, fn(f64) -> f64, fn(f64) -> f64);
    let cases: [Case; 2] = [
        (
            Coordinates::Local,
            25.0,
            20.0,
            |x| 0.02 * (6.0 * x).sin(),
            |x| {
                if x < -0.5 {
                    0.1
                } else {
                    0.0
                }
            },
        ),
        (
            Coordinates::Cartesian,
            0.0,
            18.0,
            |x| -0.5 * x,
            |x| 0.05 + 0.1 * (-(8.0 * (x + 0.4)).powi(2)).exp(),
        ),
    ];
    for (coordinates, slope, delta, bed, h0) in cases {
        for limiter in LIMITERS {
            let nx = 80;
            let spec = LineSpec {
                x_min: -1.0,
                x_max: 1.0,
                cells: nx,
                slope_deg: slope,
                coordinates,
                left: WALL,
                right: OUTFLOW,
            };
            let line = Line::new(&spec, spec.centres().iter().map(|&x| bed(x)).collect());
            let h: Vec<f64> = line.x.iter().map(|&x| h0(x)).collect();
            let mut s1 = LayeredState::from_profiles(&line, &[1.0], &h, &vec![0.0; nx]);
            let mu = tan_deg(delta);
            let heun = HeunSplitting::new(Coulomb { mu }, nx, limiter);
            let mut p1: Pipeline<Line, LayeredState> =
                Pipeline::new(vec![Box::new(heun) as Box<dyn Stage<Line, LayeredState>>]);
            let sides = Sides {
                west: WALL,
                east: OUTFLOW,
                south: WALL,
                north: WALL,
            };
            let ny = 3;
            let r = raster(
                nx,
                ny,
                (-1.0, 1.0),
                (0.0, 0.3),
                sides,
                coordinates,
                slope,
                move |x, _| bed(x),
            );
            let h2: Vec<f64> = (0..nx * ny).map(|k| h[k % nx]).collect();
            let zeros = vec![0.0; nx * ny];
            let mut s2 = State2d::from_velocities(h2, &zeros, &zeros);
            let law = FrictionLaw::Coulomb { mu };
            let mut p2 = order_2(&law, &r, 1, limiter);
            let model_1d = Granular {
                h_bed: vec![0.0; nx],
                front_threshold: 1e-3,
                static_threshold: 1e-3,
                rest_speed: 0.0,
            };
            let (mut moved, mut t) = (0.0f64, 0.0);
            for step in 0..150 {
                let d1 = model_1d.diagnose(&line, &s1);
                let clock = StepClock::at(t, 0.3 * line.dx / d1.signal_speed);
                t += clock.dt;
                p1.advance(&line, clock, &mut s1).unwrap();
                p2.advance(&r, clock, &mut s2).unwrap();
                for k in 0..nx * ny {
                    let a = k % nx + 1;
                    let scale = 1e-13 * (1.0 + s1.h[a].abs() + s1.hu[a].abs());
                    let what = format!("{coordinates:?} {limiter:?} step {step} cell {k}");
                    assert!((s2.h[k] - s1.h[a]).abs() <= scale, "h, {what}");
                    assert!((s2.hu[k] - s1.hu[a]).abs() <= scale, "hu, {what}");
                    assert_eq!(s2.hv[k], 0.0, "hv, {what}");
                }
                moved = moved.max(s1.hu.iter().fold(0.0f64, |m, q| m.max(q.abs())));
            }
            assert!(moved > 1e-3, "the case must flow (max |hu| = {moved})");
        }
    }
}

/// A frictionless lake at rest, η = 0.5 over a random bed with dry islands (Cartesian),
/// and a lake on a tilted DEM plane in the bed-normal frame: every cell is at rest,
/// hence first order, and Heun's stages return the state: to round-off (1e-13).
#[test]
fn order_2_lakes_at_rest_stay_at_rest() {
    let rand = |x: f64, y: f64| {
        let k = ((x * 1e4) as u64) ^ (((y * 1e4) as u64) << 20);
        let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let flat = raster(
        24,
        20,
        (0.0, 1.2),
        (0.0, 1.0),
        Sides::all(WALL),
        Coordinates::Cartesian,
        0.0,
        move |x, y| 0.6 * rand(x, y),
    );
    // A plane of slopes 0.3 along x and 0.1 along y as a DEM, under a lake whose
    // normal columns' tops are level (H = (K − b)/c² per horizontal area, the
    // bed-normal frame's lake; tests/terrain_2d_bed_normal.rs).
    let tilted = raster(
        30,
        20,
        (0.0, 3.0),
        (0.0, 2.0),
        Sides::all(WALL),
        Coordinates::BedNormal,
        0.0,
        |x, y| 0.3 * (x - 2.0) + 0.1 * (y - 1.0),
    );
    for r in [flat, tilted] {
        let h0: Vec<f64> = if r.metric().is_some() {
            let c2 = 1.0 / (1.0 + 0.09 + 0.01);
            r.bed().iter().map(|b| (0.5 - b) / c2).collect()
        } else {
            let h0: Vec<f64> = r.bed().iter().map(|b| (0.5 - b).max(0.0)).collect();
            assert!(h0.contains(&0.0), "the bed must emerge somewhere");
            h0
        };
        let mut s = State2d::zeros(h0.len());
        s.h.clone_from(&h0);
        for limiter in LIMITERS {
            let mut p = order_2(&FrictionLaw::Coulomb { mu: 0.0 }, &r, 1, limiter);
            let model = Granular2d::new(&r, 1e-3);
            let dt = 0.3 * r.cfl_length() / model.diagnose(&r, &s).signal_speed;
            for k in 0..200 {
                p.advance(&r, StepClock::at(k as f64 * dt, dt), &mut s)
                    .unwrap();
            }
            let dh =
                s.h.iter()
                    .zip(&h0)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
            let q = s.hu.iter().chain(&s.hv).fold(0.0f64, |m, q| m.max(q.abs()));
            assert!(dh < 1e-13, "{:?}: max |h − h0| = {dh:e}", r.coordinates());
            assert!(q < 1e-13, "{:?}: max |q| = {q:e}", r.coordinates());
        }
    }
}

/// A Coulomb layer on a random bed whose discrete surface slope stays inside the disk
/// |∇η| ≤ 0.6 μ_s (Cartesian, and on a 10° plane in the local frame): every discharge
/// stays exactly 0 at order 2.
#[test]
fn order_2_masses_below_repose_on_a_random_bed_stay_exactly_at_rest() {
    let (nx, ny) = (30, 24);
    let dx = 1.0 / nx as f64;
    let mu_s = tan_deg(25.0);
    let amp = 0.3 * mu_s * dx;
    for (coordinates, slope) in [(Coordinates::Cartesian, 0.0), (Coordinates::Local, 10.0)] {
        let r = raster(
            nx,
            ny,
            (0.0, 1.0),
            (0.0, 0.8),
            Sides::all(WALL),
            coordinates,
            slope,
            |x, y| {
                let k = ((x * 1e4) as u64) << 20 ^ (y * 1e4) as u64;
                amp * (((k.wrapping_mul(0x9E37_79B9_7F4A_7C15)) >> 11) as f64 / (1u64 << 53) as f64)
            },
        );
        let h0 = vec![0.1; nx * ny];
        let mut s = State2d::zeros(nx * ny);
        s.h.clone_from(&h0);
        let mut p = order_2(&FrictionLaw::Coulomb { mu: mu_s }, &r, 1, Limiter::Mc);
        let dt = 0.3 * dx / (9.81f64 * 0.1).sqrt();
        for k in 0..200 {
            p.advance(&r, StepClock::at(k as f64 * dt, dt), &mut s)
                .unwrap();
        }
        assert!(
            s.hu.iter().chain(&s.hv).all(|&q| q == 0.0),
            "{coordinates:?} moved"
        );
        let dh =
            s.h.iter()
                .zip(&h0)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
        // As at order 1 (tests/terrain_2d.rs): the faces' diffusion of the held
        // thicknesses moves round-off.
        assert!(dh < 1e-14, "{coordinates:?}: max |h − h0| = {dh:e}");
    }
}

/// The state of a radial collapse on a flat bed (Cartesian): a cylinder of radius 0.3 m
/// and height 0.2 m at the centre of an n × n raster of [−1, 1]².
fn collapse(n: usize) -> (Raster2d, State2d) {
    let r = raster(
        n,
        n,
        (-1.0, 1.0),
        (-1.0, 1.0),
        Sides::all(WALL),
        Coordinates::Cartesian,
        0.0,
        |_, _| 0.0,
    );
    let h: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = (r.x(k % n), r.y(k / n));
            if x * x + y * y < 0.09 {
                0.2
            } else {
                0.0
            }
        })
        .collect();
    let mut s = State2d::zeros(n * n);
    s.h = h;
    (r, s)
}

/// A dry dam break (a column released onto a dry bed with μ = 0 and μ = tan 20°):
/// the thickness stays ≥ 0 at every step and the mass is conserved to round-off.
#[test]
fn order_2_dry_dam_breaks_stay_non_negative_and_conserve_mass() {
    for mu in [0.0, tan_deg(20.0)] {
        let n = 40;
        let (r, s0) = collapse(n);
        let model = Granular2d::new(&r, 1e-3);
        let m0 = model.diagnose(&r, &s0).mass;
        let mut moved = 0.0f64;
        for limiter in LIMITERS {
            let mut s1 = s0.clone();
            let mut p = order_2(&FrictionLaw::Coulomb { mu }, &r, 1, limiter);
            let mut t = 0.0;
            for _ in 0..60 {
                let speed = model.diagnose(&r, &s1).signal_speed;
                let clock = StepClock::at(t, 0.4 * r.cfl_length() / speed);
                t += clock.dt;
                p.advance(&r, clock, &mut s1).unwrap();
                assert!(s1.h.iter().all(|&h| h >= 0.0), "{limiter:?}: negative h");
                moved = moved.max(s1.hu.iter().fold(0.0, |m, q| m.max(q.abs())));
            }
            let m1 = model.diagnose(&r, &s1).mass;
            assert!(
                ((m1 - m0) / m0).abs() < 1e-13,
                "{limiter:?}: mass {m0} → {m1}"
            );
        }
        assert!(moved > 1e-2, "the column must collapse ({moved})");
    }
}

/// A radial collapse on a square raster stays symmetric under x ↔ y to the bit on a
/// flat bed (Cartesian): the slopes, edges and faces of the two directions are the same
/// operations on the transposed data, and an update sums its x and y parts before
/// subtracting them. In a bowl b = 0.3 (x² + y²) as a DEM (bed-normal frame) to
/// round-off: the frame's metric products are not symmetric to the bit, at order 1
/// either (6.9e-18 m there).
#[test]
fn order_2_radial_collapse_stays_symmetric_under_x_y() {
    let n = 40;
    let mu = tan_deg(15.0);
    let law = FrictionLaw::Coulomb { mu };
    let flat = collapse(n).0;
    for limiter in LIMITERS {
        let mut s = collapse(n).1;
        let mut p = order_2(&law, &flat, 1, limiter);
        run_to(&flat, &mut s, &mut p, 0.3, 0.4);
        for j in 0..n {
            for i in 0..n {
                let (a, b) = (j * n + i, i * n + j);
                assert_eq!(s.h[a], s.h[b], "{limiter:?} h at ({i}, {j})");
                assert_eq!(s.hu[a], s.hv[b], "{limiter:?} hu at ({i}, {j})");
            }
        }
        assert!(s.hu.iter().any(|&q| q.abs() > 1e-3));
    }
    let bowl = raster(
        n,
        n,
        (-1.0, 1.0),
        (-1.0, 1.0),
        Sides::all(WALL),
        Coordinates::BedNormal,
        0.0,
        |x, y| 0.3 * (x * x + y * y),
    );
    let mut s = collapse(n).1;
    let mut p = order_2(&law, &bowl, 1, Limiter::Mc);
    run_to(&bowl, &mut s, &mut p, 0.3, 0.4);
    let (mut dh, mut dq) = (0.0f64, 0.0f64);
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (j * n + i, i * n + j);
            dh = dh.max((s.h[a] - s.h[b]).abs());
            dq = dq.max((s.hu[a] - s.hv[b]).abs());
        }
    }
    eprintln!("bed-normal bowl: max asymmetry {dh:e} m, {dq:e} m²/s");
    assert!(dh < 1e-14 && dq < 1e-14, "asymmetry {dh:e} m, {dq:e} m²/s");
    assert!(s.hu.iter().any(|&q| q.abs() > 1e-3));
}

/// A mass released across tile edges on a noisy 30° plane with a block of wall cells
/// (the case of tests/terrain_2d_tiles.rs), in the local frame and as a DEM in the
/// bed-normal frame: at order 2 the tiles give the full sweep's bits at every step, on
/// 1, 2 and 4 threads.
#[test]
fn order_2_tiles_and_threads_give_the_full_sweeps_bits() {
    for coordinates in [Coordinates::Local, Coordinates::BedNormal] {
        tiles_and_threads(coordinates);
    }
}

fn tiles_and_threads(coordinates: Coordinates) {
    let tilt = if coordinates == Coordinates::Local {
        0.0
    } else {
        tan_deg(30.0)
    };
    let (r, h) = cone_across_tiles(coordinates, tilt);
    let (nx, ny) = (r.nx(), r.ny());
    let zeros = vec![0.0; nx * ny];
    let law = FrictionLaw::Coulomb { mu: tan_deg(20.0) };
    let model = Granular2d::new(&r, 1e-3);
    let mut full = State2d::from_velocities(h.clone(), &zeros, &zeros);
    full.tiles.step_every_tile();
    let mut p_full = order_2(&law, &r, 1, Limiter::VanLeer);
    let mut tiled: Vec<(State2d, Pipeline<Raster2d, State2d>)> = [1, 2, 4]
        .iter()
        .map(|&t| {
            (
                State2d::from_velocities(h.clone(), &zeros, &zeros),
                order_2(&law, &r, t, Limiter::VanLeer),
            )
        })
        .collect();
    let (mut least, mut t) = (1.0f64, 0.0);
    for step in 0..300 {
        let d = model.diagnose(&r, &full);
        let clock = StepClock::at(t, 0.4 * r.cfl_length() / d.signal_speed);
        t += clock.dt;
        p_full.advance(&r, clock, &mut full).unwrap();
        for (threads, (s, p)) in [1, 2, 4].iter().zip(tiled.iter_mut()) {
            p.advance(&r, clock, s).unwrap();
            let same = s.h == full.h && s.hu == full.hu && s.hv == full.hv;
            assert!(
                same,
                "step {step} on {threads} threads differs from the full sweep"
            );
            if s.tiles.is_known() {
                least = least.min(s.tiles.stepped_fraction());
            }
        }
    }
    assert!(
        least < 0.7,
        "the tiles must skip part of the raster (least {least})"
    );
    assert!(full.hu.iter().any(|&q| q.abs() > 1e-3));
}

/// Thacker's (1981) radially symmetric paraboloid in the bowl b = −h₀(1 − r²/a²)
/// (a = 1 m, h₀ = 0.1 m, shoreline at r₀ = 0.8 m at t = 0), frictionless: h at t.
fn thacker_h(x: f64, y: f64, t: f64) -> f64 {
    let (a, h0, r0): (f64, f64, f64) = (1.0, 0.1, 0.8);
    let big_a = (a * a - r0 * r0) / (a * a + r0 * r0);
    let omega = (8.0 * 9.81 * h0).sqrt() / a;
    let c = 1.0 - big_a * (omega * t).cos();
    let r2 = (x * x + y * y) / (a * a);
    let eta = h0
        * ((1.0 - big_a * big_a).sqrt() / c - 1.0 - r2 * ((1.0 - big_a * big_a) / (c * c) - 1.0));
    (eta + h0 * (1.0 - r2)).max(0.0)
}

/// L¹ errors of h against Thacker's solution at t = T/8 on an n × n raster of
/// [−1.6, 1.6]² (the period T = 2π/ω): (over the disk r < 0.4 m, which the shoreline's
/// waves have not reached, relative to its mass; over the whole raster, relative).
pub(crate) fn thacker_errors(n: usize, order: Option<Limiter>) -> (f64, f64) {
    let r = raster(
        n,
        n,
        (-1.6, 1.6),
        (-1.6, 1.6),
        Sides::all(WALL),
        Coordinates::Cartesian,
        0.0,
        |x, y| -0.1 * (1.0 - x * x - y * y),
    );
    let h: Vec<f64> = (0..n * n)
        .map(|k| thacker_h(r.x(k % n), r.y(k / n), 0.0))
        .collect();
    let mut s = State2d::zeros(n * n);
    s.h = h;
    let law = FrictionLaw::Coulomb { mu: 0.0 };
    let mut p = match order {
        Some(limiter) => order_2(&law, &r, 1, limiter),
        None => granular_2d::pipeline(&law, &material(), &r, 1).unwrap(),
    };
    let period = 2.0 * std::f64::consts::PI / (8.0f64 * 9.81 * 0.1).sqrt();
    let t_end = 0.125 * period;
    run_to(&r, &mut s, &mut p, t_end, 0.4);
    let (mut inner, mut inner_mass, mut all, mut mass) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..n * n {
        let (x, y) = (r.x(k % n), r.y(k / n));
        let exact = thacker_h(x, y, t_end);
        let e = (s.h[k] - exact).abs();
        all += e;
        mass += exact;
        if x * x + y * y < 0.16 {
            inner += e;
            inner_mass += exact;
        }
    }
    (inner / inner_mass, all / mass)
}

/// Observed orders on Thacker's paraboloid (50, 100, 200 cells a side): ≥ 1.8 inside
/// the disk r < 0.4 m at order 2 (van Leer), ≥ 0.9 over the whole raster with its
/// moving shoreline; order 1 stays near 1 inside.
#[test]
fn order_2_thacker_paraboloid_converges_at_second_order_away_from_the_shoreline() {
    let errors: Vec<(f64, f64)> = [50, 100, 200]
        .iter()
        .map(|&n| thacker_errors(n, Some(Limiter::VanLeer)))
        .collect();
    let first: Vec<(f64, f64)> = [50, 100].iter().map(|&n| thacker_errors(n, None)).collect();
    let order = |a: f64, b: f64| (a / b).log2();
    let inner = order(errors[1].0, errors[2].0);
    let whole = order(errors[1].1, errors[2].1);
    let inner_1 = order(first[0].0, first[1].0);
    eprintln!("Thacker order 2: {errors:?}, inner order {inner:.2}, whole {whole:.2}; order 1: {first:?}, inner {inner_1:.2}");
    assert!(inner >= 1.8, "inner observed order {inner}");
    assert!(whole >= 0.9, "whole-raster observed order {whole}");
    assert!(
        errors[1].0 < 0.5 * first[1].0,
        "order 2 must beat order 1 inside"
    );
}
