//! The multilayer model on a raster (`numerics/layers_2d.rs`,
//! `state/layered_raster.rs`): a raster run invariant in y is, row by row and step by
//! step, the line's multilayer run to the bit (N = 1, 4, 20; flow along x in the local
//! frame and along y in the Cartesian frame), on any number of threads; with the μ(I)
//! viscous columns (`numerics/viscous_2d.rs`; Coulomb and no-slip beds, both
//! regularisations) and over an erodible bed of grains at rest (Fernández-Nieto et
//! al. 2016, §4.2) too.

use super::terrain_2d::{material, raster, tan_deg};
use granflow::grid::{BoundaryKind, Coordinates, Line, LineSpec, Raster2d, Sides};
use granflow::model::granular::Granular;
use granflow::model::Model;
use granflow::numerics::hydrostatic::HydrostaticStep;
use granflow::numerics::layers_2d::LayersStep2d;
use granflow::numerics::viscous::{
    BasalCondition, MultilayerViscousStep, Regularization, ViscosityTime, ViscousOptions,
};
use granflow::numerics::viscous_2d::ViscousColumns2d;
use granflow::numerics::workers::Workers;
use granflow::numerics::Stage;
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
    for i in 0..case.nx {
        for a in 0..n {
            state.hu[(i + 1) * n + a] = h0[i] * layer_speed(h0[i], a, n);
        }
    }
    state.fill_ghosts(&line);
    let mut step_1d = HydrostaticStep::with_layers(mu_i(), case.nx, n);

    let bed = case.bed;
    let (sides, (nx, ny), xr, yr) = if transposed {
        let sides = Sides {
            west: WALL,
            east: WALL,
            south: WALL,
            north: OUTFLOW,
        };
        (sides, (case.ny, case.nx), (0.0, 0.3), (x_min, x_max))
    } else {
        let sides = Sides {
            west: WALL,
            east: OUTFLOW,
            south: WALL,
            north: WALL,
        };
        (sides, (case.nx, case.ny), (x_min, x_max), (0.0, 0.3))
    };
    let r: Raster2d = raster(
        nx,
        ny,
        xr,
        yr,
        sides,
        case.coordinates,
        case.slope_deg,
        move |x, y| bed(if transposed { y } else { x }),
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
    let mut moved = 0.0f64;
    for step in 0..case.steps {
        let speed = model.diagnose(&line, &state).signal_speed;
        assert!(speed > 0.0);
        let dt = 0.3 * line.dx / speed;
        if let (Some(v1), Some(v2)) = (&mut visc_1d, &mut visc_2d) {
            v1.prepare(&line, &state);
            v2.prepare(&r, &state_2d);
        }
        step_1d.apply(&line, dt, &mut state).unwrap();
        step_2d.apply(&r, dt, &mut state_2d).unwrap();
        if let (Some(v1), Some(v2)) = (&mut visc_1d, &mut visc_2d) {
            v1.apply(&line, dt, &mut state).unwrap();
            v2.apply(&r, dt, &mut state_2d).unwrap();
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
