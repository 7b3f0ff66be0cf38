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

#[test]
fn standing_wave_periods_against_airy() {
    for kh in [0.1, 0.5, 1.0, 2.0, 3.0] {
        let exact = 2.0 * std::f64::consts::PI / airy(kh, 1.0);
        let mut line = format!("kh = {kh}:");
        for layers in [None, Some(1), Some(2), Some(3)] {
            for n in [64, 128] {
                let t = standing_period(kh, layers, n);
                line += &format!(" {layers:?}/{n}: {:+.2e}", exact / t - 1.0);
            }
        }
        println!("{line}");
    }
}
