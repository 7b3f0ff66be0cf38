//! From a validated [`Scenario`] on a raster domain to a ready 2-D granular
//! [`Simulation`]: the [`Raster2d`] of `[domain]` and `[boundary]` with the bed sampled
//! at its centres, the state (h, hu, hv) from `initial.h`, `initial.u`, `initial.v`,
//! the model and its pipeline for the friction law on `threads` threads, and the
//! [`RasterMaps`] tracker (maxima, arrival time, deposit, runout). With
//! `model.layers` = N > 1 the same pieces build the multilayer μ(I) model
//! ([`Layers2d`]): every layer starts with the cell's velocity, as on a line.
//! Everything that can be wrong with the scenario was refused by its validation.

use crate::grid::raster::{Raster2d, RasterSpec, Sides};
use crate::grid::{Grid, RasterGeometry};
use crate::model::granular_2d::{pipeline_of_order, pipeline_with_zones_of_order, Granular2d};
use crate::model::layers_2d::{self, LayeredMaps, Layers2d};
use crate::model::raster_maps::RasterMaps;
use crate::numerics::workers::Workers;
use crate::output::{RasterInfo, ReleaseVolumes};
use crate::scenario::Scenario;
use crate::setup::{run_config, run_info};
use crate::simulation::Simulation;
use crate::state::layered_2d::State2d;
use crate::state::layered_raster::LayeredRaster;

/// The raster of a scenario, with its bed sampled at the cell centres and its wall
/// cells (where a raster bed has no data).
pub fn scenario_raster(scn: &Scenario) -> Raster2d {
    let d = &scn.domain;
    let plane = d.plane.as_ref().expect("a raster domain");
    let spec = RasterSpec {
        nx: d.cells,
        ny: plane.ny,
        x_min: d.x_min,
        x_max: d.x_max,
        y_min: plane.y_min,
        y_max: plane.y_max,
        sides: Sides {
            west: scn.boundary.left,
            east: scn.boundary.right,
            south: scn.boundary.south,
            north: scn.boundary.north,
        },
        coordinates: d.coordinates,
        slope_deg: d.slope_deg,
    };
    let raster = Raster2d::with_walls(spec, scn.sampled.b.clone(), scn.sampled.wall.clone())
        .and_then(|r| r.georeferenced(raster_geometry(scn)))
        .unwrap_or_else(|e| panic!("a validated raster domain was refused: {e}"));
    if d.curvature {
        raster
    } else {
        raster.without_friction_curvature()
    }
}

/// Where the scenario's raster is on the map: the edges of `[domain]`, with the cell
/// size of the DEM exactly as read when the domain is a DEM's grid, and the CRS of its
/// raster files.
fn raster_geometry(scn: &Scenario) -> RasterGeometry {
    let d = &scn.domain;
    let plane = d.plane.as_ref().expect("a raster domain");
    let mut g = RasterGeometry::of_extent(
        d.cells,
        plane.ny,
        [d.x_min, d.x_max],
        [plane.y_min, plane.y_max],
    );
    if let Some([_, _, cell]) = plane.geotransform {
        (g.dx, g.dy) = (cell, cell);
    }
    g.crs = plane.crs.clone();
    g
}

/// The initial thickness per cell (the erodible bed under the flow included) and the
/// erodible bed (empty without one). In the bed-normal frame the state holds H = h/c
/// per horizontal area: a thickness given by an expression or a table is normal to
/// the bed (a polygon release was converted by its `thickness_is` already), and so is
/// the erodible bed's.
fn initial_thickness(scn: &Scenario, grid: &Raster2d) -> (Vec<f64>, Vec<f64>) {
    let s = &scn.sampled;
    let per_area = |values: &[f64], normal: bool| -> Vec<f64> {
        match grid.metric() {
            Some(m) if normal => values.iter().zip(&m.cos).map(|(h, c)| h / c).collect(),
            _ => values.to_vec(),
        }
    };
    let h_flow = per_area(&s.h, scn.release.is_none());
    if !scn.initial.has_erodible_bed() {
        return (h_flow, Vec::new());
    }
    // The erodible bed is grains at rest added under the flow (h = initial.h + h_i).
    let h_bed = per_area(&s.h_bed, true);
    let h = h_flow
        .iter()
        .zip(&h_bed)
        .map(|(&h, &h_i)| h + h_i)
        .collect();
    (h, h_bed)
}

/// What the output file records of the raster.
fn raster_info(scn: &Scenario) -> RasterInfo {
    RasterInfo {
        release: scn.release.as_ref().map(|r| ReleaseVolumes {
            volume: r.volume,
            volume_on_walls: r.volume_on_walls,
        }),
        wall_cells: scn.sampled.wall.iter().filter(|&&w| w).count(),
    }
}

/// The stop rules, with the bed's height over the horizontal for the travel angle.
fn stop_rules(scn: &Scenario, grid: &Raster2d) -> Vec<Box<dyn crate::stop::StopRule>> {
    let tan_theta = grid.plane_theta().tan();
    let nx = grid.nx();
    let z = (0..grid.nx() * grid.ny()).map(|c| grid.bed()[c] - grid.x(c % nx) * tan_theta);
    crate::stop::default_rules(super::stop_options(scn, z))
}

/// The maps tracker of a raster run.
fn raster_maps(scn: &Scenario, cells: usize, erodible: Vec<f64>, workers: Workers) -> RasterMaps {
    let density = scn.material.phi * scn.material.rho_s;
    RasterMaps::new(cells, scn.output.front_threshold, density)
        .with_path(scn.output.path.clone())
        .with_erodible_bed(erodible)
        .with_workers(workers)
}

pub fn build(scn: &Scenario, threads: usize) -> Simulation<Granular2d> {
    let grid = scenario_raster(scn);
    let (h, erodible) = initial_thickness(scn, &grid);
    let state = State2d::from_velocities(h, &scn.sampled.u, &scn.sampled.v);
    // A pool that cannot be started falls back to one thread: the same bits, slower.
    let workers = Workers::new(threads).unwrap_or_else(|_| Workers::serial());
    let model = Granular2d::new(&grid, scn.output.front_threshold)
        .with_workers(workers.clone())
        .with_film_thickness(scn.time.film_thickness);
    let model = if scn.initial.has_erodible_bed() {
        model.with_erodible_bed(erodible.clone())
    } else {
        model
    };
    let limiter = (scn.numerics.order == 2).then_some(scn.numerics.limiter);
    let stages = match &scn.friction_zones {
        None => pipeline_of_order(
            &scn.friction,
            &scn.material,
            &grid,
            workers.clone(),
            limiter,
        ),
        Some(zones) => {
            pipeline_with_zones_of_order(&scn.friction, &grid, workers.clone(), zones, limiter)
                .expect("validation refuses friction zones for the μ(I) law")
        }
    };
    let mut info = run_info(scn, "hydrostatic", 1);
    info.raster = Some(raster_info(scn));
    let rules = stop_rules(scn, &grid);
    let cells = grid.nx() * grid.ny();
    let maps = raster_maps(scn, cells, erodible, workers);
    let mut sim = Simulation::new(grid, model, state, stages, rules, run_config(scn), info);
    sim.set_tracker(Box::new(maps));
    sim
}

/// The multilayer μ(I) model (`model.layers` > 1) on a raster, on `threads` threads.
pub fn build_layers(scn: &Scenario, threads: usize) -> Simulation<Layers2d> {
    let grid = scenario_raster(scn);
    let (h, erodible) = initial_thickness(scn, &grid);
    let l = &scn.multilayer.layer_fractions;
    let s = &scn.sampled;
    let state = LayeredRaster::from_velocities((grid.nx(), grid.ny()), l, h, &s.u, &s.v);
    let workers = Workers::new(threads).unwrap_or_else(|_| Workers::serial());
    let model = Layers2d::new(
        &grid,
        scn.output.front_threshold,
        scn.multilayer.static_threshold,
    )
    .with_workers(workers.clone())
    .with_film_thickness(scn.time.film_thickness)
    .with_erodible_bed(erodible.clone());
    let stages = layers_2d::pipeline(
        &scn.friction,
        &scn.material,
        &grid,
        &scn.multilayer,
        workers.clone(),
    );
    let mut info = run_info(scn, "hydrostatic", l.len());
    info.raster = Some(raster_info(scn));
    let rules = stop_rules(scn, &grid);
    let cells = grid.nx() * grid.ny();
    let maps = LayeredMaps::new(raster_maps(scn, cells, erodible, workers));
    let mut sim = Simulation::new(grid, model, state, stages, rules, run_config(scn), info);
    sim.set_tracker(Box::new(maps));
    sim
}
