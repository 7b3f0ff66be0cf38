//! Cost of a time step of the dilatant μ(I)–φ model (Bouchut et al. 2021) relative to a
//! step of the hydrostatic Savage–Hutter μ(I) monolayer on the same grid (not a test:
//! nothing is asserted; target ≤ 1.5×), for the default split scheme and the
//! Appendix B one (`dilatancy.scheme`).
//!
//!   cargo bench --bench dilatant
//!
//! Both models run the collapse of Bouchut et al. 2021, §4 (14 cm × 20 cm column, 22°, Δx = 5 mm on
//! [−0.2, 3] m, 640 cells; the dilatant one dense, φ0 = 0.62, Table 1) to t0 untimed,
//! then steps (CFL + all stages) are timed in bursts that alternate between the two;
//! the best burst of each is kept (the machine is shared). Second case: the same with
//! a 1 cm layer everywhere (every cell wet), 640 and 64 000 cells.
//!
//! For instruction counts under callgrind (docs/performance.md, "Dilatant model"), a
//! fixed number of steps of one stepper from t = 0, nothing timed:
//!
//!   BENCH_BINARY --profile {sh|split|stab} CELLS LAYER STEPS
//!
//! (`sh`: Savage–Hutter μ(I); `split`: the split scheme without viscosity; `stab`: with
//! ξ = (2, 2, 2)); BENCH_BINARY is the executable `cargo bench --bench dilatant
//! --no-run` prints.

use std::hint::black_box;
use std::time::Instant;

use granflow::grid::{Line, LineSpec};
use granflow::numerics::dilatant::split::SplitScheme;
use granflow::numerics::dilatant::step::{DilatantOptions, DilatantScheme};
use granflow::numerics::friction::CoulombFrictionStep;
use granflow::numerics::hydrostatic::HydrostaticStep;
use granflow::numerics::{Stage, StepClock};
use granflow::physics::dilatancy::DilatantLaw;
use granflow::physics::rheology::{MonolayerShear, MuI};
use granflow::physics::shallow::velocity;
use granflow::scenario::{BoundaryKind, Coordinates};
use granflow::state::dilatant::DilatantState;
use granflow::state::layered::LayeredState as State;

const MU_I: MuI = MuI {
    mu_s: 0.48,
    mu_2: 0.73,
    i0: 0.279,
    d_s: 7e-4,
    phi: 0.62,
    shear: MonolayerShear::Bagnold,
};

struct SavageHutter {
    state: State,
    /// Time of the state.
    t: f64,
    hyperbolic: HydrostaticStep<MuI>,
    friction: CoulombFrictionStep<MuI>,
}

impl SavageHutter {
    fn step(&mut self, mesh: &Line) {
        let s = &self.state;
        let speed = (1..=mesh.nx)
            .map(|j| s.mean_velocity(j).abs() + (mesh.g_n * s.h[j]).sqrt())
            .fold(0.0, f64::max);
        let clock = StepClock::at(self.t, 0.5 * mesh.dx / speed);
        self.t += clock.dt;
        self.hyperbolic.apply(mesh, clock, &mut self.state).unwrap();
        self.friction.apply(mesh, clock, &mut self.state).unwrap();
    }
}

struct Dilatant {
    state: DilatantState,
    scheme: DilatantScheme,
}

impl Dilatant {
    fn step(&mut self, mesh: &Line) {
        let dt = self.scheme.max_dt(mesh, &self.state);
        self.scheme.step(mesh, &mut self.state, 0.0, dt).unwrap();
    }
}

/// The default (split) dilatant scheme, with the Savage–Hutter CFL step.
struct Split {
    state: DilatantState,
    scheme: SplitScheme,
}

impl Split {
    fn step(&mut self, mesh: &Line) {
        let s = &self.state;
        let speed = (1..=mesh.nx)
            .map(|j| velocity(s.h[j], s.hu[j]).abs() + (mesh.g_n * s.h[j]).sqrt())
            .fold(0.0, f64::max);
        let dt = 0.5 * mesh.dx / speed;
        self.scheme.step(mesh, &mut self.state, dt).unwrap();
    }
}

/// The collapse of Bouchut et al. 2021, §4 on `cells` cells of 5 mm from x = −0.2 m (22°, wall on the
/// left, outflow on the right): the 14 cm column on x ≤ 0, `layer` m of grains beyond.
fn collapse(cells: usize, layer: f64) -> (Line, Vec<f64>) {
    let spec = LineSpec {
        x_min: -0.2,
        x_max: -0.2 + cells as f64 * 0.005,
        cells,
        slope_deg: 22.0,
        coordinates: Coordinates::Local,
        left: BoundaryKind::Wall,
        right: BoundaryKind::Outflow,
    };
    let mesh = Line::new(&spec, vec![0.0; cells]);
    let h = mesh
        .x
        .iter()
        .map(|&x| if x <= 0.0 { 0.14 } else { layer })
        .collect();
    (mesh, h)
}

impl SavageHutter {
    fn new(mesh: &Line, h: &[f64]) -> Self {
        SavageHutter {
            state: State::from_profiles(mesh, &[1.0], h, &vec![0.0; mesh.nx]),
            t: 0.0,
            hyperbolic: HydrostaticStep::new(MU_I, mesh.nx),
            friction: CoulombFrictionStep::new(MU_I),
        }
    }
}

impl Split {
    /// The dense column (φ0 = 0.62, Table 1) with the viscosity coefficients ξ.
    fn new(mesh: &Line, h: &[f64], xi: f64) -> Self {
        let nx = mesh.nx;
        let mut options = DilatantOptions::default();
        options.viscosity.xi = [xi; 3];
        Split {
            state: DilatantState::from_profiles(mesh, 2.0, h, &vec![0.0; nx], &vec![0.62; nx]),
            scheme: SplitScheme::new(DilatantLaw::table1(), options, nx, 0.62),
        }
    }
}

fn case(cells: usize, layer: f64, t0: f64) {
    let (mesh, h) = collapse(cells, layer);
    let zero = vec![0.0; cells];
    let mut sh = SavageHutter::new(&mesh, &h);
    let mut dil = Dilatant {
        state: DilatantState::from_profiles(&mesh, 2.0, &h, &zero, &vec![0.62; cells]),
        scheme: DilatantScheme::new(DilatantLaw::table1(), DilatantOptions::default(), cells),
    };
    // The split scheme with the scenarios' default: no stabilisation viscosity.
    let mut split = Split::new(&mesh, &h, 0.0);
    // Advance both to about t0 (their own Δt), untimed.
    let steps_to_t0 = (t0 / (0.5 * mesh.dx / (9.81f64 * 0.14).sqrt())) as usize;
    for _ in 0..steps_to_t0 {
        sh.step(&mesh);
        dil.step(&mesh);
        split.step(&mesh);
    }
    let burst = (200_000 / cells).clamp(5, 400);
    let (mut best_sh, mut best_dil, mut best_split) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..15 {
        let start = Instant::now();
        for _ in 0..burst {
            sh.step(&mesh);
        }
        best_sh = best_sh.min(start.elapsed().as_secs_f64() / burst as f64);
        let start = Instant::now();
        for _ in 0..burst {
            dil.step(&mesh);
        }
        best_dil = best_dil.min(start.elapsed().as_secs_f64() / burst as f64);
        let start = Instant::now();
        for _ in 0..burst {
            split.step(&mesh);
        }
        best_split = best_split.min(start.elapsed().as_secs_f64() / burst as f64);
    }
    black_box(&split.state.h);
    let wet_split = split.state.h[1..=cells]
        .iter()
        .filter(|&&h| h > 0.0)
        .count();
    black_box((&sh.state.h, &dil.state.m));
    let wet_sh = sh.state.h[1..=cells].iter().filter(|&&h| h > 0.0).count();
    let wet_dil = dil.state.m[1..=cells].iter().filter(|&&m| m > 0.0).count();
    let dt = dil.scheme.max_dt(&mesh, &dil.state);
    let substeps = dil
        .scheme
        .step(&mesh, &mut dil.state, 0.0, dt)
        .unwrap()
        .viscosity_substeps;
    println!(
        "collapse 22°, {cells} cells, layer {layer} m, from ≈ {t0} s: SH {:.2} µs/step ({wet_sh} wet cells); \
         split dilatant {:.2} µs/step ({wet_split} wet cells), ratio {:.2}×; \
         Appendix B dilatant {:.2} µs/step ({wet_dil} wet cells, {substeps} viscosity sub-steps), ratio {:.2}×",
        best_sh * 1e6,
        best_split * 1e6,
        best_split / best_sh,
        best_dil * 1e6,
        best_dil / best_sh,
    );
}

/// `--profile WHICH CELLS LAYER STEPS`: `STEPS` steps of one stepper, for callgrind.
fn profile(args: &[String]) {
    let usage = "usage: --profile {sh|split|stab} CELLS LAYER STEPS";
    let [which, cells, layer, steps] = args else {
        panic!("{usage}");
    };
    let cells: usize = cells.parse().expect(usage);
    let layer: f64 = layer.parse().expect(usage);
    let steps: usize = steps.parse().expect(usage);
    let (mesh, h) = collapse(cells, layer);
    let h_sum = match which.as_str() {
        "sh" => {
            let mut sh = SavageHutter::new(&mesh, &h);
            (0..steps).for_each(|_| sh.step(&mesh));
            sh.state.h.iter().sum::<f64>()
        }
        "split" | "stab" => {
            let mut split = Split::new(&mesh, &h, if which == "stab" { 2.0 } else { 0.0 });
            (0..steps).for_each(|_| split.step(&mesh));
            split.state.h.iter().sum::<f64>()
        }
        _ => panic!("{usage}"),
    };
    println!("{h_sum}");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(k) = args.iter().position(|a| a == "--profile") {
        return profile(&args[k + 1..]);
    }
    case(640, 0.0, 0.3);
    case(640, 0.01, 0.3);
    case(64_000, 0.01, 0.0);
}
