//! Order 2 of the dilatant model's split scheme (`numerics.order = 2`;
//! `granflow::numerics::dilatant::heun`): conservation of mass and grains, rest below
//! repose to the bit, positivity, φ within bounds, the observed order on smooth flows,
//! and the scenario path (order 1 unchanged, order 2 built and refused where it does
//! not exist).

use crate::common::{l1, observed_order};
use granflow::grid::{Line, LineSpec};
use granflow::numerics::dilatant::heun::HeunSplit;
use granflow::numerics::dilatant::split::SplitScheme;
use granflow::numerics::dilatant::stabilisation::Viscosity;
use granflow::numerics::dilatant::step::DilatantOptions;
use granflow::numerics::muscl::Limiter;
use granflow::physics::dilatancy::DilatantLaw;
use granflow::scenario::{BoundaryKind, Coordinates};
use granflow::state::dilatant::DilatantState;

const LIMITERS: [Limiter; 3] = [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc];

fn mesh(x_max: f64, cells: usize, slope_deg: f64, walls: bool) -> Line {
    let kind = if walls {
        BoundaryKind::Wall
    } else {
        BoundaryKind::Outflow
    };
    let spec = LineSpec {
        x_min: 0.0,
        x_max,
        cells,
        slope_deg,
        coordinates: Coordinates::Local,
        left: kind,
        right: kind,
    };
    Line::new(&spec, vec![0.0; cells])
}

fn state(
    mesh: &Line,
    h: impl Fn(f64) -> f64,
    v: impl Fn(f64) -> f64,
    phi: impl Fn(f64) -> f64,
) -> DilatantState {
    let hs: Vec<f64> = mesh.x.iter().map(|&x| h(x)).collect();
    let vs: Vec<f64> = mesh.x.iter().map(|&x| v(x)).collect();
    let ps: Vec<f64> = mesh.x.iter().map(|&x| phi(x)).collect();
    DilatantState::from_profiles(mesh, 2.0, &hs, &vs, &ps)
}

/// The split scheme's options without stabilisation (the scenarios' default).
fn options() -> DilatantOptions {
    DilatantOptions {
        viscosity: Viscosity { xi: [0.0; 3] },
        ..DilatantOptions::default()
    }
}

/// Δt = `cfl` Δx / max(|v| + √(g_c h)).
fn cfl_dt(mesh: &Line, s: &DilatantState, cfl: f64) -> f64 {
    let speed = (1..=s.nx)
        .map(|j| {
            let u = if s.h[j] > 1e-10 {
                s.hu[j] / s.h[j]
            } else {
                0.0
            };
            u.abs() + (mesh.g_n * s.h[j]).sqrt()
        })
        .fold(0.0, f64::max);
    cfl * mesh.dx / speed
}

/// Runs `step` to `t_end` at CFL 0.5, calling `each` after every step.
fn run(
    mut step: impl FnMut(&Line, &mut DilatantState, f64),
    mesh: &Line,
    s: &mut DilatantState,
    t_end: f64,
    mut each: impl FnMut(&DilatantState),
) -> usize {
    let (mut t, mut steps) = (0.0, 0);
    while t < t_end - 1e-12 {
        let dt = cfl_dt(mesh, s, 0.5).min(t_end - t);
        step(mesh, s, dt);
        t += dt;
        steps += 1;
        each(s);
    }
    steps
}

fn heun(
    law: DilatantLaw,
    nx: usize,
    limiter: Limiter,
) -> impl FnMut(&Line, &mut DilatantState, f64) {
    let mut scheme = HeunSplit::new(law, options(), nx, 0.62, limiter);
    move |mesh, s, dt| scheme.step(mesh, s, dt).unwrap()
}

fn grains(s: &DilatantState, dx: f64) -> f64 {
    (1..=s.nx).map(|j| s.phi[j] * s.h[j]).sum::<f64>() * dx
}

fn volume(s: &DilatantState, dx: f64) -> f64 {
    s.h[1..=s.nx].iter().sum::<f64>() * dx
}

#[test]
fn masses_at_rest_below_repose_stay_exactly_at_rest() {
    // The cases of the order-1 test (tests/dilatant.rs): uniform φ on a 10° plane with
    // a surface sloping at +0.2 − tan 10°, and φ 0.55 → 0.62 on a flat bed whose
    // surface slope and φ-gradient pressure stay below μ_1: h, hv, φ unchanged bit
    // for bit for 2 s, with every limiter.
    let law = DilatantLaw::table1();
    type Profile = Box<dyn Fn(f64) -> f64>;
    let cases: [(f64, Profile, Profile); 2] = [
        (10.0, Box::new(|x| 0.1 + 0.2 * x), Box::new(|_| 0.6)),
        (
            0.0,
            Box::new(|x| 0.1 - 0.1 * x),
            Box::new(|x| 0.55 + 0.14 * x),
        ),
    ];
    for (slope, h, phi) in cases {
        for limiter in LIMITERS {
            let mesh = mesh(0.5, 50, slope, true);
            let mut s = state(&mesh, &h, |_| 0.0, &phi);
            let start = s.clone();
            let steps = run(heun(law, mesh.nx, limiter), &mesh, &mut s, 2.0, |_| {});
            println!("order 2 at rest, slope {slope}°, {limiter:?}: {steps} steps");
            assert_eq!(s.h, start.h);
            assert_eq!(s.hu, start.hu);
            assert_eq!(s.phi, start.phi);
        }
    }
    // The same plane at 30° (tan 30° > μ_1 + tan ψ) moves.
    let mesh = mesh(0.5, 50, 30.0, true);
    let mut s = state(&mesh, |_| 0.1, |_| 0.0, |_| 0.6);
    run(heun(law, mesh.nx, Limiter::Mc), &mesh, &mut s, 0.1, |_| {});
    assert!(s.hu[1..=50].iter().any(|q| q.abs() > 1e-5));
}

#[test]
fn collapses_conserve_grains_and_keep_h_and_phi_admissible() {
    // A dense-over-loose column collapsing between walls on 22° (fronts running onto
    // a dry bed). K = 0: ∫h and ∫φh conserved, φ within its initial bounds (the
    // transport's maximum principle and the average's convex combination). K = 4.09
    // (Table 1): ∫φh conserved, φ in (0, 1), h ≥ 0 after every step.
    let column = |x: f64| if (0.1..0.4).contains(&x) { 0.08 } else { 0.0 };
    let fraction = |x: f64| 0.56 + 0.06 * ((x - 0.1) / 0.3).clamp(0.0, 1.0);
    for k in [0.0, DilatantLaw::table1().k] {
        for limiter in LIMITERS {
            let law = DilatantLaw {
                k,
                ..DilatantLaw::table1()
            };
            let mesh = mesh(1.5, 300, 22.0, true);
            let mut s = state(&mesh, column, |_| 0.0, fraction);
            let (v0, m0) = (volume(&s, mesh.dx), grains(&s, mesh.dx));
            let (lo, hi) = (0.56, 0.62);
            let mut worst_phi = (f64::INFINITY, f64::NEG_INFINITY);
            let mut lowest_h = f64::INFINITY;
            let steps = run(heun(law, mesh.nx, limiter), &mesh, &mut s, 0.6, |s| {
                for j in 1..=s.nx {
                    lowest_h = lowest_h.min(s.h[j]);
                    if s.h[j] > 0.0 {
                        worst_phi = (worst_phi.0.min(s.phi[j]), worst_phi.1.max(s.phi[j]));
                    }
                }
            });
            let (dv, dm) = (
                volume(&s, mesh.dx) / v0 - 1.0,
                grains(&s, mesh.dx) / m0 - 1.0,
            );
            println!(
                "K {k}, {limiter:?}: {steps} steps, ∫φh {dm:.1e}, ∫h {dv:.2e}, φ in [{:.4}, {:.4}], min h {lowest_h:e}",
                worst_phi.0, worst_phi.1
            );
            assert!(dm.abs() < 1e-13, "∫φh {dm:e}");
            assert!(lowest_h >= 0.0);
            assert!(worst_phi.0 > 0.0 && worst_phi.1 < 1.0);
            if k == 0.0 {
                assert!(dv.abs() < 1e-13, "∫h {dv:e}");
                assert!(
                    worst_phi.0 >= lo - 1e-14 && worst_phi.1 <= hi + 1e-14,
                    "{worst_phi:?}"
                );
            }
            // The front moved.
            assert!(s.h[1..=s.nx].iter().rposition(|&h| h > 1e-3).unwrap() > 150);
        }
    }
}

/// The cell means of a run on `fine` cells over blocks of `fine / coarse` cells.
fn restrict(values: &[f64], factor: usize) -> Vec<f64> {
    values
        .chunks(factor)
        .map(|c| c.iter().sum::<f64>() / factor as f64)
        .collect()
}

/// Runs a smooth case on each of `grids` and on `reference` cells; returns the L1
/// errors of h and of φh against the reference, restricted to each grid.
fn smooth_errors(
    law: DilatantLaw,
    slope: f64,
    limiter: Option<Limiter>,
    grids: &[usize],
    reference: usize,
    t_end: f64,
) -> (Vec<f64>, Vec<f64>) {
    let solve = |cells: usize| {
        let mesh = mesh(1.0, cells, slope, false);
        let bump = |x: f64| (-((x - 0.5) / 0.1).powi(2)).exp();
        let mut s = state(
            &mesh,
            |x| 0.1 + 0.02 * bump(x),
            |x| 0.5 + 0.1 * bump(x),
            |x| 0.6 - 0.02 * bump(x + 0.1),
        );
        match limiter {
            Some(limiter) => {
                run(heun(law, cells, limiter), &mesh, &mut s, t_end, |_| {});
            }
            None => {
                let mut scheme = SplitScheme::new(law, options(), cells, 0.62);
                let step =
                    |m: &Line, s: &mut DilatantState, dt: f64| scheme.step(m, s, dt).unwrap();
                run(step, &mesh, &mut s, t_end, |_| {});
            }
        }
        let m: Vec<f64> = (1..=cells).map(|j| s.phi[j] * s.h[j]).collect();
        (s.h[1..=cells].to_vec(), m)
    };
    let (h_ref, m_ref) = solve(reference);
    let mut errors = (Vec::new(), Vec::new());
    for &cells in grids {
        let (h, m) = solve(cells);
        let factor = reference / cells;
        let dx = 1.0 / cells as f64;
        errors.0.push(l1(&h, &restrict(&h_ref, factor), dx));
        errors.1.push(l1(&m, &restrict(&m_ref, factor), dx));
    }
    errors
}

#[test]
fn smooth_flows_converge_at_second_order() {
    // A smooth wave (h, v bumps) moving over a non-uniform φ (a dip of 0.02), outflow
    // ends that see a uniform state to 0.1 s; L1 errors of h and φh on 50/100/200 cells
    // against 1600 cells of the same scheme. Frictionless with K = 0 (the hyperbolic
    // step, the φ-gradient pressure and the φ transport): order ≥ 1.8 with MC and
    // van Leer (measured 2.02/2.03 and 1.98/1.98; minmod 1.69/1.71, asserted ≥ 1.6,
    // the limiter that clips most at these grids; order 1 0.96). With the Table 1 law on
    // 30° (μ(I) friction and the dilatancy step at K = 4.09 in every cell) the
    // splitting of a state-dependent friction is O(Δt²) per step, as for the monolayer
    // (docs/numerics.md, "Second order"): measured 1.32–1.44, asserted above 1.2 and
    // below order 1's error.
    let grids = [50, 100, 200];
    let dx: Vec<f64> = grids.iter().map(|&n| 1.0 / n as f64).collect();
    let frictionless = DilatantLaw {
        mu_1: 0.0,
        mu_2: 0.0,
        k: 0.0,
        ..DilatantLaw::table1()
    };
    let cases = [
        ("frictionless, K = 0, flat", frictionless, 0.0),
        ("Table 1 (K = 4.09), 30°", DilatantLaw::table1(), 30.0),
    ];
    for (name, law, slope) in cases {
        let (first, _) = smooth_errors(law, slope, None, &grids, 1600, 0.1);
        println!(
            "{name}, order 1: L1 h {:.3e} at 200 cells (order {:.2})",
            first[2],
            observed_order(&dx, &first)
        );
        for limiter in LIMITERS {
            let (eh, em) = smooth_errors(law, slope, Some(limiter), &grids, 1600, 0.1);
            let (ph, pm) = (observed_order(&dx, &eh), observed_order(&dx, &em));
            println!(
                "{name}, {limiter:?}: L1 h {:.3e}, φh {:.3e} at 200 cells; order h {ph:.2}, φh {pm:.2}",
                eh[2], em[2]
            );
            let least = match (law.mu_1 == 0.0, limiter) {
                (true, Limiter::Minmod) => 1.6,
                (true, _) => 1.8,
                (false, _) => 1.2,
            };
            assert!(ph >= least && pm >= least, "{name}, {limiter:?}: {ph} {pm}");
            assert!(eh[2] < first[2], "{name}, {limiter:?}");
        }
    }
}

/// The last cell-centre contour of `q` at level `c`, linearly interpolated between the
/// last cell above `c` and the next one.
fn contour(x: &[f64], q: &[f64], c: f64) -> f64 {
    let i = q
        .iter()
        .rposition(|&v| v > c)
        .expect("a cell above the level");
    if i + 1 == q.len() {
        return x[i];
    }
    x[i] + (q[i] - c) / (q[i] - q[i + 1]) * (x[i + 1] - x[i])
}

/// The shipped dense collapse on 22° (`scenarios/dilatancy_dense.toml`) to 0.48 s on
/// `cells` cells at `order`: (the h = 1 mm contour, linear between cell centres; the
/// front CSV's front, the largest cell centre with h > 1 mm) at 0.48 s.
fn dense_front_at_22_degrees(cells: usize, order: u8) -> (f64, f64) {
    use granflow::output::memory::MemorySink;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let sets = [
        format!("domain.cells={cells}"),
        "time.t_end=0.48".to_string(),
        "output.every=0.48".to_string(),
        format!("numerics.order={order}"),
    ];
    let path = dir.join("scenarios").join("dilatancy_dense.toml");
    let scn = granflow::scenario::load_file(&path, &sets).unwrap();
    let mut sim = granflow::setup::build_dilatant(&scn);
    let x = sim.grid.x.clone();
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).unwrap();
    let last = sink.snapshots.last().unwrap();
    assert!(
        (last.t - 0.48).abs() < 1e-9,
        "last snapshot at {} s",
        last.t
    );
    let front = x[last.h.iter().rposition(|&h| h > 1e-3).unwrap()];
    (contour(&x, &last.h, 1e-3), front)
}

#[test]
#[ignore = "slow: refinement study"]
fn the_one_millimetre_contour_of_the_dense_front_at_both_orders() {
    // The refereeing question of docs/validation.md (dil-thin-layer): at order 1 the
    // h = 1 mm contour of the dense 22° collapse at 0.48 s enters its asymptotic range
    // only once Δx ≲ 1 mm. Both orders on Δx = 5 mm to 0.156 mm: printed, with the
    // successive differences and their ratios; asserted: at order 2 the contour moves
    // monotonically and its successive differences shrink (measured ratios 1.38, 4.18,
    // 3.37, 1.57; order 1: 1.23, 1.41, 1.96, 1.83).
    let grids = [640, 1280, 2560, 5120, 10240, 20480];
    for order in [1, 2] {
        let rows: Vec<(f64, f64)> = grids
            .iter()
            .map(|&cells| dense_front_at_22_degrees(cells, order))
            .collect();
        for (cells, (c, f)) in grids.iter().zip(&rows) {
            println!(
                "order {order}, Δx = {:.4} mm: h = 1 mm contour {c:.5} m, h > 1 mm front {f:.5} m",
                3.2e3 / *cells as f64
            );
        }
        let d: Vec<f64> = rows.windows(2).map(|w| w[1].0 - w[0].0).collect();
        let ratios: Vec<f64> = d.windows(2).map(|w| w[0] / w[1]).collect();
        let shown: Vec<f64> = d.iter().map(|d| d * 1e3).collect();
        println!("order {order}: contour differences {shown:.2?} mm, ratios {ratios:.2?}");
        if order == 2 {
            assert!(d.iter().all(|&d| d > 0.0), "{d:?}");
            assert!(ratios.iter().all(|&r| r > 1.0), "{ratios:?}");
        }
    }
}

#[test]
fn scenarios_choose_the_order_and_refuse_it_where_it_does_not_exist() {
    // The shipped dense collapse runs at order 2 (Heun's stage), and to 0.05 s keeps
    // its grains; the Appendix B scheme and the submarine model refuse order 2 with an
    // error naming numerics.order and saying why.
    use granflow::output::memory::MemorySink;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let load = |file: &str, sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        granflow::scenario::load_file(&dir.join(file), &sets)
    };
    let scn = load(
        "dilatancy_dense.toml",
        &["numerics.order=2", "time.t_end=0.05", "domain.cells=160"],
    )
    .unwrap();
    let mut sim = granflow::setup::build_dilatant(&scn);
    assert_eq!(sim.stage_names(), ["ssp_rk2"]);
    let grains = |s: &DilatantState| (1..=s.nx).map(|j| s.phi[j] * s.h[j]).sum::<f64>();
    let before = grains(&sim.state);
    sim.run(&mut MemorySink::default(), &mut |_| {}).unwrap();
    assert!((grains(&sim.state) / before - 1.0).abs() < 1e-13);
    let e = load(
        "dilatancy_dense.toml",
        &["numerics.order=2", "dilatancy.scheme=\"appendix_b\""],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("numerics.order") && e.contains("split"), "{e}");
    let e = load("submarine_landslide.toml", &["numerics.order=2"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("numerics.order") && e.contains("submarine"),
        "{e}"
    );
}
