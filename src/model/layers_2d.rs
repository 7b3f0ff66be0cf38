//! The multilayer μ(I) model on a raster: one material in N layers of fixed fractions
//! l_α, each with its velocity (u_α, v_α) ([`LayeredRaster`]), on a [`Raster2d`] in the
//! Cartesian or local frame (Fernández-Nieto et al. 2016, eq. 27–28, and Escalante et
//! al. 2023, eq. 9 with p_nh = 0, in two horizontal dimensions). The time step is the
//! pipeline hyperbolic → viscous ([`pipeline`]): the N-layer hydrostatic step
//! (`numerics/layers_2d.rs`, the line's face kernel on every x- and y-face) and the
//! μ(I) viscous columns (`numerics/viscous_2d.rs`, the line's column kernel in every
//! cell, with the vector Coulomb threshold at the bed). The scenario keys are the
//! line's (`model.layers`, `model.layer_fractions`, `rheology.basal`,
//! `rheology.regularization`, `output.static_threshold`, `initial.erodible_bed`).
//!
//! Diagnostics, as on the line (`model::granular::diagnostics`) with both components:
//! mass ∫ h dx dy, kinetic energy ∫ ½ h Σ_α l_α (u_α² + v_α²) dx dy, the largest layer
//! speed √(u_α² + v_α²), and the signal speed of the CFL step
//! ([`crate::numerics::layers_2d::signal_speed`]). The regularised rheology leaves a
//! deposit creeping at O(δ) (Escalante et al. 2023, Remark 2): a mass counts as at rest
//! below `output.static_threshold`, as on the line.
//!
//! Output: `/snapshots/h` and the depth-averaged `u`, `v` (ū = Σ l_α u_α), so the
//! monolayer's readers, maps and exports read a layered run unchanged; the profiles in
//! `/snapshots/u_layers`, `v_layers` (nt, N, ny, nx); `static_interface` (nt, ny, nx),
//! the height above the bed of the base of the lowest layer faster than the static
//! threshold (Fernández-Nieto et al. 2016, §4.2.5). The maps (largest thickness and
//! speed, arrival, deposit) are the monolayer's ([`RasterMaps`]) of the depth-averaged
//! flow ([`LayeredMaps`]).

use crate::grid::Raster2d;
use crate::model::band_sums::{self, BandSums};
use crate::model::granular::config::MultilayerSpec;
use crate::model::granular::pipeline::{with_law, WithLaw};
use crate::model::granular::profiles::interface_height;
use crate::model::raster_maps::RasterMaps;
use crate::model::tracker::Tracker;
use crate::model::{first_maximum, Diagnostics, Model};
use crate::numerics::layers_2d::{signal_speed_of, LayersStep2d};
use crate::numerics::viscous_2d::ViscousColumns2d;
use crate::numerics::workers::Workers;
use crate::numerics::Stage;
use crate::output::{CellField, OutputError, OutputSink, SnapshotView};
use crate::physics::rheology::{BasalFriction, FrictionLaw, LocalFriction};
use crate::physics::shallow::H_DRY;
use crate::physics::Material;
use crate::pipeline::Pipeline;
use crate::state::layered_raster::LayeredRaster;
use crate::state::State2d;

/// The layered raster model's run-time parameters (the physics is in the pipeline).
#[derive(Debug, Clone)]
pub struct Layers2d {
    /// Thickness above the erodible bed from which a cell counts for the front (m).
    pub front_threshold: f64,
    /// Layer speed (m/s) above which a layer flows: `static_interface` and the speed
    /// of a mass at rest ([`Model::rest_speed`]).
    pub static_threshold: f64,
    /// The erodible bed h_i per cell (zeros without one).
    pub h_bed: Vec<f64>,
    /// `time.film_thickness`: a thinner cell does not count for the kinetic energy.
    film: f64,
    /// The run's threads, for the diagnostics.
    workers: Workers,
}

impl Layers2d {
    /// The model on `raster` with the front and static thresholds (m, m/s).
    pub fn new(raster: &Raster2d, front_threshold: f64, static_threshold: f64) -> Layers2d {
        Layers2d {
            front_threshold,
            static_threshold,
            h_bed: vec![0.0; raster.nx() * raster.ny()],
            film: 0.0,
            workers: Workers::serial(),
        }
    }

    /// The model over the erodible bed `h_bed` (one per cell, row-major; empty: none).
    pub fn with_erodible_bed(mut self, h_bed: Vec<f64>) -> Layers2d {
        if h_bed.is_empty() {
            return self;
        }
        assert_eq!(h_bed.len(), self.h_bed.len(), "one erodible bed per cell");
        self.h_bed = h_bed;
        self
    }

    /// Films thinner than `film` (m) left out of the kinetic energy.
    pub fn with_film_thickness(mut self, film: f64) -> Layers2d {
        self.film = film;
        self
    }

    /// The diagnostics on the run's threads (the numbers do not depend on them).
    pub fn with_workers(mut self, workers: Workers) -> Layers2d {
        self.workers = workers;
        self
    }

    fn band_diagnostics(&self, raster: &Raster2d, state: &LayeredRaster, band: usize) -> BandSums {
        let (nx, n) = (raster.nx(), state.layers);
        let rows = raster.band_rows(band);
        let cells = rows.start * nx..rows.end * nx;
        let mut d = BandSums {
            signal: signal_speed_of(raster, state, cells.clone()),
            ..BandSums::empty()
        };
        for k in cells {
            let h = state.h[k];
            let (qx, qy) = (&state.hu[k * n..(k + 1) * n], &state.hv[k * n..(k + 1) * n]);
            d.mass += h;
            d.h_max = d.h_max.max(h);
            // Σ_α l_α (q_x² + q_y²)_α / h, and the fastest layer, one division per cell.
            let (mut energy, mut q2_max) = (0.0, 0.0f64);
            for ((&qx, &qy), &l) in qx.iter().zip(qy).zip(&state.l) {
                d.q_sum += qx + qy;
                let q2 = qx * qx + qy * qy;
                energy += l * q2;
                q2_max = q2_max.max(q2);
            }
            if h > H_DRY {
                d.wet += 1;
                let inv_h = 1.0 / h;
                if self.film == 0.0 || h >= self.film {
                    d.ke += energy * inv_h;
                }
                d.max_speed2 = d.max_speed2.max(q2_max * inv_h * inv_h);
            }
            if h - self.h_bed[k] > self.front_threshold {
                d.front = d.front.max(raster.x(k % nx));
            }
        }
        d
    }

    /// The depth-averaged velocities (ū, v̄) of every cell.
    fn mean_velocities(state: &LayeredRaster) -> (Vec<f64>, Vec<f64>) {
        (0..state.cells()).map(|k| state.mean_velocity(k)).unzip()
    }

    /// Height above the bed of the base of the lowest layer faster than the static
    /// threshold, in every cell (h where none is, 0 where dry).
    fn static_interface(&self, state: &LayeredRaster) -> Vec<f64> {
        let thr2 = self.static_threshold * self.static_threshold;
        (0..state.cells())
            .map(|k| {
                let h = state.h[k];
                if h <= H_DRY {
                    return 0.0;
                }
                let flowing = (0..state.layers).position(|a| {
                    let (u, v) = state.layer_velocity(k, a);
                    u * u + v * v > thr2
                });
                interface_height(&state.l, h, flowing)
            })
            .collect()
    }
}

impl Model for Layers2d {
    type Grid = Raster2d;
    type State = LayeredRaster;

    fn kind(&self) -> &'static str {
        "granular"
    }

    /// Band by band, the bands' sums added in band order: the same bits on any number
    /// of threads.
    fn diagnose(&self, raster: &Raster2d, state: &LayeredRaster) -> Diagnostics {
        let bands = self
            .workers
            .map_bands(raster.bands(), |k| self.band_diagnostics(raster, state, k));
        let n = state.layers;
        band_sums::combine(&bands, raster.cell_area(), || {
            (0..state.cells()).find(|&k| {
                let column = state.hu[k * n..(k + 1) * n]
                    .iter()
                    .chain(&state.hv[k * n..(k + 1) * n]);
                !state.h[k].is_finite() || column.clone().any(|q| !q.is_finite())
            })
        })
    }

    /// The layers keep regularised creep velocities (Escalante et al. 2023, Remark 2):
    /// a mass slower than the static threshold is at rest, as on the line.
    fn rest_speed(&self) -> f64 {
        self.static_threshold
    }

    /// The first cell with the fastest layer.
    fn fastest_cell(&self, _raster: &Raster2d, state: &LayeredRaster) -> Option<usize> {
        let fastest = |k: usize| {
            (0..state.layers)
                .map(|a| {
                    let (u, v) = state.layer_velocity(k, a);
                    u * u + v * v
                })
                .fold(0.0, f64::max)
        };
        first_maximum((0..state.cells()).map(fastest))
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    fn workers(&self) -> Option<&Workers> {
        Some(&self.workers)
    }

    /// The top of the flow b + h and the thickness h.
    fn gauge_cell(&self, raster: &Raster2d, state: &LayeredRaster, i: usize) -> Option<(f64, f64)> {
        use crate::grid::Grid;
        let h = state.h[i];
        Some((raster.bed()[i] + h, h))
    }

    fn snapshot(
        &self,
        raster: &Raster2d,
        state: &LayeredRaster,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let (u, v) = Self::mean_velocities(state);
        let (u_layers, v_layers) = state.layer_fields();
        let interface = self.static_interface(state);
        let extra = [CellField {
            name: "static_interface",
            units: "m",
            description: "elevation of the interface between the static and the flowing grains",
            data: &interface,
        }];
        sink.snapshot(&SnapshotView {
            t,
            h: &state.h,
            u: &u,
            v: Some(&v),
            shape: Some((raster.ny(), raster.nx())),
            w: None,
            p_nh: None,
            layers: state.layers,
            extra: &extra,
            layer_uv: Some((&u_layers, &v_layers)),
        })
    }
}

/// The stages of a layered raster run for one friction law: hyperbolic → viscous.
struct Stages<'a> {
    raster: &'a Raster2d,
    spec: &'a MultilayerSpec,
    workers: Workers,
}

impl WithLaw for Stages<'_> {
    type Out = Vec<Box<dyn Stage<Raster2d, LayeredRaster>>>;

    fn with<L: BasalFriction + LocalFriction + 'static>(self, law: L) -> Self::Out {
        let (spec, l) = (self.spec, &self.spec.layer_fractions);
        let opts = spec.viscous_options();
        vec![
            Box::new(LayersStep2d::new(law, self.raster, l, self.workers.clone())),
            Box::new(ViscousColumns2d::new(
                law,
                self.raster,
                l,
                opts,
                self.workers,
            )),
        ]
    }
}

/// The pipeline hyperbolic → viscous of a layered raster run (N ≥ 2 layers) with
/// friction law `law` on the threads of `workers` (the same bits on any number).
pub fn pipeline(
    law: &FrictionLaw,
    material: &Material,
    raster: &Raster2d,
    spec: &MultilayerSpec,
    workers: Workers,
) -> Pipeline<Raster2d, LayeredRaster> {
    let stages = Stages {
        raster,
        spec,
        workers,
    };
    Pipeline::new(with_law(law, material, stages))
}

/// The monolayer maps ([`RasterMaps`]) of a layered run: each state is handed to
/// them as its depth-averaged flow (h, h ū, h v̄), in a buffer kept between steps.
pub struct LayeredMaps {
    maps: RasterMaps,
    mean: State2d,
}

impl LayeredMaps {
    pub fn new(maps: RasterMaps) -> LayeredMaps {
        LayeredMaps {
            maps,
            mean: State2d::zeros(0),
        }
    }
}

/// The depth-averaged flow of `state` (h, Σ_α l_α (hu)_α, Σ_α l_α (hv)_α) into `mean`.
fn average_into(mean: &mut State2d, state: &LayeredRaster) {
    let cells = state.cells();
    mean.h.clone_from(&state.h);
    mean.hu.resize(cells, 0.0);
    mean.hv.resize(cells, 0.0);
    for k in 0..cells {
        (mean.hu[k], mean.hv[k]) = state.mean_discharge(k);
    }
}

/// The depth-averaged flow of `state`, in a new buffer (the end of a run, snapshots).
fn averaged(state: &LayeredRaster) -> State2d {
    let mut mean = State2d::zeros(0);
    average_into(&mut mean, state);
    mean
}

impl Tracker<Raster2d, LayeredRaster> for LayeredMaps {
    fn observe(&mut self, grid: &Raster2d, state: &LayeredRaster, t: f64) {
        average_into(&mut self.mean, state);
        self.maps.observe(grid, &self.mean, t);
    }

    fn write(
        &self,
        grid: &Raster2d,
        state: &LayeredRaster,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        self.maps.write(grid, &averaged(state), sink)
    }

    fn scalars(&self, grid: &Raster2d, state: &LayeredRaster) -> Vec<(&'static str, f64)> {
        self.maps.scalars(grid, &averaged(state))
    }

    fn write_so_far(
        &self,
        grid: &Raster2d,
        state: &LayeredRaster,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        self.maps.write_so_far(grid, &averaged(state), sink)
    }
}
