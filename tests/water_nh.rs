//! The submarine model's non-hydrostatic water (`submarine.water_pressure =
//! "nonhydrostatic"`, `numerics::water_nh`): linear dispersion against Airy theory
//! for M = 1, 2, 3 layers, a solitary wave, a lake at rest over a deposit, the wave of
//! a bottom that rises against linear potential theory (Hammack 1973), and the keys.

use granflow::grid::{BoundaryKind, CurvedLine, Line};
use granflow::numerics::two_layer::TwoLayerSolver;
use granflow::numerics::water_nh::WaterProjection;
use granflow::physics::two_layer::TwoLayerParams;
use granflow::physics::GRAVITY;
use granflow::state::TwoLayerState;

/// Water over a flat bed (no grains, or a grain layer `h2` at rest held by friction
/// δ₀ = 80°), with `layers` non-hydrostatic water layers (None: hydrostatic).
struct Tank {
    grid: CurvedLine,
    state: TwoLayerState,
    solver: TwoLayerSolver,
    projection: Option<WaterProjection>,
    t: f64,
}

impl Tank {
    fn new(
        x_min: f64,
        dx: f64,
        nx: usize,
        eta: impl Fn(f64) -> f64,
        h2: impl Fn(f64) -> f64,
        layers: Option<usize>,
        boundary: BoundaryKind,
    ) -> Tank {
        let line = Line::cartesian(x_min, dx, &vec![0.0; nx], boundary, boundary);
        let grid = CurvedLine::new(line);
        let mut state = TwoLayerState::zeros(nx);
        for i in 1..=nx {
            let x = grid.line.x[i - 1];
            state.h2[i] = h2(x);
            state.h1[i] = (eta(x) - state.h2[i]).max(0.0);
        }
        state.fill_ghosts(&grid);
        let params = TwoLayerParams::new(0.5, 1.0, 0.0, 0.0, 80.0);
        let projection = layers.map(|m| WaterProjection::new(&grid, m));
        if let Some(p) = &projection {
            state.water = Some(p.water_at_rest(nx));
        }
        Tank {
            solver: TwoLayerSolver::new(params, 0.8, nx),
            grid,
            state,
            projection,
            t: 0.0,
        }
    }

    /// One step of at most `dt_max` (CFL 0.8 on the two-layer bounds).
    fn step(&mut self, dt_max: f64) -> f64 {
        let s = self.solver.max_speed(&self.grid, &self.state);
        let dt = (self.solver.cfl * self.grid.line.dx / s).min(dt_max);
        if let Some(p) = &mut self.projection {
            p.record_bottom(&self.grid, &self.state);
        }
        self.solver.step_with(&self.grid, &mut self.state, dt);
        if let Some(p) = &mut self.projection {
            p.project(&self.grid, &mut self.state, dt);
        }
        self.t += dt;
        dt
    }

    fn eta(&self, i: usize) -> f64 {
        self.state.eta(&self.grid, i + 1)
    }
}

/// ω of Airy theory, ω² = g k tanh(kh).
fn airy(k: f64, h: f64) -> f64 {
    (GRAVITY * k * (k * h).tanh()).sqrt()
}

/// Period of the standing wave η = h + a cos(kx) in a basin of one wavelength
/// (walls), from the zero crossings of η − h at the wall cell over two periods, with
/// `per_wave` cells per wavelength.
fn standing_period(kh: f64, layers: Option<usize>, per_wave: usize) -> f64 {
    let h = 1.0;
    let k = kh / h;
    let l = 2.0 * std::f64::consts::PI / k;
    let dx = l / per_wave as f64;
    let a = 1e-3 * h;
    let mut tank = Tank::new(
        0.0,
        dx,
        per_wave,
        |x| h + a * (k * x).cos(),
        |_| 0.0,
        layers,
        BoundaryKind::Wall,
    );
    let mut crossings = Vec::new();
    let mut prev = (0.0, tank.eta(0) - h);
    while crossings.len() < 5 {
        tank.step(f64::INFINITY);
        let now = (tank.t, tank.eta(0) - h);
        if prev.1 * now.1 < 0.0 || now.1 == 0.0 {
            crossings.push(prev.0 + (now.0 - prev.0) * prev.1 / (prev.1 - now.1));
        }
        prev = now;
        assert!(tank.t < 1e4, "no oscillation");
    }
    (crossings[4] - crossings[0]) / 2.0
}

/// ω_model/ω_Airy − 1 of the standing wave.
fn dispersion_error(kh: f64, layers: Option<usize>, per_wave: usize) -> f64 {
    let exact = 2.0 * std::f64::consts::PI / airy(kh, 1.0);
    exact / standing_period(kh, layers, per_wave) - 1.0
}

/// The phase speed of standing waves against Airy theory, ω² = g k tanh(kh), for kh
/// from 0.1 to 3 (converged in Δx: 128 and 256 cells per wavelength agree to 3·10⁻⁴): the error
/// falls with the number of water layers M at every kh ≥ 0.5, and the weakly
/// non-hydrostatic monolayer (M = 1) is within 4 % up to kh = 3 where the hydrostatic
/// water is 74 % too fast.
#[test]
fn standing_waves_disperse_as_airy_waves_better_with_more_layers() {
    for kh in [0.1, 0.5, 1.0, 2.0, 3.0] {
        let mut errors = Vec::new();
        for layers in [None, Some(1), Some(2), Some(3)] {
            let (coarse, medium, fine) = (
                dispersion_error(kh, layers, 64),
                dispersion_error(kh, layers, 128),
                dispersion_error(kh, layers, 256),
            );
            println!("kh = {kh}, layers {layers:?}: ω/ω_Airy − 1 = {coarse:+.2e} (64 cells/λ), {medium:+.2e} (128), {fine:+.2e} (256)");
            // Converged: the mesh changes the error by far less than the model does.
            assert!(
                (medium - fine).abs() < 3e-4,
                "{kh} {layers:?}: {medium} {fine}"
            );
            errors.push(fine.abs());
        }
        let (hydrostatic, m1, m2, m3) = (errors[0], errors[1], errors[2], errors[3]);
        assert!(
            m1 < 0.04 && m2 < 0.007 && m3 < 0.003,
            "kh = {kh}: {errors:?}"
        );
        if kh >= 0.5 {
            assert!(hydrostatic > 0.03, "kh = {kh}: {errors:?}");
            assert!(
                m3 < m2 && m2 < m1 && m1 < hydrostatic,
                "kh = {kh}: {errors:?}"
            );
        }
    }
}

/// The solitary wave of the Serre equations (Rayleigh's sech² profile), η − h =
/// a sech²(κ(x − x₀)), κ = √(3a/(4h²(h + a))), u = c(η − h)/η, c = √(g(h + a)), with
/// the vertical velocity of each layer w = −(z − z_b) ∂_x u at its middle.
fn solitary(a: f64, dx: f64, layers: Option<usize>) -> Tank {
    let (h, x0) = (1.0, 0.0);
    let kappa = (3.0 * a / (4.0 * h * h * (h + a))).sqrt();
    let c = (GRAVITY * (h + a)).sqrt();
    let eta = move |x: f64| h + a / (kappa * (x - x0)).cosh().powi(2);
    let u = move |x: f64| c * (eta(x) - h) / eta(x);
    let (x_min, x_max) = (-15.0, 65.0);
    let nx = ((x_max - x_min) / dx).round() as usize;
    let mut tank = Tank::new(x_min, dx, nx, eta, |_| 0.0, layers, BoundaryKind::Outflow);
    for i in 1..=nx {
        let x = tank.grid.line.x[i - 1];
        tank.state.q1[i] = tank.state.h1[i] * u(x);
        if let Some(w) = &mut tank.state.water {
            let m = w.layers;
            let du = (u(x + 0.5 * dx) - u(x - 0.5 * dx)) / dx;
            for a in 0..m {
                let mid = (a as f64 + 0.5) / m as f64;
                w.w[i * m + a] = -mid * eta(x) * du;
            }
        }
    }
    tank.state.fill_ghosts(&tank.grid);
    tank
}

/// (amplitude, steepest slope of η) of a tank's wave.
fn wave_shape(tank: &Tank) -> (f64, f64) {
    let nx = tank.grid.line.nx;
    let dx = tank.grid.line.dx;
    let amp = (0..nx).map(|i| tank.eta(i) - 1.0).fold(0.0, f64::max);
    let slope = (0..nx - 1)
        .map(|i| ((tank.eta(i + 1) - tank.eta(i)) / dx).abs())
        .fold(0.0, f64::max);
    (amp, slope)
}

/// A solitary wave (a/h = 0.1 and 0.2) travels 50 depths. With non-hydrostatic water
/// (M = 1, 2) it keeps its front as steep as at the start (within 25 %), at Δx = h/10
/// and h/20, and loses less than 4 % of its amplitude at Δx = h/20, a loss that falls
/// with Δx (the diffusion of the first-order scheme); the hydrostatic water steepens
/// it into a bore (the slope grows by more than 2×, more on the finer mesh).
#[test]
fn a_solitary_wave_keeps_its_shape_over_fifty_depths() {
    for a in [0.1, 0.2] {
        let t_end = 50.0 / (GRAVITY * (1.0 + a)).sqrt();
        for layers in [None, Some(1), Some(2)] {
            let mut shapes = Vec::new();
            for dx in [0.1, 0.05] {
                let mut tank = solitary(a, dx, layers);
                let start = wave_shape(&tank);
                while tank.t < t_end - 1e-12 {
                    tank.step(t_end - tank.t);
                }
                let end = wave_shape(&tank);
                let (loss, steepening) = (1.0 - end.0 / start.0, end.1 / start.1);
                println!(
                    "a/h = {a}, layers {layers:?}, dx = {dx}: amplitude {:.4} -> {:.4} (loss {:+.2} %), max slope x{steepening:.2}",
                    start.0, end.0, 100.0 * loss
                );
                shapes.push((loss, steepening));
            }
            let ((coarse, s_coarse), (fine, s_fine)) = (shapes[0], shapes[1]);
            if layers.is_some() {
                // The loss is the first-order scheme's diffusion: it falls with Δx.
                assert!(fine.abs() < 0.04, "a = {a} {layers:?}: {shapes:?}");
                assert!(
                    fine.abs() < 0.6 * coarse.abs(),
                    "a = {a} {layers:?}: {shapes:?}"
                );
                for s in [s_coarse, s_fine] {
                    assert!((s - 1.0).abs() < 0.25, "a = {a} {layers:?}: {shapes:?}");
                }
            } else {
                assert!(s_coarse > 2.0 && s_fine > s_coarse, "a = {a}: {shapes:?}");
            }
        }
    }
}
