//! The multilayer weakly non-hydrostatic model (seed 003): the exact projection's
//! constraint after every step, conservation and positivity, the well-balanced test
//! of Table 6, the hydrostatic path left untouched, and determinism.

mod common;

use std::path::Path;

use granflow::model::granular::Granular;
use granflow::numerics::projection::multilayer::MultilayerOperator;
use granflow::output::memory::MemorySink;
use granflow::scenario::load_file;
use granflow::setup::build_granular;
use granflow::simulation::Simulation;

type Sim = Simulation<Granular>;

fn build(file: &str, sets: &[&str]) -> Sim {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    let scn = load_file(&path, &sets).expect("scenario loads");
    build_granular(&scn)
}

fn run(sim: &mut Sim) -> MemorySink {
    let mut sink = MemorySink::default();
    sim.run(&mut sink, &mut |_| {}).expect("run succeeds");
    sink
}

/// Advances `steps` steps, checking the discrete constraints after each projection;
/// returns the worst relative residual and the largest number of constrained
/// unknowns seen.
fn worst_constraint_residual(sim: &mut Sim, steps: usize) -> (f64, usize) {
    let mut op = MultilayerOperator::new(&sim.mesh, &sim.state.l);
    let (mut worst, mut constrained) = (0.0f64, 0usize);
    for _ in 0..steps {
        let dt = sim.step(f64::INFINITY).expect("step succeeds");
        sim.t += dt;
        op.update(&sim.mesh, &sim.state);
        let r = op.residual(&sim.state);
        assert!(r.relative().is_finite());
        worst = worst.max(r.relative());
        constrained = constrained.max(r.faces);
    }
    (worst, constrained)
}

#[test]
fn discrete_constraints_hold_after_every_projection() {
    let cases: [(&str, &[&str]); 3] = [
        // §5.1 collapse, wall + outflow, a film (the erodible bed) ahead of the front
        (
            "nh_multilayer_collapse.toml",
            &["domain.cells=160", "model.layers=6"],
        ),
        // §5.2, two outflows, every face wet
        (
            "nh_multilayer_convergence.toml",
            &["domain.cells=100", "model.layers=4"],
        ),
        // Cartesian wedge: bed slopes in 𝒯 (the ∂_X b terms)
        (
            "nh_coordinates_wedge_cartesian.toml",
            &["model.layers=3", "domain.cells=200"],
        ),
    ];
    for (file, sets) in cases {
        let mut sim = build(file, sets);
        let (worst, faces) = worst_constraint_residual(&mut sim, 150);
        println!("{file}: worst relative residual over 150 steps = {worst:.2e} ({faces} unknowns)");
        assert!(faces > 100, "{file}: only {faces} constrained unknowns");
        assert!(worst <= 1e-10, "{file}: relative residual {worst:e}");
    }
}

#[test]
fn collapse_conserves_mass_and_keeps_h_nonnegative() {
    // Between two walls so that no mass leaves.
    let mut sim = build(
        "nh_multilayer_collapse.toml",
        &[
            "domain.cells=160",
            "model.layers=5",
            "boundary.right=wall",
            "domain.x_max=1.0",
            "time.t_end=0.6",
            "output.every=0.05",
        ],
    );
    let mass = |h: &[f64]| h.iter().sum::<f64>();
    let m0 = mass(sim.state.h_interior());
    let sink = run(&mut sim);
    assert!(sink.snapshots.len() > 10);
    for s in &sink.snapshots {
        assert!(s.h.iter().all(|&h| h >= 0.0 && h.is_finite()));
        assert!(
            (mass(&s.h) - m0).abs() <= 1e-13 * m0,
            "{} vs {m0}",
            mass(&s.h)
        );
        let w = s.w.as_ref().expect("w is written");
        assert!(w.iter().all(|w| w.is_finite() && w.abs() < 5.0));
    }
    // The non-hydrostatic pressure is written at the N + 1 interfaces.
    let last = sink.snapshots.last().unwrap();
    let p = last.p_nh.as_ref().expect("p_nh is written");
    assert_eq!(p.len(), 6 * 161);
    assert!(p.iter().any(|&p| p != 0.0));
    assert!(p[5 * 161..].iter().all(|&p| p == 0.0), "surface row is 0");
}

/// L1 departures from the initial state (seed 003 eq. 35), maximal over the snapshots:
/// Δx Σ|h − h⁰|, Δx Σ h/N Σ_α |u_α|, and the same for w.
fn departures_from_rest(sink: &MemorySink, dx: f64, layers: usize) -> [f64; 3] {
    departures_inside(sink, dx, layers, 0)
}

/// [`departures_from_rest`] over the cells `cut..nx − cut`.
fn departures_inside(sink: &MemorySink, dx: f64, layers: usize, cut: usize) -> [f64; 3] {
    let h0 = &sink.snapshots[0].h;
    let nx = h0.len();
    let cells = cut..nx - cut;
    let mut worst = [0.0f64; 3];
    for snap in &sink.snapshots {
        let eh: f64 = cells
            .clone()
            .map(|i| (snap.h[i] - h0[i]).abs())
            .sum::<f64>()
            * dx;
        let layer_sum = |v: &[f64]| -> f64 {
            cells
                .clone()
                .map(|i| {
                    snap.h[i] / layers as f64
                        * (0..layers).map(|a| v[a * nx + i].abs()).sum::<f64>()
                })
                .sum::<f64>()
                * dx
        };
        let eu = layer_sum(&snap.u);
        let ew = layer_sum(snap.w.as_ref().expect("w"));
        worst = [worst[0].max(eh), worst[1].max(eu), worst[2].max(ew)];
    }
    worst
}

/// Seed 003 §5.3, Table 6 away from the outflows: without the 3 cells next to each
/// outflow boundary the departures from rest of the NH multilayer model are those of
/// the hydrostatic one and proportional to δ (measured h: 4.8e-4, 3.7e-9, 2.6e-14 for
/// δ = 1e-5, 1e-10, 1e-15), within the bound the hydrostatic multilayer test uses
/// (100 δ for h, 300 δ for u and w).
#[test]
fn mass_at_repose_stays_at_rest_to_order_delta_away_from_the_outflows() {
    for delta in [1e-5, 1e-10, 1e-15] {
        let mut sim = build(
            "nh_multilayer_at_rest.toml",
            &[&format!("rheology.delta={delta:e}")],
        );
        let sink = run(&mut sim);
        let [eh, eu, ew] = departures_inside(&sink, sim.mesh.dx, sim.state.layers, 3);
        println!("  δ = {delta:.0e}, inside: {eh:.3e} {eu:.3e} {ew:.3e}");
        assert!(
            eh <= 100.0 * delta && eu <= 300.0 * delta && ew <= 300.0 * delta,
            "δ = {delta}: {eh:e} {eu:e} {ew:e}"
        );
    }
}

/// Seed 003 §5.3, Table 6 (a): errors of the order of δ (paper: h 5.34e-5, 5.34e-10,
/// 2.99e-16; u 5.38e-5, 5.39e-10, 5.39e-15; w 4.21e-5, 4.21e-10, 4.21e-15).
///
/// KNOWN FAILURE (issue 10, open): measured h, u, w errors 6.3e-4, 1.6e-3, 1.1e-3
/// (δ = 1e-5), 1.3e-8, 3.0e-8, 2.9e-8 (δ = 1e-10) and 1.2e-13 for h (δ = 1e-15):
/// proportional to δ, but 130 δ for h at δ = 1e-10 against the 100 δ bound (the
/// hydrostatic model: 70 δ; the paper: 5.3 δ). At t = 1 s, 9.3e-9 of the 1.3e-8 are in
/// the 3 cells next to each outflow (hydrostatic: 3.4e-9 of 7.0e-9), growing linearly
/// in time, and the NH bed pressure there is 10× its value inside (2.7e-7 and 5.7e-7
/// against ~3e-8). Cause found: the outflow treatment of the projection. Seed 003
/// eq. (37) drops the constraint at the two outermost faces and copies p̃ from the
/// third (a non-symmetric system); ours merges the edge face into its neighbour and
/// imposes the sum of their constraints (symmetric), in which the edge cell has no
/// horizontal mass flux through the boundary face (the ghost column is not part of
/// 𝒯), so the creep leaving the domain reads as a divergence that the projection
/// answers with pressure. p̃ = 0 at the outflow faces instead (Dirichlet) is far worse
/// (1.8e-5 for h). The fix is eq. (37) itself, which needs a non-symmetric banded
/// solve (LU) at the two ends; not done (docs/validation.md).
#[test]
fn mass_at_repose_stays_at_rest_to_order_delta() {
    println!(
        "seed 003 Table 6 with the NH multilayer model (10 layers, t = 1 s): δ, errors h, u, w"
    );
    for delta in [1e-5, 1e-10, 1e-15] {
        let mut sim = build(
            "nh_multilayer_at_rest.toml",
            &[&format!("rheology.delta={delta:e}")],
        );
        let sink = run(&mut sim);
        assert!(sim.steps > 400, "{} steps", sim.steps);
        let [eh, eu, ew] = departures_from_rest(&sink, sim.mesh.dx, sim.state.layers);
        println!("  δ = {delta:.0e}: {eh:.3e} {eu:.3e} {ew:.3e}");
        assert!(
            eh <= 100.0 * delta + 1e-12
                && eu <= 300.0 * delta + 1e-12
                && ew <= 300.0 * delta + 1e-12,
            "δ = {delta}: {eh:e} {eu:e} {ew:e}"
        );
    }
    // 0.01° beyond the repose slope the mass moves (seed 003 §5.3).
    let mut sim = build(
        "nh_multilayer_at_rest.toml",
        &[
            "rheology.delta=1e-10",
            "initial.h=\"0.8 - tan(20.01*deg)*(x-2) - b\"",
        ],
    );
    let sink = run(&mut sim);
    let [eh, eu, _] = departures_from_rest(&sink, sim.mesh.dx, sim.state.layers);
    assert!(eh > 1e-5 && eu > 1e-5, "{eh:e} {eu:e}");
}

use common::fingerprint;

/// (h, hu) fingerprint of the §5.1 collapse with 4 layers switched to the hydrostatic
/// pressure, recorded with the code of main at ecc2685 (before this model): the
/// hydrostatic multilayer path is untouched by the non-hydrostatic one. Re-recorded
/// once, deliberately, when step 1's gravity source of a draining cell moved to the
/// mass that stays in it (issue 13 item 3; was 0x388f_a4ca_e881_ba7f).
const HYDROSTATIC_FINGERPRINT: u64 = 0x171c_610c_748c_59e7;

#[test]
fn hydrostatic_switch_gives_the_hydrostatic_multilayer_model_bit_for_bit() {
    let mut sim = build(
        "nh_multilayer_collapse.toml",
        &[
            "domain.cells=120",
            "model.layers=4",
            "time.t_end=1.0",
            "model.pressure=hydrostatic",
        ],
    );
    assert_eq!(
        sim.stage_names(),
        vec!["hyperbolic", "viscous"],
        "no NH stage"
    );
    run(&mut sim);
    assert!(sim.state.nh.is_none() && sim.state.tracers.is_empty());
    let hash = fingerprint(sim.state.h.iter().chain(&sim.state.hu));
    println!(
        "hydrostatic fingerprint {hash:#x} after {} steps",
        sim.steps
    );
    assert_eq!(hash, HYDROSTATIC_FINGERPRINT);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let sets = ["domain.cells=120", "model.layers=5", "time.t_end=0.15"];
    let hashes: Vec<u64> = [1, 2]
        .iter()
        .map(|&threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut sim = build("nh_multilayer_collapse.toml", &sets);
                run(&mut sim);
                fingerprint(
                    sim.state
                        .h
                        .iter()
                        .chain(&sim.state.hu)
                        .chain(sim.state.hw()),
                )
            })
        })
        .collect();
    assert_eq!(hashes[0], hashes[1]);
}

/// Final (h, u_α, w_α) of the §5.2 convergence run on (cells, layers), physical cells;
/// u and w layer-major (α·nx + i).
fn convergence_run(cells: usize, layers: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, f64) {
    convergence_run_with(cells, layers, &[])
}

/// [`convergence_run`] with more scenario overrides (`key=value`).
fn convergence_run_with(
    cells: usize,
    layers: usize,
    extra: &[&str],
) -> (Vec<f64>, Vec<f64>, Vec<f64>, f64) {
    let (c, l) = (
        format!("domain.cells={cells}"),
        format!("model.layers={layers}"),
    );
    let sets: Vec<&str> = [c.as_str(), l.as_str()]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    let mut sim = build("nh_multilayer_convergence.toml", &sets);
    run(&mut sim);
    assert!((sim.t - 0.15).abs() < 1e-12);
    let s = &sim.state;
    let (nx, n) = (cells, layers);
    let h = s.h_interior().to_vec();
    let (mut u, mut w) = (vec![0.0; n * nx], vec![0.0; n * nx]);
    for i in 0..nx {
        for a in 0..n {
            let k = (i + 1) * n + a;
            u[a * nx + i] = s.hu[k] / s.h[i + 1];
            if s.nh.is_some() {
                w[a * nx + i] = s.hw()[k] / s.h[i + 1];
            }
        }
    }
    (h, u, w, sim.mesh.dx)
}

/// The layered L1 norm of seed 003 eq. (35): Δx Σ_i (h_i/N) Σ_α |v_{α,i} − r_{α,i}|,
/// for fields stored layer-major (`v[α·nx + i]`).
fn layered_l1(h: &[f64], v: &[f64], r: &[f64], nx: usize, n: usize, dx: f64) -> f64 {
    (0..nx)
        .map(|i| {
            h[i] / n as f64
                * (0..n)
                    .map(|a| (v[a * nx + i] - r[a * nx + i]).abs())
                    .sum::<f64>()
        })
        .sum::<f64>()
        * dx
}

/// The reference averaged onto the coarse cells and layers ("projections of the
/// reference solutions onto the spaces of the local solutions", seed 003 eq. 35).
fn project(v: &[f64], nx_f: usize, n_f: usize, nx: usize, n: usize) -> Vec<f64> {
    let (rx, rz) = (nx_f / nx, n_f / n);
    let mut out = vec![0.0; n * nx];
    for a in 0..n {
        for i in 0..nx {
            let mut s = 0.0;
            for b in a * rz..(a + 1) * rz {
                for j in i * rx..(i + 1) * rx {
                    s += v[b * nx_f + j];
                }
            }
            out[a * nx + i] = s / (rx * rz) as f64;
        }
    }
    out
}

/// Seed 003 §5.2, Table 5: L1 errors (eq. 35) of h, u(z), w(z) at t = 0.15 s refining
/// (Nx, N) together, against (1600, 32) (the paper's reference is (6400, 128)). Paper:
/// errors of h 1.59e-2, 1.22e-2, 6.40e-3 on (100, 2), (200, 4), (400, 8), orders 0.39,
/// 0.93 (then 1.06, 1.18). Measured: h 2.245e-3, 1.269e-3, 7.201e-4; u 7.372e-3,
/// 5.725e-3, 4.177e-3; w 3.712e-3, 2.709e-3, 1.862e-3 (orders h 0.82/0.82, u 0.36/0.45,
/// w 0.45/0.54). The whole family up to (1600, 32) against (6400, 128) is
/// scripts/table5_convergence.py (docs/validation.md): last orders h 1.15, u 0.79,
/// w 0.80 (paper 1.18, 1.07, 1.18; 1.03, 0.94, 0.94 with `rheology.viscosity =
/// "implicit"`); the differences between consecutive runs fall at
/// order >= 1 only from (3200, 64) to (6400, 128), too costly for a test.
/// Why u and w converge slowly: see [`vertical_refinement_converges_when_the_basal_friction_does_not_depend_on_n`]
/// and docs/validation.md.
#[test]
fn convergence_at_first_order_table_5() {
    let (nx_f, n_f) = (1600, 32);
    let (h_r, u_r, w_r, _) = convergence_run(nx_f, n_f);
    let mut errors = Vec::new();
    println!("seed 003 Table 5 against (1600, 32): (Nx, N), L1 errors of h, u(z), w(z)");
    for (nx, n) in [(100, 2), (200, 4), (400, 8)] {
        let (h, u, w, dx) = convergence_run(nx, n);
        let (hr, ur, wr) = (
            project(&h_r, nx_f, 1, nx, 1),
            project(&u_r, nx_f, n_f, nx, n),
            project(&w_r, nx_f, n_f, nx, n),
        );
        let eh: f64 = h.iter().zip(&hr).map(|(a, b)| (a - b).abs()).sum::<f64>() * dx;
        let layered = |v: &[f64], r: &[f64]| layered_l1(&h, v, r, nx, n, dx);
        let e = [eh, layered(&u, &ur), layered(&w, &wr)];
        println!("  ({nx}, {n}): {:.3e} {:.3e} {:.3e}", e[0], e[1], e[2]);
        errors.push(e);
    }
    for k in 1..errors.len() {
        let order: Vec<f64> = (0..3)
            .map(|v| (errors[k - 1][v] / errors[k][v]).log2())
            .collect();
        println!("  orders {:.2} {:.2} {:.2}", order[0], order[1], order[2]);
    }
    // h converges at first order (measured 0.82, 0.82; paper 0.39, 0.93). u(z) and
    // w(z) converge more slowly here (measured 0.36/0.45 and 0.45/0.54 against the
    // paper's 0.66/1.18 and 0.68/1.29), so only their decrease is asserted. The
    // reference is only 4 times finer than the finest run, which biases the last orders
    // upwards, not downwards. The errors are in the moving core (not at the outflows
    // or in the 2 cm film), and come from two parts (docs/validation.md): in z, the
    // basal inertial number uses the shear rate u_1/h_1 (seed 001 eq. 26), so the basal
    // μ changes with N (the test below); in x, the in-depth profile is pre-asymptotic
    // (at N = 8 against (6400, 8): u orders 0.43, 0.53, 0.68 up to 1600 cells, ū 0.83,
    // 0.90, 0.96).
    let order_h = (errors[1][0] / errors[2][0]).log2();
    assert!((0.6..=1.4).contains(&order_h), "order of h: {order_h}");
    for v in 1..3 {
        assert!(
            errors[2][v] < errors[1][v] && errors[1][v] < errors[0][v],
            "{errors:?}"
        );
    }
    assert!(errors[2][0] < errors[0][0] / 2.0);
}

/// The vertical discretisation itself converges: on the §5.2 set-up at 400 cells with
/// a constant Coulomb μ = tan 25.5° (basal and internal), refining the layers N = 2, 4,
/// 8 against N = 32 gives u(z) errors falling at second order (measured 9.73e-4,
/// 2.63e-4, 6.17e-5: orders 1.89, 2.09). With μ(I) the same refinement gives 4.03e-3,
/// 3.12e-3, 2.47e-3 (orders 0.37, 0.34), all of it in the depth-averaged velocity: the
/// basal inertial number I_{1/2} uses the shear rate u_1/h_1 of the bottom layer
/// (seed 001 eq. 26, seed 003 eq. 11), which grows with N wherever the column slides,
/// so the basal friction μ(I_{1/2}) moves towards μ_2 as N grows. That is the slow
/// part of Table 5's u(z), w(z) orders (the model as printed, not a solver error).
#[test]
fn vertical_refinement_converges_when_the_basal_friction_does_not_depend_on_n() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/nh_multilayer_convergence.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let coulomb = text
        .replace("law = \"mu_i\"", "law = \"coulomb\"")
        .replace("mu_s_deg = 25.5", "mu_deg = 25.5")
        .lines()
        .filter(|l| !l.starts_with("mu_2_deg") && !l.starts_with("i0 ="))
        .collect::<Vec<_>>()
        .join("\n");
    assert!(coulomb.contains("law = \"coulomb\"") && coulomb.contains("mu_deg"));
    let run = |text: &str, layers: usize| -> (Vec<f64>, Vec<f64>) {
        let sets = vec![
            "domain.cells=400".to_string(),
            format!("model.layers={layers}"),
        ];
        let scn = granflow::scenario::load_str(text, path.parent().unwrap(), &sets).unwrap();
        let mut sim = build_granular(&scn);
        run(&mut sim);
        let s = &sim.state;
        let h = s.h_interior().to_vec();
        let mut u = vec![0.0; layers * 400];
        for i in 0..400 {
            for a in 0..layers {
                u[a * 400 + i] = s.hu[(i + 1) * layers + a] / s.h[i + 1];
            }
        }
        (h, u)
    };
    let dx = 2.0 / 400.0;
    let errors = |text: &str| -> Vec<f64> {
        let (_, u_ref) = run(text, 32);
        [2, 4, 8]
            .iter()
            .map(|&n| {
                let (h, u) = run(text, n);
                let ur = project(&u_ref, 400, 32, 400, n);
                layered_l1(&h, &u, &ur, 400, n, dx)
            })
            .collect()
    };
    let order = |e: &[f64], k: usize| (e[k - 1] / e[k]).log2();
    let c = errors(&coulomb);
    let m = errors(&text);
    println!("u(z) errors, N = 2, 4, 8 against 32 at 400 cells: Coulomb {c:?}, mu(I) {m:?}");
    println!(
        "orders: Coulomb {:.2} {:.2}, mu(I) {:.2} {:.2}",
        order(&c, 1),
        order(&c, 2),
        order(&m, 1),
        order(&m, 2)
    );
    assert!(order(&c, 1) > 1.5 && order(&c, 2) > 1.5, "{c:?}");
    assert!(order(&m, 1) < 0.8 && order(&m, 2) < 0.8, "{m:?}");
}

/// Why u(z) and w(z) converge slowly in x along Table 5 (docs/validation.md): at a fixed
/// grid (400 cells, N = 8) the time step alone moves the in-depth profile. Halving the
/// CFL from the scenario's 0.7 down to 0.7/64, the u(z) differences (eq. 35 norm)
/// between consecutive CFLs are 1.144e-3, 9.983e-4, 8.753e-4, 6.226e-4, 3.880e-4,
/// 2.163e-4: orders 0.20, 0.19, 0.49, 0.68, 0.84. It is the bottom layer (u_1 in the
/// cell at x = 0.5 m: 0.419, 0.407, 0.395, 0.383, 0.371, 0.363, 0.358 m/s); the same
/// differences appear at 800 cells one CFL halving earlier, i.e. at the same time step:
/// first order in time only for dt below about 5e-5 s, so refining x at CFL 0.7 is
/// pre-asymptotic for the profile up to about 10^4 cells. The hydrostatic multilayer
/// model shows it too (docs/validation.md), so it is the viscous/friction step.
#[test]
fn in_depth_profile_is_first_order_in_time_only_below_the_scenario_cfl() {
    let (nx, n) = (400, 8);
    let runs: Vec<_> = (0..7)
        .map(|k| {
            let cfl = format!("time.cfl={}", 0.7 / f64::from(1 << k));
            convergence_run_with(nx, n, &[&cfl])
        })
        .collect();
    let diffs: Vec<f64> = runs
        .windows(2)
        .map(|p| {
            let ((h, u, _, dx), (_, u_f, _, _)) = (&p[0], &p[1]);
            layered_l1(h, u, u_f, nx, n, *dx)
        })
        .collect();
    let orders: Vec<f64> = diffs.windows(2).map(|d| (d[0] / d[1]).log2()).collect();
    let i05 = ((0.5 + 0.5) / runs[0].3) as usize;
    let u1: Vec<f64> = runs.iter().map(|r| r.1[i05]).collect();
    println!(
        "u(z) differences between CFL 0.7/2^k and 0.7/2^(k+1), 400 cells, N = 8: {}",
        diffs
            .iter()
            .map(|d| format!("{d:.3e}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("orders {orders:.2?}; bottom-layer u at x = 0.5 m: {u1:.3?}");
    // Pre-asymptotic at the scenario's CFL (measured 0.20, 0.19), first order once the
    // step is small enough (measured 0.84 at the last halving).
    assert!(orders[0] < 0.4 && orders[1] < 0.4, "{orders:?}");
    let last = orders[orders.len() - 1];
    assert!((0.7..=1.3).contains(&last), "{orders:?}");
    assert!(orders.windows(2).skip(1).all(|o| o[1] > o[0]), "{orders:?}");
    assert!(u1.windows(2).all(|v| v[1] < v[0]), "{u1:?}");
}

/// With `rheology.viscosity = "implicit"` (the viscosities, inertial numbers and
/// basal friction of step 2 at the new speed, iterated to convergence: docs/numerics.md)
/// the in-depth profile of the test above is first order in time from the scenario's
/// CFL 0.7 on: the frozen viscosities at t^n were the pre-asymptotic part.
#[test]
fn implicit_viscosity_makes_the_in_depth_profile_first_order_in_time_at_the_scenario_cfl() {
    let (nx, n) = (400, 8);
    let runs: Vec<_> = (0..5)
        .map(|k| {
            let cfl = format!("time.cfl={}", 0.7 / f64::from(1 << k));
            convergence_run_with(nx, n, &[&cfl, "rheology.viscosity=implicit"])
        })
        .collect();
    let diffs: Vec<f64> = runs
        .windows(2)
        .map(|p| {
            let ((h, u, _, dx), (_, u_f, _, _)) = (&p[0], &p[1]);
            layered_l1(h, u, u_f, nx, n, *dx)
        })
        .collect();
    let orders: Vec<f64> = diffs.windows(2).map(|d| (d[0] / d[1]).log2()).collect();
    let i05 = ((0.5 + 0.5) / runs[0].3) as usize;
    let u1: Vec<f64> = runs.iter().map(|r| r.1[i05]).collect();
    println!(
        "implicit: u(z) differences between CFL 0.7/2^k and 0.7/2^(k+1), 400 cells, N = 8: {}",
        diffs
            .iter()
            .map(|d| format!("{d:.3e}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("orders {orders:.2?}; bottom-layer u at x = 0.5 m: {u1:.4?}");
    // Frozen at CFL 0.7 (the test above): difference 1.144e-3, orders 0.20, 0.19,
    // bottom u 0.419 m/s against 0.358 at CFL 0.7/64. Implicit (measured): 1.958e-4,
    // 1.036e-4, 6.109e-5, 3.749e-5, orders 0.92, 0.76, 0.70, bottom u 0.3548 ... 0.3536.
    // The orders fall below 1 towards small steps where the bed stops at the rear of
    // the mass (x in [0, 0.3] m), less so with a larger δ (δ = 1e-3: 0.94, 0.91, 0.78;
    // δ = 0.1: 0.98, 0.95, 0.95); the hydrostatic model is exactly first order (test
    // below; docs/validation.md).
    assert!((0.8..=1.2).contains(&orders[0]), "{orders:?}");
    assert!(orders.iter().all(|o| (0.6..=1.2).contains(o)), "{orders:?}");
    assert!(diffs[0] < 1144e-6 / 4.0, "{diffs:?}");
    assert!(u1.windows(2).all(|v| v[1] < v[0]), "{u1:?}");
    assert!(u1[0] - u1[4] < 0.005, "{u1:?}");
}

/// (h, hu, hw) fingerprint of the §5.2 run at (400, 8), recorded with the code before
/// `rheology.viscosity` existed (deea950; the fingerprints example gives identical
/// hashes for every bundled scenario before and after): the default is the frozen
/// step, bit for bit, and "implicit" is another scheme.
const CONVERGENCE_FINGERPRINT: u64 = 0x2ab8_421d_a468_127f;

#[test]
fn default_viscosity_is_the_frozen_step_bit_for_bit() {
    let hash = |extra: &[&str]| {
        let mut sets = vec!["domain.cells=400", "model.layers=8"];
        sets.extend_from_slice(extra);
        let mut sim = build("nh_multilayer_convergence.toml", &sets);
        run(&mut sim);
        fingerprint(
            sim.state
                .h
                .iter()
                .chain(&sim.state.hu)
                .chain(sim.state.hw()),
        )
    };
    let default = hash(&[]);
    println!("convergence fingerprint {default:#x}");
    assert_eq!(default, CONVERGENCE_FINGERPRINT);
    assert_eq!(hash(&["rheology.viscosity=frozen"]), default);
    assert_ne!(hash(&["rheology.viscosity=implicit"]), default);
}

/// `rheology.viscosity = "implicit"` converges (within its default tolerance and
/// iteration limit, else the run fails with a solver error) on every bundled
/// multilayer scenario: δ and bound regularisations, Coulomb beds that stop, thin
/// 20-layer columns (§5.1), sidewalls, hydrostatic and non-hydrostatic.
#[test]
fn implicit_viscosity_converges_on_every_bundled_multilayer_scenario() {
    for file in [
        "at_rest_random_bed_multilayer.toml",
        "bagnold.toml",
        "erodible_bed.toml",
        "nh_multilayer_at_rest.toml",
        "nh_multilayer_collapse.toml",
        "nh_multilayer_convergence.toml",
        "sidewall_channel.toml",
        "transient_channel.toml",
    ] {
        let mut sim = build(file, &["rheology.viscosity=implicit", "time.t_end=0.05"]);
        assert!(sim.state.layers > 1, "{file}");
        run(&mut sim);
        assert!(
            sim.state
                .h
                .iter()
                .chain(&sim.state.hu)
                .all(|v| v.is_finite()),
            "{file}"
        );
    }
}

/// The hydrostatic multilayer model on the same set-up (`model.pressure =
/// "hydrostatic"`, 400 cells, N = 8): frozen viscosities give a plug at CFL 0.7 and no
/// order in time (u(z) differences between CFL 0.7/2^k and 0.7/2^(k+1): 3.217e-4,
/// 3.294e-4, 5.556e-4, 4.885e-4, orders −0.03, −0.75, 0.19), implicit ones exactly
/// first order (3.156e-4, 1.564e-4, 7.808e-5, 3.906e-5: orders 1.01, 1.00, 1.00). The
/// non-hydrostatic model's orders above fall below 1 at small steps: what the
/// non-hydrostatic step adds (the explicit p^nh at t^n in the stresses, the projection
/// after the viscous step) meets the stiff δ-regularised plug at the rear of the mass.
#[test]
fn implicit_viscosity_makes_the_hydrostatic_multilayer_profile_first_order_in_time() {
    let (nx, n) = (400, 8);
    let runs: Vec<_> = (0..5)
        .map(|k| {
            let cfl = format!("time.cfl={}", 0.7 / f64::from(1 << k));
            convergence_run_with(
                nx,
                n,
                &[
                    &cfl,
                    "rheology.viscosity=implicit",
                    "model.pressure=hydrostatic",
                ],
            )
        })
        .collect();
    let diffs: Vec<f64> = runs
        .windows(2)
        .map(|p| {
            let ((h, u, _, dx), (_, u_f, _, _)) = (&p[0], &p[1]);
            layered_l1(h, u, u_f, nx, n, *dx)
        })
        .collect();
    let orders: Vec<f64> = diffs.windows(2).map(|d| (d[0] / d[1]).log2()).collect();
    println!("hydrostatic, implicit: differences {diffs:?}, orders {orders:.2?}");
    assert!(orders.iter().all(|o| (0.9..=1.1).contains(o)), "{orders:?}");
}
