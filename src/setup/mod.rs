//! From a validated [`Scenario`] to a ready run of its model: the pieces every model
//! shares (grid, time-loop settings, run metadata), the dispatch on `model.kind`, and
//! one module per model that reads its part of the scenario. This is the only place
//! where scenarios meet models: `model/` and `numerics/` never read a scenario.

mod dilatant;
mod granular;
mod granular_2d;
mod submarine;

use crate::grid::{Grid, Line, LineSpec};
use crate::model::granular::Granular;
use crate::model::ModelKind;
use crate::output::{OutputSink, RunInfo, RunSummary};
use crate::scenario::{Coordinates, Scenario};
use crate::simulation::{Progress, RunConfig, RunError, Simulation};

/// A run of any model, as the command line and the sweeps drive it.
pub trait Run: Send {
    /// Runs to the end (see [`Simulation::run`]).
    fn run(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<RunSummary, RunError>;
    /// Names of the pipeline's stages, in order.
    fn stage_names(&self) -> Vec<&'static str>;
    /// Number of cells.
    fn cells(&self) -> usize;
    /// Run metadata (model, pressure, layers, …).
    fn info(&self) -> &RunInfo;
    /// Mass of the current (before a run: the initial) state.
    fn mass(&self) -> f64;
    /// Diagnostics of the current (before a run: the initial) state.
    fn diagnostics(&self) -> crate::model::Diagnostics;
}

impl<M: crate::model::Model> Run for Simulation<M> {
    fn run(
        &mut self,
        sink: &mut dyn OutputSink,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<RunSummary, RunError> {
        Simulation::run(self, sink, progress)
    }
    fn stage_names(&self) -> Vec<&'static str> {
        Simulation::stage_names(self)
    }
    fn cells(&self) -> usize {
        self.grid.cells()
    }
    fn mass(&self) -> f64 {
        self.diagnostics().mass
    }
    fn diagnostics(&self) -> crate::model::Diagnostics {
        Simulation::diagnostics(self)
    }
    fn info(&self) -> &RunInfo {
        &self.info
    }
}

/// The run of `scn`'s model, on one thread (a sweep's runs, `granflow check`).
pub fn build(scn: &Scenario) -> Box<dyn Run> {
    build_threads(scn, 1)
}

/// The run of `scn`'s model; a raster run works on `threads` threads (≥ 1), a line on
/// one. The results do not depend on `threads`.
pub fn build_threads(scn: &Scenario, threads: usize) -> Box<dyn Run> {
    match scn.model.kind {
        ModelKind::Granular if scn.domain.plane.is_some() && scn.model.layers > 1 => {
            Box::new(granular_2d::build_layers(scn, threads.max(1)))
        }
        ModelKind::Granular if scn.domain.plane.is_some() => {
            Box::new(build_granular_2d(scn, threads.max(1)))
        }
        ModelKind::Granular => Box::new(build_granular(scn)),
        ModelKind::Submarine => Box::new(build_submarine(scn)),
        ModelKind::Dilatant => Box::new(build_dilatant(scn)),
    }
}

/// The run of a dilatant scenario (`model.kind = "dilatant"`, Bouchut et al. 2021).
pub fn build_dilatant(scn: &Scenario) -> Simulation<crate::model::dilatant::Dilatant> {
    dilatant::build(scn)
}

/// The run of a granular scenario (`model.kind = "granular"`).
/// The submarine model's simulation (tests and benchmarks).
pub fn build_submarine(scn: &Scenario) -> Simulation<crate::model::submarine::Submarine> {
    submarine::build(scn)
}

pub fn build_granular(scn: &Scenario) -> Simulation<Granular> {
    granular::build(scn)
}

/// The run of a granular scenario on a raster domain (2-D) with one layer, on
/// `threads` threads ([`build_layers_2d`] for more layers).
pub fn build_granular_2d(
    scn: &Scenario,
    threads: usize,
) -> Simulation<crate::model::granular_2d::Granular2d> {
    assert_eq!(
        scn.model.layers, 1,
        "a multilayer raster scenario is built by build_layers_2d"
    );
    granular_2d::build(scn, threads)
}

/// The multilayer μ(I) model (`model.layers` > 1) on a raster domain, on `threads`
/// threads.
pub fn build_layers_2d(
    scn: &Scenario,
    threads: usize,
) -> Simulation<crate::model::layers_2d::Layers2d> {
    granular_2d::build_layers(scn, threads)
}

/// The line of a scenario, with its bed sampled at the cell centres.
pub fn scenario_line(scn: &Scenario) -> Line {
    let d = &scn.domain;
    let spec = LineSpec {
        x_min: d.x_min,
        x_max: d.x_max,
        cells: d.cells,
        slope_deg: d.slope_deg,
        coordinates: d.coordinates,
        left: scn.boundary.left,
        right: scn.boundary.right,
    };
    assert_eq!(
        scn.sampled.b.len(),
        d.cells,
        "the scenario's sampled profiles do not match domain.cells (see Sampled::of)"
    );
    Line::new(&spec, scn.sampled.b.clone())
}

/// The stop rules' plain values: the optional rules of `[time]` and the run's speed
/// bound. `z`: the potential elevation
/// (bed and plane) at the centres of the grid the run was built on.
pub fn stop_options(scn: &Scenario, z: impl Iterator<Item = f64>) -> crate::stop::StopOptions {
    let time = &scn.time;
    crate::stop::StopOptions {
        at_rest: time.stop_at_rest,
        settled_fraction: time.stop_when_settled.then_some(time.settle_fraction),
        speed_bound: speed_bound(scn, z),
    }
}

/// [`crate::stop::SPEED_BOUND_FACTOR`] × √(u₀² + w₀² + 2 g (Δz + h₀)): Δz the relief of
/// the potential elevation z (bed and plane) over the domain, h₀ the largest initial
/// thickness (erodible bed and water depth included), u₀, w₀ the largest initial
/// speeds.
pub fn speed_bound(scn: &Scenario, z: impl Iterator<Item = f64>) -> f64 {
    let (z_min, z_max) = z.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let s = &scn.sampled;
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut h0 = largest(&s.h) + largest(&s.h_bed);
    if let Some(eta) = &s.eta {
        let depth = eta.iter().zip(&s.b).fold(0.0f64, |m, (e, b)| m.max(e - b));
        h0 = h0.max(depth);
    }
    // On a raster the largest speed of the two components (w is empty there).
    let (u0, w0) = (largest(&s.u).max(largest(&s.v)), largest(&s.w));
    let drop = (z_max - z_min).max(0.0) + h0;
    crate::stop::SPEED_BOUND_FACTOR
        * (u0 * u0 + w0 * w0 + 2.0 * crate::physics::GRAVITY * drop).sqrt()
}

pub fn run_config(scn: &Scenario) -> RunConfig {
    RunConfig {
        t_end: scn.time.t_end,
        cfl: scn.time.cfl,
        output_every: scn.output.every,
        gauges: scn.output.gauges.clone(),
        gauges_y: scn.output.gauges_y.clone(),
        gauge_every: scn.output.gauge_every,
        settle_fraction: scn.time.settle_fraction,
    }
}

/// The run metadata written to the output file.
pub fn run_info(scn: &Scenario, pressure: &str, layers: usize) -> RunInfo {
    RunInfo {
        granflow_version: env!("CARGO_PKG_VERSION").to_string(),
        model: scn.model.kind.name().to_string(),
        pressure: pressure.to_string(),
        layers,
        coordinates: match scn.domain.coordinates {
            Coordinates::Local => "local",
            Coordinates::Cartesian => "cartesian",
            Coordinates::BedNormal => "bed_normal",
        }
        .to_string(),
        slope_deg: scn.domain.slope_deg,
        scenario_toml: scn.source_toml.clone(),
        front_threshold: scn.output.front_threshold,
        raster: None,
    }
}
