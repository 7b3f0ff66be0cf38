//! Builds runs from plain closures, without scenario files.
#![allow(dead_code)]

use granflow::mesh::{Mesh, MeshSpec};
use granflow::output::memory::MemorySink;
use granflow::output::{RunInfo, RunSummary};
use granflow::pipeline::hydrostatic_monolayer;
use granflow::scenario::{BoundaryKind, Coordinates, FrictionLaw, Material};
use granflow::simulation::{RunConfig, Simulation};
use granflow::state::State;

pub struct Case {
    pub x_min: f64,
    pub x_max: f64,
    pub cells: usize,
    pub slope_deg: f64,
    pub coordinates: Coordinates,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
    pub law: FrictionLaw,
    pub cfl: f64,
    pub t_end: f64,
    pub every: f64,
    pub stop_at_rest: bool,
}

impl Case {
    pub fn new(x_min: f64, x_max: f64, cells: usize) -> Case {
        Case {
            x_min,
            x_max,
            cells,
            slope_deg: 0.0,
            coordinates: Coordinates::Local,
            left: BoundaryKind::Wall,
            right: BoundaryKind::Wall,
            law: FrictionLaw::Coulomb { mu: 0.0 },
            cfl: 0.5,
            t_end: 1.0,
            every: 0.1,
            stop_at_rest: false,
        }
    }

    pub fn beads_material() -> Material {
        Material {
            rho_s: 2500.0,
            phi: 0.62,
            d_s: 0.7e-3,
        }
    }

    /// Builds the run with bed `b(x)`, thickness `h(x, b)` and velocity `u(x)`.
    pub fn build(
        &self,
        b: impl Fn(f64) -> f64,
        h: impl Fn(f64, f64) -> f64,
        u: impl Fn(f64) -> f64,
    ) -> Simulation {
        let spec = MeshSpec {
            x_min: self.x_min,
            x_max: self.x_max,
            cells: self.cells,
            slope_deg: self.slope_deg,
            coordinates: self.coordinates,
            left: self.left,
            right: self.right,
        };
        let x = spec.centres();
        let bed: Vec<f64> = x.iter().map(|&x| b(x)).collect();
        let h0: Vec<f64> = x.iter().zip(&bed).map(|(&x, &b)| h(x, b)).collect();
        let u0: Vec<f64> = x.iter().map(|&x| u(x)).collect();
        let mesh = Mesh::new(&spec, bed);
        let state = State::from_profiles(&mesh, &[1.0], &h0, &u0);
        let pipeline = hydrostatic_monolayer(&self.law, &Self::beads_material(), self.cells);
        let config = RunConfig {
            t_end: self.t_end,
            cfl: self.cfl,
            stop_at_rest: self.stop_at_rest,
            output_every: self.every,
            front_threshold: 1e-3,
        };
        let info = RunInfo {
            granflow_version: "test".into(),
            model: "granular".into(),
            pressure: "hydrostatic".into(),
            layers: 1,
            coordinates: "local".into(),
            slope_deg: self.slope_deg,
            scenario_toml: String::new(),
            front_threshold: 1e-3,
        };
        Simulation::new(mesh, state, vec![0.0; self.cells], pipeline, config, info)
    }
}

/// Runs to the end, keeping everything in memory.
pub fn run(sim: &mut Simulation) -> (MemorySink, RunSummary) {
    let mut sink = MemorySink::default();
    let summary = sim.run(&mut sink, &mut |_| {}).expect("run succeeds");
    (sink, summary)
}

pub fn tan_deg(deg: f64) -> f64 {
    deg.to_radians().tan()
}

/// L1 norm of a − b times dx.
pub fn l1(a: &[f64], b: &[f64], dx: f64) -> f64 {
    a.iter().zip(b).map(|(a, b)| (a - b).abs()).sum::<f64>() * dx
}

/// Least-squares slope of log(err) against log(dx): the observed order.
pub fn observed_order(dx: &[f64], err: &[f64]) -> f64 {
    let n = dx.len() as f64;
    let lx: Vec<f64> = dx.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}
