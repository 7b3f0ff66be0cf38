//! The multilayer model on a raster (`numerics/layers_2d.rs`,
//! `state/layered_raster.rs`): a raster run invariant in y is, row by row and step by
//! step, the line's multilayer run to the bit (N = 1, 4, 20; flow along x in the local
//! frame and along y in the Cartesian frame), on any number of threads; with the μ(I)
//! viscous columns (`numerics/viscous_2d.rs`; Coulomb and no-slip beds, both
//! regularisations) and over an erodible bed of grains at rest (Fernández-Nieto et
//! al. 2016, §4.2) too.

use super::terrain_2d::{invariant_raster, material, raster, tan_deg};
use granflow::grid::{BoundaryKind, Coordinates, Line, LineSpec, Raster2d, Sides};
use granflow::model::granular::Granular;
use granflow::model::Model;
use granflow::numerics::hydrostatic::HydrostaticStep;
use granflow::numerics::layers_2d::{self, LayersStep2d};
use granflow::numerics::viscous::{
    BasalCondition, MultilayerViscousStep, Regularization, ViscosityTime, ViscousOptions,
};
use granflow::numerics::viscous_2d::ViscousColumns2d;
use granflow::numerics::workers::Workers;
use granflow::numerics::{Stage, StepClock};
use granflow::physics::rheology::{MonolayerShear, MuI};
use granflow::state::layered_raster::LayeredRaster;
use granflow::state::LayeredState;

const WALL: BoundaryKind = BoundaryKind::Wall;
const OUTFLOW: BoundaryKind = BoundaryKind::Outflow;

pub(crate) fn mu_i() -> MuI {
    let m = material();
    MuI {
        mu_s: tan_deg(20.9),
        mu_2: tan_deg(32.76),
        i0: 0.279,
        d_s: m.d_s,
        phi: m.phi,
        shear: MonolayerShear::Bagnold,
    }
}

/// Equal layer fractions.
pub(crate) fn fractions(n: usize) -> Vec<f64> {
    vec![1.0 / n as f64; n]
}

/// A y-invariant case: the line and its extrusion over `ny` rows.
struct Case {
    coordinates: Coordinates,
    slope_deg: f64,
    bed: fn(f64) -> f64,
    h0: fn(f64) -> f64,
    nx: usize,
    ny: usize,
    steps: usize,
}

/// The viscous options of the tests: `basal` with the bound regularisation (Coulomb)
/// or δ = 1e-4 1/s (no slip).
pub(crate) fn viscous(basal: BasalCondition) -> ViscousOptions {
    ViscousOptions {
        basal,
        regularization: match basal {
            BasalCondition::Coulomb => Regularization::Bound,
            BasalCondition::NoSlip => Regularization::Delta { delta: 1e-4 },
        },
        sidewall: None,
        c_msm: false,
        viscosity: ViscosityTime::Frozen,
    }
}

/// A sheared profile: layer α of N moves at (0.2 + 0.8 α/N) m/s down the slope where
/// the layer is thicker than 5 cm (a thinner erodible bed starts at rest).
fn layer_speed(h: f64, a: usize, n: usize) -> f64 {
    if h > 0.05 {
        0.2 + 0.8 * a as f64 / n as f64
    } else {
        0.0
    }
}

/// Runs the hyperbolic step on the line and on the raster (flow along x, or along y
/// when `transposed`) with the line's time steps and checks every row, layer and
/// step to the bit.
fn check(case: &Case, n: usize, transposed: bool, threads: usize, opts: Option<ViscousOptions>) {
    let (x_min, x_max) = (-1.0, 1.0);
    let spec = LineSpec {
        x_min,
        x_max,
        cells: case.nx,
        slope_deg: case.slope_deg,
        coordinates: case.coordinates,
        left: WALL,
        right: OUTFLOW,
    };
    let line = Line::new(
        &spec,
        spec.centres().iter().map(|&x| (case.bed)(x)).collect(),
    );
    let l = fractions(n);
    let h0: Vec<f64> = line.x.iter().map(|&x| (case.h0)(x)).collect();
    let mut state = LayeredState::from_profiles(&line, &l, &h0, &vec![0.0; case.nx]);
    for (i, &h) in h0.iter().enumerate() {
        for a in 0..n {
            state.hu[(i + 1) * n + a] = h * layer_speed(h, a, n);
        }
    }
    state.fill_ghosts(&line);
    let mut step_1d = HydrostaticStep::with_layers(mu_i(), case.nx, n);

    let (r, nx, ny) = invariant_raster(
        (case.nx, case.ny),
        (x_min, x_max),
        transposed,
        case.coordinates,
        case.slope_deg,
        case.bed,
    );
    let along = |k: usize| if transposed { k / nx } else { k % nx };
    let h: Vec<f64> = (0..nx * ny).map(|k| h0[along(k)]).collect();
    let zeros = vec![0.0; nx * ny];
    let mut state_2d = LayeredRaster::from_velocities((nx, ny), &l, h, &zeros, &zeros);
    for k in 0..nx * ny {
        let a_cell = along(k);
        for a in 0..n {
            let q = state.hu[(a_cell + 1) * n + a];
            if transposed {
                state_2d.hv[k * n + a] = q;
            } else {
                state_2d.hu[k * n + a] = q;
            }
        }
    }
    let workers = Workers::new(threads).unwrap();
    let mut step_2d = LayersStep2d::new(mu_i(), &r, &l, workers.clone());
    let mut visc_1d = opts.map(|o| MultilayerViscousStep::new(mu_i(), case.nx, &l, o));
    let mut visc_2d = opts.map(|o| ViscousColumns2d::new(mu_i(), &r, &l, o, workers));

    let model = Granular {
        h_bed: vec![0.0; case.nx],
        front_threshold: 1e-3,
        static_threshold: 1e-3,
        rest_speed: 0.0,
    };
    let (mut moved, mut t) = (0.0f64, 0.0);
    for step in 0..case.steps {
        let speed = model.diagnose(&line, &state).signal_speed;
        assert!(speed > 0.0);
        let clock = StepClock::at(t, 0.3 * line.dx / speed);
        t += clock.dt;
        if let (Some(v1), Some(v2)) = (&mut visc_1d, &mut visc_2d) {
            v1.prepare(&line, clock, &state);
            v2.prepare(&r, clock, &state_2d);
        }
        step_1d.apply(&line, clock, &mut state).unwrap();
        step_2d.apply(&r, clock, &mut state_2d).unwrap();
        if let (Some(v1), Some(v2)) = (&mut visc_1d, &mut visc_2d) {
            v1.apply(&line, clock, &mut state).unwrap();
            v2.apply(&r, clock, &mut state_2d).unwrap();
        }
        for k in 0..nx * ny {
            let c = along(k) + 1;
            assert_eq!(
                state_2d.h[k], state.h[c],
                "h, N = {n}, step {step}, cell {k}"
            );
            for a in 0..n {
                let (q_along, q_across) = if transposed {
                    (state_2d.hv[k * n + a], state_2d.hu[k * n + a])
                } else {
                    (state_2d.hu[k * n + a], state_2d.hv[k * n + a])
                };
                let q = state.hu[c * n + a];
                assert_eq!(q_along, q, "hu, N = {n}, layer {a}, step {step}, cell {k}");
                assert_eq!(
                    q_across, 0.0,
                    "cross discharge, N = {n}, step {step}, cell {k}"
                );
            }
        }
        moved = moved.max(state.hu.iter().fold(0.0f64, |m, q| m.max(q.abs())));
    }
    assert!(moved > 1e-3, "the case must flow (max |hu| = {moved})");
}

fn cases() -> Vec<Case> {
    vec![
        // A sheared dam break on a 25° plane over a bumpy bed, local frame.
        Case {
            coordinates: Coordinates::Local,
            slope_deg: 25.0,
            bed: |x| 0.02 * (6.0 * x).sin(),
            h0: |x| if x < -0.5 { 0.1 } else { 0.0 },
            nx: 60,
            ny: 3,
            steps: 120,
        },
        // A collapse over a bed step, Cartesian frame.
        Case {
            coordinates: Coordinates::Cartesian,
            slope_deg: 0.0,
            bed: |x| if x > 0.3 { 0.01 } else { 0.0 },
            h0: |x| if x < -0.6 { 0.2 } else { 0.0 },
            nx: 60,
            ny: 3,
            steps: 120,
        },
    ]
}

#[test]
fn hyperbolic_runs_invariant_in_y_reproduce_the_line_bit_for_bit() {
    for n in [1, 4, 20] {
        for case in cases() {
            check(&case, n, false, 1, None);
        }
    }
}

#[test]
fn hyperbolic_runs_invariant_in_x_reproduce_the_line_along_y() {
    for n in [1, 4] {
        check(&cases()[1], n, true, 1, None);
    }
}

#[test]
fn hyperbolic_bits_do_not_depend_on_the_threads() {
    let mut case = cases().remove(0);
    case.ny = 40;
    case.steps = 40;
    for threads in [2, 4] {
        check(&case, 4, false, threads, None);
        check(
            &case,
            4,
            false,
            threads,
            Some(viscous(BasalCondition::Coulomb)),
        );
    }
}

#[test]
fn viscous_runs_invariant_in_y_reproduce_the_line_bit_for_bit() {
    for n in [4, 20] {
        for basal in [BasalCondition::Coulomb, BasalCondition::NoSlip] {
            for case in cases() {
                check(&case, n, false, 1, Some(viscous(basal)));
            }
        }
    }
    // Flow along y: the v components take the line's operations.
    check(
        &cases()[1],
        4,
        true,
        1,
        Some(viscous(BasalCondition::Coulomb)),
    );
}

/// A release over an erodible bed: 2 cm of grains at rest on the whole slope
/// (Fernández-Nieto et al. 2016, §4.2), which the flow sets moving.
#[test]
fn viscous_runs_over_an_erodible_bed_reproduce_the_line_bit_for_bit() {
    let case = Case {
        coordinates: Coordinates::Local,
        slope_deg: 22.0,
        bed: |_| 0.0,
        h0: |x| if x < -0.5 { 0.12 } else { 0.02 },
        nx: 60,
        ny: 3,
        steps: 150,
    };
    for n in [4, 20] {
        check(&case, n, false, 1, Some(viscous(BasalCondition::Coulomb)));
    }
}

/// Hyperbolic and viscous stages of a layered raster, one step of Δt.
fn step_2d(
    r: &Raster2d,
    (hyp, visc): (&mut LayersStep2d<MuI>, &mut ViscousColumns2d<MuI>),
    clock: StepClock,
    state: &mut LayeredRaster,
) {
    visc.prepare(r, clock, state);
    hyp.apply(r, clock, state).unwrap();
    visc.apply(r, clock, state).unwrap();
}

/// Relative L1 error of `u` against `exact`.
fn relative_l1(u: &[f64], exact: &[f64]) -> f64 {
    let d: f64 = u.iter().zip(exact).map(|(u, e)| (u - e).abs()).sum();
    d / exact.iter().map(|e| e.abs()).sum::<f64>()
}

/// Midpoints of the layers of a column of thickness `h`.
fn midpoints(l: &[f64], h: f64) -> Vec<f64> {
    let mut below = 0.0;
    l.iter()
        .map(|&l| {
            let z = (below + 0.5 * l) * h;
            below += l;
            z
        })
        .collect()
}

/// The μ(I) law of the Bagnold tests (bagnold.toml's material).
fn bagnold_law() -> MuI {
    MuI {
        mu_s: 0.38,
        mu_2: 0.62,
        i0: 0.279,
        d_s: 0.04,
        phi: 0.62,
        shear: MonolayerShear::Bagnold,
    }
}

/// (2/3) I_G √(φ g_n)/d_s of the Bagnold profile on slope tan θ = `slope`, where
/// μ(I_G) = `slope`.
fn bagnold_scale(law: &MuI, slope: f64, g_n: f64) -> f64 {
    let i_g = law.i0 * (slope - law.mu_s) / (law.mu_2 - slope);
    2.0 / 3.0 * i_g * (law.phi * g_n).sqrt() / law.d_s
}

/// The Bagnold flow of Fernández-Nieto et al. 2016, §4.1.1 (eq. 29; scenarios/bagnold.toml:
/// μ_s = 0.38, μ_2 = 0.62, I_0 = 0.279, d_s = 4 cm, φ = 0.62, no slip, δ = 1e-5 1/s,
/// h = 1 m on a slope of tan 0.43) on the line and on a raster whose steepest descent
/// makes the angle `angle_deg` with the x axis: the local frame's plane along x
/// carries tan θ_x = G cos φ and the bed the slope G sin φ along y (G = tan 0.43), the
/// ghosts continue both. Starting at rest, after `t_end` the layer speeds |(u, v)_α| of
/// every cell are compared with the exact profile
/// |u|(z) = (2/3) I_G √(φ g_n)/d_s (h^{3/2} − (h − z)^{3/2}), μ(I_G) = G, and the
/// direction with the slope's. Returns (relative L1 error, largest |h − 1|, largest
/// angle error in radians).
fn bagnold_2d(n: usize, angle_deg: f64, t_end: f64) -> (f64, f64, f64) {
    let law = bagnold_law();
    let slope = 0.43f64.tan();
    let angle = angle_deg.to_radians();
    let (tan_x, tan_y) = (slope * angle.cos(), slope * angle.sin());
    let (nx, ny, dx) = (3, 3, 1.0 / 30.0);
    let sides = Sides::all(OUTFLOW);
    let slope_deg = tan_x.atan().to_degrees();
    let mut r: Raster2d = raster(
        nx,
        ny,
        (0.0, nx as f64 * dx),
        (0.0, ny as f64 * dx),
        sides,
        Coordinates::Local,
        slope_deg,
        |_, y| -y * tan_y,
    );
    // The south and north ghosts continue the bed's slope along y (the raster's
    // outflow copies the edge row's bed; the line's Bagnold column continues the plane).
    let tan_theta = slope_deg.to_radians().tan();
    for c in 0..nx + 2 {
        let x = (c as f64 - 0.5) * dx;
        for (row, y) in [(0, -0.5 * dx), (ny + 1, (ny as f64 + 0.5) * dx)] {
            let g = row * (nx + 2) + c;
            r.b_ghost[g] = -y * tan_y;
            r.z[g] = r.b_ghost[g] - x * tan_theta;
        }
    }
    let l = fractions(n);
    let cells = nx * ny;
    let zeros = vec![0.0; cells];
    let mut state = LayeredRaster::from_velocities((nx, ny), &l, vec![1.0; cells], &zeros, &zeros);
    let opts = ViscousOptions {
        basal: BasalCondition::NoSlip,
        regularization: Regularization::Delta { delta: 1e-5 },
        sidewall: None,
        c_msm: false,
        viscosity: ViscosityTime::Frozen,
    };
    let mut hyp = LayersStep2d::new(law, &r, &l, Workers::serial());
    let mut visc = ViscousColumns2d::new(law, &r, &l, opts, Workers::serial());
    let mut t = 0.0;
    while t < t_end {
        let speed = layers_2d::signal_speed(&r, &state);
        let dt = (0.5 * dx / speed).min(t_end - t);
        step_2d(&r, (&mut hyp, &mut visc), StepClock::at(t, dt), &mut state);
        t += dt;
    }
    let g_n = r.g_n;
    let scale = bagnold_scale(&law, slope, g_n);
    let (mut speeds, mut exact) = (Vec::new(), Vec::new());
    let (mut dh, mut d_angle) = (0.0f64, 0.0f64);
    for cell in 0..cells {
        let h = state.h[cell];
        dh = dh.max((h - 1.0).abs());
        for (a, z) in midpoints(&l, h).into_iter().enumerate() {
            let (u, v) = state.layer_velocity(cell, a);
            speeds.push(u.hypot(v));
            exact.push(scale * (h.powf(1.5) - (h - z).powf(1.5)));
            d_angle = d_angle.max((v.atan2(u) - angle).abs());
        }
    }
    (relative_l1(&speeds, &exact), dh, d_angle)
}

/// The line's Bagnold column (one cell between outflows, as the line's test runs it)
/// after `t_end`: the relative L1 error of its layer velocities.
fn bagnold_line(n: usize, t_end: f64) -> f64 {
    let law = bagnold_law();
    let spec = LineSpec {
        x_min: 0.0,
        x_max: 1.0 / 30.0,
        cells: 1,
        slope_deg: 0.43f64.to_degrees(),
        coordinates: Coordinates::Local,
        left: OUTFLOW,
        right: OUTFLOW,
    };
    let line = Line::new(&spec, vec![0.0]);
    let l = fractions(n);
    let mut state = LayeredState::from_profiles(&line, &l, &[1.0], &[0.0]);
    let opts = ViscousOptions {
        basal: BasalCondition::NoSlip,
        regularization: Regularization::Delta { delta: 1e-5 },
        sidewall: None,
        c_msm: false,
        viscosity: ViscosityTime::Frozen,
    };
    let mut hyp = HydrostaticStep::with_layers(law, 1, n);
    let mut visc = MultilayerViscousStep::new(law, 1, &l, opts);
    let model = Granular {
        h_bed: vec![0.0],
        front_threshold: 1e-3,
        static_threshold: 1e-3,
        rest_speed: 0.0,
    };
    let mut t = 0.0;
    while t < t_end {
        let speed = model.diagnose(&line, &state).signal_speed;
        let dt = (0.5 * line.dx / speed).min(t_end - t);
        let clock = StepClock::at(t, dt);
        visc.prepare(&line, clock, &state);
        hyp.apply(&line, clock, &mut state).unwrap();
        visc.apply(&line, clock, &mut state).unwrap();
        t += dt;
    }
    let h = state.h[1];
    let slope = 0.43f64.tan();
    let scale = bagnold_scale(&law, slope, line.g_n);
    let exact: Vec<f64> = midpoints(&l, h)
        .iter()
        .map(|z| scale * (h.powf(1.5) - (h - z).powf(1.5)))
        .collect();
    let u: Vec<f64> = (0..n).map(|a| state.hu[n + a] / h).collect();
    relative_l1(&u, &exact)
}

/// Uniform steady flow of N layers on a raster plane whose slope makes 0°, 30° and 45°
/// with the x axis reproduces the line's Bagnold profile (Fernández-Nieto et al. 2016,
/// §4.1.1) to the line's error: the column problem is the line's with g_n G for the
/// drive, and the relative error of its steady solution does not depend on g_n.
#[test]
fn bagnold_profile_on_an_inclined_raster_plane_in_any_direction() {
    let t_end = 200.0;
    for n in [4, 8] {
        let line = bagnold_line(n, t_end);
        for angle in [0.0, 30.0, 45.0] {
            let (error, dh, d_angle) = bagnold_2d(n, angle, t_end);
            println!(
                "Bagnold on a raster, N = {n}, {angle}° to x: L1 error {error:.4e} (line {line:.4e}), max |h − 1| {dh:.1e}, direction error {d_angle:.1e} rad"
            );
            assert!(dh < 1e-9, "N = {n}, {angle}°: max |h − 1| = {dh:e}");
            assert!(
                d_angle < 1e-9,
                "N = {n}, {angle}°: direction error {d_angle:e}"
            );
            assert!(
                (error - line).abs() <= 1e-3 * line,
                "N = {n}, {angle}°: L1 error {error:e}, line {line:e}"
            );
        }
    }
}

/// Deterministic pseudo-random numbers in [0, 1).
fn rand01(k: u64) -> f64 {
    let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// A granular layer below its repose on a random 2-D bed (the set-up of the
/// monolayer's test in `terrain_2d.rs`: 0.1 m thick, the discrete surface slope inside
/// the disk |∇η| ≤ 0.6 μ_s, μ_s = tan 25°; Cartesian, and local on a 10° plane) stays
/// at rest with N layers and the viscous columns, up to the creep that the δ
/// regularisation allows, as on the line (Escalante et al. 2023, Table 6;
/// `multilayer::multilayer_mass_at_repose_stays_at_rest_to_order_delta`): after 200
/// steps (0.92 s) the largest |h − h⁰| and |(u, v)_α| are within 100 δ (plus
/// round-off) for δ = 1e-10 and 1e-15 1/s.
#[test]
fn mass_below_repose_on_a_random_bed_stays_at_rest_with_layers() {
    let (nx, ny) = (30, 24);
    let dx = 1.0 / nx as f64;
    let mu_s = tan_deg(25.0);
    let amp = 0.3 * mu_s * dx;
    let law = MuI { mu_s, ..mu_i() };
    for (coordinates, slope) in [(Coordinates::Cartesian, 0.0), (Coordinates::Local, 10.0)] {
        let r: Raster2d = raster(
            nx,
            ny,
            (0.0, 1.0),
            (0.0, 0.8),
            Sides::all(WALL),
            coordinates,
            slope,
            |x, y| amp * rand01(((x * 1e4) as u64) << 20 ^ (y * 1e4) as u64),
        );
        let h0 = vec![0.1; nx * ny];
        let dt = 0.4 * dx / (9.81f64 * 0.1).sqrt();
        for (n, delta) in [(4, 1e-10), (4, 1e-15), (20, 1e-15)] {
            let l = fractions(n);
            let zeros = vec![0.0; nx * ny];
            let mut state =
                LayeredRaster::from_velocities((nx, ny), &l, h0.clone(), &zeros, &zeros);
            let mut hyp = LayersStep2d::new(law, &r, &l, Workers::serial());
            let opts = ViscousOptions {
                regularization: Regularization::Delta { delta },
                ..viscous(BasalCondition::Coulomb)
            };
            let mut visc = ViscousColumns2d::new(law, &r, &l, opts, Workers::serial());
            for k in 0..200 {
                let clock = StepClock::at(k as f64 * dt, dt);
                step_2d(&r, (&mut hyp, &mut visc), clock, &mut state);
            }
            let dh = state
                .h
                .iter()
                .zip(&h0)
                .fold(0.0f64, |m, (h, h0)| m.max((h - h0).abs()));
            let speed = (0..nx * ny * n)
                .map(|k| state.hu[k].hypot(state.hv[k]) / state.h[k / n])
                .fold(0.0f64, f64::max);
            println!(
                "at rest, {coordinates:?}, N = {n}, δ = {delta:e}: max |h − h0| {dh:.2e}, max |(u, v)_α| {speed:.2e}"
            );
            let what = format!("{coordinates:?}, N = {n}, δ = {delta:e}");
            assert!(dh <= 100.0 * delta + 1e-14, "{what}: max |h − h0| = {dh:e}");
            assert!(
                speed <= 100.0 * delta + 1e-14,
                "{what}: max speed {speed:e}"
            );
        }
    }
}
