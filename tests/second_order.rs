//! The second-order scheme (`numerics.order = 2`: MUSCL reconstruction in the
//! hydrostatic reconstruction, Heun's method around the splitting; docs/numerics.md,
//! "Second order"): observed orders on a smooth flow and at a dry front, and every
//! property of the first-order scheme in both orders (mass, lake at rest, rest below
//! repose, stopping, positivity at wet/dry fronts, symmetry).

use crate::common::{l1, observed_order, run, tan_deg, Case};
use granflow::model::granular::Granular;
use granflow::physics::GRAVITY as G;
use granflow::scenario::{BoundaryKind, FrictionLaw, Limiter, MonolayerShear, Numerics};
use granflow::simulation::Simulation;

pub(crate) const ORDER_1: Numerics = Numerics {
    order: 1,
    limiter: Limiter::VanLeer,
};

pub(crate) fn order_2(limiter: Limiter) -> Numerics {
    Numerics { order: 2, limiter }
}

/// Both orders, with the default limiter at order 2.
pub(crate) fn both() -> [Numerics; 2] {
    [ORDER_1, order_2(Numerics::default().limiter)]
}

/// Deterministic stand-in for a random number in [0, 1).
pub(crate) fn rand01(x: f64) -> f64 {
    let mut z = x.to_bits().wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

pub(crate) fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// A smooth frictionless flow: a hump of water (10 cm on 1 m) over a smooth bed bump,
/// on [0, 10] m with walls, to t = 0.5 s (the two waves have travelled 1.6 m, no
/// shock has formed, nothing has reached a wall). Returns h at the end.
fn smooth_wave(numerics: Numerics, cells: usize) -> Vec<f64> {
    let mut case = Case::new(0.0, 10.0, cells);
    case.numerics = numerics;
    case.t_end = 0.5;
    case.every = 0.5;
    let bed = |x: f64| 0.1 * (-(x - 6.0).powi(2)).exp();
    let mut sim = case.build(
        bed,
        move |x, b| 1.0 + 0.1 * (-2.0 * (x - 4.5).powi(2)).exp() - b,
        |_| 0.0,
    );
    let (sink, summary) = run(&mut sim);
    assert_eq!(summary.t_end, 0.5);
    sink.snapshots.last().unwrap().h.clone()
}

/// Cell means of a fine solution on a grid `factor` times coarser.
fn coarsen(fine: &[f64], factor: usize) -> Vec<f64> {
    fine.chunks(factor)
        .map(|c| c.iter().sum::<f64>() / factor as f64)
        .collect()
}

/// L1 errors of h on 100, 200, 400 cells against the same scheme on 3200 cells, and
/// the observed order.
fn smooth_convergence(numerics: Numerics) -> (Vec<f64>, f64) {
    let reference = smooth_wave(numerics, 3200);
    let cells = [100, 200, 400];
    let errors: Vec<f64> = cells
        .iter()
        .map(|&n| {
            let h = smooth_wave(numerics, n);
            l1(&h, &coarsen(&reference, 3200 / n), 10.0 / n as f64)
        })
        .collect();
    let dx: Vec<f64> = cells.iter().map(|&n| 10.0 / n as f64).collect();
    (errors.clone(), observed_order(&dx, &errors))
}

#[test]
#[ignore = "slow: refinement study"]
fn smooth_flow_converges_at_second_order_with_order_2() {
    for limiter in [Limiter::Minmod, Limiter::VanLeer, Limiter::Mc] {
        let (errors, order) = smooth_convergence(order_2(limiter));
        eprintln!("order 2, {limiter:?}: L1(h) {errors:?}, observed order {order:.3}");
        assert!(order >= 1.8, "{limiter:?}: observed order {order}");
    }
    let (errors, order) = smooth_convergence(ORDER_1);
    eprintln!("order 1: L1(h) {errors:?}, observed order {order:.3}");
    assert!(
        (0.9..1.3).contains(&order),
        "order 1: observed order {order}"
    );
}

/// The Ritter dam break (h = 1 m | dry, flat bed) on [−2, 2.5] m at t = 0.3 s: the
/// front (largest x with h > 1 mm) and its distance to the exact 1 mm contour
/// x = t (2c₀ − 3√(g·1 mm)), relative to that distance from the dam.
fn ritter_front(numerics: Numerics, cells: usize) -> (f64, f64, Vec<f64>) {
    let mut case = Case::new(-2.0, 2.5, cells);
    case.numerics = numerics;
    case.t_end = 0.3;
    case.every = 0.3;
    let mut sim = case.build(|_| 0.0, |x, _| if x < 0.0 { 1.0 } else { 0.0 }, |_| 0.0);
    let (sink, _) = run(&mut sim);
    let last = sink.snapshots.last().unwrap();
    assert!(last.h.iter().all(|&h| h >= 0.0));
    let front = sim.diagnostics().front_x;
    let exact = 0.3 * (2.0 * G.sqrt() - 3.0 * (G * 1e-3).sqrt());
    (front, (exact - front) / exact, last.h.clone())
}

#[test]
fn ritter_front_error_at_2048_cells_in_both_orders() {
    let (front_1, lag_1, _) = ritter_front(ORDER_1, 2048);
    let (front_2, lag_2, _) = ritter_front(order_2(Numerics::default().limiter), 2048);
    eprintln!("Ritter, 2048 cells: front {front_1:.4} m (lag {lag_1:.4}) at order 1, {front_2:.4} m (lag {lag_2:.4}) at order 2");
    // Measured: lag 0.0729 at order 1, 0.0091 at order 2 (MC), Basilisk's
    // saint-venant.h 0.0116 (second order) and 0.0729 (first order).
    assert!(lag_1 > 0.0 && lag_1 < 0.075, "order 1 lag {lag_1}");
    assert!(lag_2.abs() < 0.01, "order 2 lag {lag_2}");
}

/// The front's lag converges at order ≥ 0.9 with order 2; order 1 is stated, not
/// asserted beyond convergence (its 1 mm contour converges at order 0.3–0.5 on these
/// grids: the first-order front is smeared over a number of cells that grows).
#[test]
#[ignore = "slow: refinement study"]
fn ritter_front_converges_at_order_one_with_order_2() {
    let cells = [512, 1024, 2048];
    let dx: Vec<f64> = cells.iter().map(|&n| 4.5 / n as f64).collect();
    for numerics in both() {
        let lags: Vec<f64> = cells.iter().map(|&n| ritter_front(numerics, n).1).collect();
        let order = observed_order(&dx, &lags);
        eprintln!(
            "order {}: Ritter front lags {lags:?}, observed order {order:.3}",
            numerics.order
        );
        assert!(
            lags.windows(2).all(|w| w[1] < w[0] && w[1] > 0.0),
            "{lags:?}"
        );
        if numerics.order == 2 {
            assert!(order >= 0.9, "order 2: front order {order}");
        }
    }
}

/// A dam break over a random bed with a dry patch and random velocities, walls at
/// both ends: h ≥ 0 and finite throughout, mass conserved to round-off.
#[test]
fn wet_dry_fronts_stay_positive_and_mass_is_conserved_in_both_orders() {
    for numerics in both() {
        let mut case = Case::new(0.0, 4.0, 200);
        case.numerics = numerics;
        case.t_end = 1.5;
        case.every = 0.05;
        let bed = |x: f64| 0.3 * (-(x - 2.5).powi(2) * 4.0).exp() + 0.05 * rand01(x);
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
        let m0: f64 = sim.state.h_interior().iter().sum();
        let (sink, summary) = run(&mut sim);
        assert_eq!(
            summary.t_end, 1.5,
            "order {}: {}",
            numerics.order, summary.status
        );
        for snap in &sink.snapshots {
            assert!(snap.h.iter().all(|h| h.is_finite() && *h >= 0.0));
            assert!(snap.u.iter().all(|u| u.is_finite()));
            let m: f64 = snap.h.iter().sum();
            assert!(
                ((m - m0) / m0).abs() < 1e-13,
                "order {}: t = {}: relative mass change {:e}",
                numerics.order,
                snap.t,
                (m - m0) / m0
            );
        }
    }
}

#[test]
fn frictionless_lake_at_rest_over_a_random_bed_in_both_orders() {
    for numerics in both() {
        lake_at_rest_over_a_random_bed(numerics, 1);
    }
}

/// A frictionless lake of `layers` layers over a random bed with emerging islands and
/// submerged bumps stays at rest (|u|, |Δh| ≤ 1e-13) with `numerics`.
pub(crate) fn lake_at_rest_over_a_random_bed(numerics: Numerics, layers: usize) {
    let mut case = Case::new(0.0, 10.0, 200);
    case.numerics = numerics;
    case.layers = layers;
    case.t_end = 1.0;
    case.every = 0.25;
    let bed = |x: f64| 0.7 * rand01(x) * (-(x - 5.0).powi(2) / 8.0).exp();
    let mut sim = case.build(bed, |_, b| (0.5 - b).max(0.0), |_| 0.0);
    let h0 = sim.state.h_interior().to_vec();
    assert!(h0.contains(&0.0), "the bed must emerge somewhere");
    let (sink, _) = run(&mut sim);
    assert!(sim.steps > 50);
    for snap in &sink.snapshots {
        assert_eq!(snap.u.len(), layers * 200);
        assert!(snap.u.iter().all(|u| u.abs() <= 1e-13), "t = {}", snap.t);
        assert!(max_abs_diff(&snap.h, &h0) <= 1e-13, "t = {}", snap.t);
    }
}

/// Escalante et al. 2023, §5.3 (as `well_balanced.rs`): a μ(I) mass (μ_s = tan 20°) on
/// a random bed with a free surface of slope `surface_deg`.
fn random_bed_mass(numerics: Numerics, surface_deg: f64) -> (Vec<f64>, Simulation<Granular>) {
    random_bed_mass_of(numerics, surface_deg, 1)
}

/// [`random_bed_mass`] with `layers` layers.
pub(crate) fn random_bed_mass_of(
    numerics: Numerics,
    surface_deg: f64,
    layers: usize,
) -> (Vec<f64>, Simulation<Granular>) {
    let mut case = Case::new(-3.0, 1.0, 300);
    case.numerics = numerics;
    case.layers = layers;
    case.mesh.left = BoundaryKind::Outflow;
    case.mesh.right = BoundaryKind::Outflow;
    case.law = FrictionLaw::MuI {
        mu_s: tan_deg(20.0),
        mu_2: tan_deg(36.0),
        i0: 0.279,
        shear: MonolayerShear::Bagnold,
    };
    case.t_end = 1.0;
    case.every = 0.25;
    let bed = |x: f64| 2.0 / (x + 4.0) - 0.5 + (-10.0 * (x + 1.5).powi(2)).exp() + 0.15 * rand01(x);
    let slope = tan_deg(surface_deg);
    let sim = case.build(bed, move |x, b| 0.8 - slope * (x - 2.0) - b, |_| 0.0);
    (sim.state.h_interior().to_vec(), sim)
}

#[test]
fn granular_mass_at_repose_stays_exactly_at_rest_and_beyond_it_moves_in_both_orders() {
    for numerics in both() {
        let (h0, mut sim) = random_bed_mass(numerics, 20.0);
        let (sink, _) = run(&mut sim);
        assert!(sim.steps > 100);
        // The tolerances of well_balanced.rs (order 1 holds it to round-off).
        for snap in &sink.snapshots {
            let du = snap.u.iter().fold(0.0f64, |m, u| m.max(u.abs()));
            assert!(
                du <= 1e-12,
                "order {}: t = {}: |u| {du:e}",
                numerics.order,
                snap.t
            );
            let dh = max_abs_diff(&snap.h, &h0);
            assert!(
                dh <= 1e-12,
                "order {}: t = {}: |Δh| {dh:e}",
                numerics.order,
                snap.t
            );
        }
        let (h0, mut sim) = random_bed_mass(numerics, 20.01);
        let (sink, _) = run(&mut sim);
        let last = sink.snapshots.last().unwrap();
        assert!(
            max_abs_diff(&last.h, &h0) > 1e-6,
            "order {}",
            numerics.order
        );
    }
}

/// A uniform Coulomb layer sliding up to rest on a 20° plane (μ = tan 30°): the speed
/// falls at the exact rate g(μ cos θ − sin θ) and stops exactly (every u = 0) right
/// after the exact stop time u₀/(g(μ cos θ − sin θ)) = 0.512 s.
#[test]
fn decelerating_layer_stops_exactly_at_the_exact_time_in_both_orders() {
    let (theta, mu, u0) = (20.0f64, tan_deg(30.0), 1.0);
    let a = G * (mu * theta.to_radians().cos() - theta.to_radians().sin());
    let t_stop = u0 / a;
    for numerics in both() {
        let mut case = Case::new(0.0, 1.0, 40);
        case.numerics = numerics;
        case.mesh.slope_deg = theta;
        case.mesh.left = BoundaryKind::Outflow;
        case.mesh.right = BoundaryKind::Outflow;
        case.law = FrictionLaw::Coulomb { mu };
        case.t_end = 0.8;
        case.every = 0.02;
        let mut sim = case.build(|_| 0.0, |_, _| 0.1, move |_| u0);
        let (sink, _) = run(&mut sim);
        for snap in &sink.snapshots {
            let exact = (u0 - a * snap.t).max(0.0);
            for &u in &snap.u {
                assert!(
                    (u - exact).abs() < 1e-9,
                    "order {}: t = {}: u = {u}, exact {exact}",
                    numerics.order,
                    snap.t
                );
            }
            if snap.t > t_stop {
                assert!(
                    snap.u.iter().all(|&u| u == 0.0),
                    "order {}: t = {}",
                    numerics.order,
                    snap.t
                );
            }
        }
    }
}

/// A Coulomb dam break on a 20° plane with δ = 30° (a mass that stops): it comes to
/// rest exactly (every u = 0) in both orders.
#[test]
fn coulomb_dam_break_on_a_slope_comes_to_rest_in_both_orders() {
    for numerics in both() {
        let mut case = Case::new(-1.0, 4.0, 250);
        case.numerics = numerics;
        case.mesh.slope_deg = 20.0;
        case.law = FrictionLaw::Coulomb { mu: tan_deg(30.0) };
        case.t_end = 4.0;
        case.every = 0.5;
        case.stop_at_rest = true;
        let mut sim = case.build(|_| 0.0, |x, _| if x < 0.0 { 0.2 } else { 0.0 }, |_| 0.0);
        let (sink, summary) = run(&mut sim);
        eprintln!(
            "order {}: {} at t = {} s, front {:.3} m",
            numerics.order,
            summary.status,
            summary.t_end,
            sim.diagnostics().front_x
        );
        assert!(
            summary.t_end < 4.0,
            "order {}: {}",
            numerics.order,
            summary.status
        );
        let last = sink.snapshots.last().unwrap();
        assert!(last.u.iter().all(|&u| u == 0.0));
    }
}

/// A symmetric hump of water on a symmetric bed: the solution stays mirror-symmetric.
/// The cell centres x and −x differ in their last bits, and so do their beds; order 1
/// keeps that round-off (≤ 1e-12), order 2's limiters amplify it where a one-sided
/// difference passes through 0 (switches of φ), so it is held to 1e-9.
#[test]
fn symmetric_flow_stays_symmetric_in_both_orders() {
    for numerics in [ORDER_1, order_2(Limiter::Minmod), order_2(Limiter::Mc)] {
        let mut case = Case::new(-5.0, 5.0, 200);
        case.numerics = numerics;
        case.t_end = 2.0;
        case.every = 0.5;
        let bed = |x: f64| 0.2 * (-x * x).exp() + 0.05 * (3.0 * x).cos();
        let mut sim = case.build(
            bed,
            |x, b| (0.5 + 0.3 * (-4.0 * x * x).exp() - b).max(0.0),
            |_| 0.0,
        );
        let (sink, _) = run(&mut sim);
        let (mut dh, mut du) = (0.0f64, 0.0f64);
        for snap in &sink.snapshots {
            let n = snap.h.len();
            for i in 0..n / 2 {
                dh = dh.max((snap.h[i] - snap.h[n - 1 - i]).abs());
                du = du.max((snap.u[i] + snap.u[n - 1 - i]).abs());
            }
        }
        eprintln!("{numerics:?}: asymmetry |Δh| {dh:e}, |Δu| {du:e}");
        let bound = if numerics.order == 1 { 1e-12 } else { 1e-9 };
        assert!(
            dh <= bound && du <= 10.0 * bound,
            "{numerics:?}: {dh:e}, {du:e}"
        );
    }
}

/// A Voellmy dam break on a 34° plane (1 m over 300 m, μ = 0.155, ξ = 4000 m/s², as the
/// AvaFrame scenarios; local frame, 30 s): order 2 (MC) on 20 m cells has the peak
/// speed of order 1 on 0.625 m cells within 0.5 %, where order 1 on 20 m cells is 9 %
/// slow (docs/validation.md, "AvaFrame's standard avalanches": the hockey stick's
/// faster stream at order 2 is the channel's resolution, not a bias of order 2).
#[test]
fn voellmy_dam_break_peak_speed_of_order_2_on_coarse_cells_is_order_1_on_fine_cells() {
    let peak = |numerics: Numerics, cells: usize| {
        let mut case = Case::new(0.0, 3000.0, cells);
        case.mesh.slope_deg = 34.0;
        case.mesh.right = BoundaryKind::Outflow;
        case.law = FrictionLaw::Voellmy {
            mu: 0.155,
            xi: 4000.0,
        };
        case.cfl = 0.45;
        case.t_end = 30.0;
        case.every = 30.0;
        case.numerics = numerics;
        let mut sim = case.build(|_| 0.0, |x, _| if x < 300.0 { 1.0 } else { 0.0 }, |_| 0.0);
        let (sink, _) = run(&mut sim);
        let u = &sink.snapshots.last().unwrap().u;
        u.iter().fold(0.0f64, |m, &v| m.max(v))
    };
    let fine = peak(ORDER_1, 4800);
    let coarse_2 = peak(order_2(Limiter::Mc), 150);
    let coarse_1 = peak(ORDER_1, 150);
    eprintln!("peak speed: order 1 on 4800 cells {fine:.3}, order 2 on 150 {coarse_2:.3}, order 1 on 150 {coarse_1:.3} m/s");
    assert!(
        (coarse_2 / fine - 1.0).abs() < 5e-3,
        "{coarse_2} against {fine}"
    );
    assert!(coarse_1 < 0.95 * fine, "order 1 on 150 cells: {coarse_1}");
}
