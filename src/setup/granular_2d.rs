//! From a validated [`Scenario`] on a raster domain to a ready 2-D granular
//! [`Simulation`]: the [`Raster2d`] of `[domain]` and `[boundary]` with the bed sampled
//! at its centres, the state (h, hu, hv) from `initial.h`, `initial.u`, `initial.v`,
//! the model and its pipeline for the friction law on `threads` threads, and the
//! [`RasterMaps`] tracker (maxima, arrival time, deposit, runout).
//! Everything that can be wrong with the scenario was refused by its validation.

use crate::grid::raster::{Raster2d, RasterSpec, Sides};
use crate::grid::Grid;
use crate::model::granular_2d::{pipeline_of_order, pipeline_with_zones_of_order, Granular2d};
use crate::model::raster_maps::RasterMaps;
use crate::numerics::workers::Workers;
use crate::output::{RasterInfo, ReleaseVolumes};
use crate::scenario::Scenario;
use crate::setup::{run_config, run_info};
use crate::simulation::Simulation;
use crate::state::layered_2d::State2d;

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
        .unwrap_or_else(|e| panic!("a validated raster domain was refused: {e}"));
    if d.curvature {
        raster
    } else {
        raster.without_friction_curvature()
    }
}

pub fn build(scn: &Scenario, threads: usize) -> Simulation<Granular2d> {
    let grid = scenario_raster(scn);
    let plane = scn.domain.plane.as_ref().expect("a raster domain");
    let s = &scn.sampled;
    // In the bed-normal frame the state holds H = h/c per horizontal area: a thickness
    // given by an expression or a table is normal to the bed (a polygon release was
    // converted by its `thickness_is` already), and so is the erodible bed's.
    let per_area = |values: &[f64], normal: bool| -> Vec<f64> {
        match grid.metric() {
            Some(m) if normal => values.iter().zip(&m.cos).map(|(h, c)| h / c).collect(),
            _ => values.to_vec(),
        }
    };
    let h_flow = per_area(&s.h, scn.release.is_none());
    let h_bed = per_area(&s.h_bed, true);
    // The erodible bed is grains at rest added under the flow (h = initial.h + h_i).
    let h: Vec<f64> = if scn.initial.has_erodible_bed() {
        h_flow
            .iter()
            .zip(&h_bed)
            .map(|(&h, &h_i)| h + h_i)
            .collect()
    } else {
        h_flow
    };
    let state = State2d::from_velocities(h, &s.u, &s.v);
    // A pool that cannot be started falls back to one thread: the same bits, slower.
    let workers = Workers::new(threads).unwrap_or_else(|_| Workers::serial());
    let model = Granular2d::new(&grid, scn.output.front_threshold)
        .with_workers(workers.clone())
        .with_film_thickness(scn.time.film_thickness);
    let (model, erodible) = if scn.initial.has_erodible_bed() {
        (model.with_erodible_bed(h_bed.clone()), h_bed)
    } else {
        (model, Vec::new())
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
    info.raster = Some(RasterInfo {
        nx: grid.nx(),
        ny: grid.ny(),
        dx: grid.dx(),
        dy: grid.dy(),
        crs_epsg: plane.crs.epsg,
        crs_wkt: plane.crs.wkt.clone(),
        release: scn.release.as_ref().map(|r| ReleaseVolumes {
            volume: r.volume,
            volume_on_walls: r.volume_on_walls,
        }),
        wall_cells: scn.sampled.wall.iter().filter(|&&w| w).count(),
        geotransform: plane.geotransform,
    });
    let tan_theta = grid.plane_theta().tan();
    let nx = grid.nx();
    let z = (0..grid.nx() * grid.ny()).map(|c| grid.bed()[c] - grid.x(c % nx) * tan_theta);
    let rules = crate::stop::default_rules(super::stop_options(scn, z));
    let config = run_config(scn);
    let cells = grid.nx() * grid.ny();
    let mut sim = Simulation::new(grid, model, state, stages, rules, config, info);
    let density = scn.material.phi * scn.material.rho_s;
    sim.set_tracker(Box::new(
        RasterMaps::new(cells, scn.output.front_threshold, density)
            .with_path(scn.output.path.clone())
            .with_erodible_bed(erodible)
            .with_workers(workers),
    ));
    sim
}
