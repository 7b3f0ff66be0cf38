//! The Savage–Hutter model on a raster (two horizontal dimensions): one layer of
//! thickness h with the velocity (u, v) ([`State2d`]), on a [`Raster2d`] in Cartesian
//! or local coordinates, with Coulomb, μ(I) or Voellmy basal friction. The time step
//! is the pipeline hyperbolic → friction ([`pipeline`]): the 2-D hydrostatic step
//! (`numerics/hydrostatic_2d.rs`, the 1-D face kernel on every x- and y-face) and the
//! vector friction step (`numerics/friction_2d.rs`, the disk rule). At
//! `numerics.order = 2` the step is Heun's method around both, with the second-order
//! reconstruction of `numerics/muscl_2d.rs` ([`second_order_pipeline`]).
//!
//! Diagnostics: mass ∫ h dx dy, kinetic energy ∫ ½ h (u² + v²) dx dy, the largest
//! speed √(u² + v²), the signal speed max(|u|, |v|) + √(g_n h) per cell (with the
//! raster's `cfl_length` = min(Δx, Δy), the CFL bound of `numerics::hydrostatic_2d`),
//! and the front: the largest x of a cell thicker than the threshold above the erodible
//! bed.
//!
//! The erodible bed (Fernández-Nieto et al. 2016, §4.2; `initial.erodible_bed`, as on a
//! line) is a layer of the same grains at rest on the bed, added to the initial
//! thickness: h = h_flow + h_i. The friction law mobilises it or leaves it at rest;
//! no other term sees it. The front, the maps ([`crate::model::raster_maps`]) and
//! `/grid/h_bed` count h − h_i.

use crate::grid::Raster2d;
use crate::model::band_sums::{self, BandSums};
use crate::model::granular::pipeline::{with_law, WithLaw};
use crate::model::{first_maximum, Diagnostics, Model};
use crate::numerics::friction_2d::{CellFriction, FrictionStep2d};
use crate::numerics::hydrostatic_2d::HydrostaticStep2d;
use crate::numerics::muscl::Limiter;
use crate::numerics::ssp_rk2::Heun2d;
use crate::numerics::workers::{Disjoint, Workers};
use crate::numerics::Stage;
use crate::output::{OutputError, OutputSink, SnapshotView};
use crate::physics::rheology::{BasalFriction, Coulomb, FrictionLaw, LocalFriction, Voellmy};
use crate::physics::shallow::{celerity, velocity, H_DRY};
use crate::physics::{Material, GRAVITY};
use crate::pipeline::Pipeline;
use crate::state::tiles::Tiles;
use crate::state::State2d;

/// Per-cell friction coefficients of a raster run (row-major, one per cell), where the
/// scenario gives them as fields (friction zones); `None`: the law's own number.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrictionZones {
    /// The Coulomb coefficient μ (Coulomb and Voellmy laws).
    pub mu: Option<Vec<f64>>,
    /// Voellmy's turbulence coefficient ξ (m/s²).
    pub xi: Option<Vec<f64>>,
}

/// The 2-D granular model's run-time parameters.
#[derive(Debug, Clone)]
pub struct Granular2d {
    /// Thickness from which a cell counts for the front (m).
    pub front_threshold: f64,
    /// The erodible bed h_i per cell (Fernández-Nieto et al. 2016, §4.2; zeros without
    /// one), for `/grid/h_bed` and the front.
    pub h_bed: Vec<f64>,
    /// Whether `h_bed` is an erodible bed (not the zeros of a run without one).
    erodible: bool,
    /// The run's threads, for the diagnostics and the copy of the state of t^n.
    workers: Workers,
    /// `time.film_thickness`: a cell of smaller normal thickness does not count for
    /// the kinetic energy (0: every cell counts).
    film: f64,
}

impl Granular2d {
    /// The model on `raster` with the front threshold `front_threshold` (m).
    pub fn new(raster: &Raster2d, front_threshold: f64) -> Granular2d {
        Granular2d {
            front_threshold,
            h_bed: vec![0.0; raster.nx() * raster.ny()],
            erodible: false,
            workers: Workers::serial(),
            film: 0.0,
        }
    }

    /// The model with films thinner than `film` (m, normal to the bed) left out of the
    /// kinetic energy (and so from the settle stop; `time.film_thickness`).
    pub fn with_film_thickness(mut self, film: f64) -> Granular2d {
        self.film = film;
        self
    }

    /// The model with its diagnostics and its copy of the state on `workers` (the
    /// run's pool; the numbers do not depend on it).
    pub fn with_workers(mut self, workers: Workers) -> Granular2d {
        self.workers = workers;
        self
    }

    /// The diagnostics of the cells of band `band` of `state`: every cell while its
    /// tiles are unknown, else those of its visited tiles (non-empty or stepped,
    /// `state::tiles`), in row-major order either way (the cells left out are +0 and add
    /// nothing).
    fn band_diagnostics(&self, raster: &Raster2d, state: &State2d, band: usize) -> BandSums {
        let nx = raster.nx();
        let rows = raster.band_rows(band);
        if !state.tiles.is_known() {
            let cells = rows.start * nx..rows.end * nx;
            return self.cells_diagnostics(raster, state, std::iter::once(cells));
        }
        let tiles = &state.tiles;
        // A band with no visited tile is passed over with one look at its tiles.
        if tiles.band_columns(band, Tiles::is_visited).next().is_none() {
            return self.cells_diagnostics(raster, state, std::iter::empty());
        }
        let ranges = rows.flat_map(|j| {
            tiles
                .band_columns(band, Tiles::is_visited)
                .map(move |c| j * nx + c.start..j * nx + c.end)
        });
        self.cells_diagnostics(raster, state, ranges)
    }

    /// The diagnostics of the cells `cells` of `state`, in that order.
    fn cells_diagnostics(
        &self,
        raster: &Raster2d,
        state: &State2d,
        cells: impl Iterator<Item = std::ops::Range<usize>>,
    ) -> BandSums {
        let g_n = raster.g_n;
        let nx = raster.nx();
        let mut d = BandSums::empty();
        for k in cells.flatten() {
            let (h, qx, qy) = (state.h[k], state.hu[k], state.hv[k]);
            // An empty cell (every bit +0) changes no sum or extremum.
            if h.to_bits() | qx.to_bits() | qy.to_bits() == 0 {
                continue;
            }
            d.wet += usize::from(h > H_DRY);
            d.mass += h;
            d.q_sum += qx + qy;
            d.h_max = d.h_max.max(h);
            let (u, v) = (velocity(h, qx), velocity(h, qy));
            // In the bed-normal frame the speed along the surface and the celerity
            // √(g c h) of the normal thickness h = c H (docs/numerics.md).
            let (speed2, wave) = match raster.metric() {
                None => (u * u + v * v, celerity(g_n, h)),
                Some(m) => {
                    let c = m.cos[k];
                    (m.speed(k, u, v).powi(2), celerity(GRAVITY * c * c, h))
                }
            };
            d.max_speed2 = d.max_speed2.max(speed2);
            d.signal = d.signal.max(u.abs().max(v.abs()) + wave);
            if film_counts(self.film, raster, k, h) {
                d.ke += h * speed2;
            }
            // h − h_i ≤ h: without an erodible bed the first test decides. In the
            // bed-normal frame the threshold is on the normal thickness c H.
            let normal = raster.metric().map_or(1.0, |m| m.cos[k]);
            if normal * h > self.front_threshold
                && (!self.erodible || normal * (h - self.h_bed[k]) > self.front_threshold)
            {
                d.front = d.front.max(raster.x(k % nx));
            }
        }
        d
    }

    /// The model over the erodible bed `h_bed` (one per cell, row-major).
    pub fn with_erodible_bed(mut self, h_bed: Vec<f64>) -> Granular2d {
        assert_eq!(h_bed.len(), self.h_bed.len(), "one erodible bed per cell");
        self.h_bed = h_bed;
        self.erodible = true;
        self
    }
}

/// The stages of a 2-D run for the friction of its cells: hyperbolic → friction as one
/// stage, the friction applied in the hyperbolic step's last pass over the tiles
/// ([`HydrostaticStep2d::then_friction`], the same bits as two stages), or at order 2
/// (`limiter`) Heun's method around both ([`Heun2d`]).
fn stages<L: BasalFriction + 'static>(
    friction: CellFriction<L>,
    raster: &Raster2d,
    workers: Workers,
    limiter: Option<Limiter>,
) -> Vec<Box<dyn Stage<Raster2d, State2d>>> {
    if let Some(limiter) = limiter {
        return vec![Box::new(Heun2d::new(friction, raster, workers, limiter))];
    }
    let step = FrictionStep2d::with_friction(friction.clone(), workers.clone());
    vec![Box::new(
        HydrostaticStep2d::with_friction(friction, raster, workers).then_friction(step),
    )]
}

/// The stages of a 2-D run for one friction law, uniform over the raster.
struct Stages2d<'a> {
    raster: &'a Raster2d,
    workers: Workers,
    limiter: Option<Limiter>,
}

impl WithLaw for Stages2d<'_> {
    type Out = Vec<Box<dyn Stage<Raster2d, State2d>>>;

    fn with<L: BasalFriction + LocalFriction + 'static>(self, law: L) -> Self::Out {
        stages(
            CellFriction::Uniform(law),
            self.raster,
            self.workers,
            self.limiter,
        )
    }
}

/// The pipeline hyperbolic → friction of a 2-D run with friction law `law` on
/// `threads` threads: 1 runs fully serially; more give both stages one shared pool of
/// that many threads (`numerics::workers`), owned by the pipeline. The results are the
/// same bits for any `threads` (`numerics::workers`).
pub fn pipeline(
    law: &FrictionLaw,
    material: &Material,
    raster: &Raster2d,
    threads: usize,
) -> Result<Pipeline<Raster2d, State2d>, String> {
    Ok(pipeline_on(law, material, raster, Workers::new(threads)?))
}

/// [`pipeline`] on a given pool (shared with the run's maps tracker).
pub fn pipeline_on(
    law: &FrictionLaw,
    material: &Material,
    raster: &Raster2d,
    workers: Workers,
) -> Pipeline<Raster2d, State2d> {
    pipeline_of_order(law, material, raster, workers, None)
}

/// [`pipeline`] at order 2 with `limiter` (`numerics.order = 2`): one stage, Heun's
/// method around the second-order hyperbolic step and the friction ([`Heun2d`]).
pub fn second_order_pipeline(
    law: &FrictionLaw,
    material: &Material,
    raster: &Raster2d,
    threads: usize,
    limiter: Limiter,
) -> Result<Pipeline<Raster2d, State2d>, String> {
    let workers = Workers::new(threads)?;
    Ok(pipeline_of_order(
        law,
        material,
        raster,
        workers,
        Some(limiter),
    ))
}

/// [`pipeline_on`] at order 1 (`limiter` `None`) or 2.
pub fn pipeline_of_order(
    law: &FrictionLaw,
    material: &Material,
    raster: &Raster2d,
    workers: Workers,
    limiter: Option<Limiter>,
) -> Pipeline<Raster2d, State2d> {
    let stages = Stages2d {
        raster,
        workers,
        limiter,
    };
    Pipeline::new(with_law(law, material, stages))
}

/// [`pipeline_on`] with friction zones: the Coulomb or Voellmy law of every cell takes
/// the cell's μ and ξ where `zones` gives them (the law's own number elsewhere); μ(I)
/// has no zones (refused by validation).
pub fn pipeline_with_zones(
    law: &FrictionLaw,
    raster: &Raster2d,
    workers: Workers,
    zones: &FrictionZones,
) -> Result<Pipeline<Raster2d, State2d>, String> {
    pipeline_with_zones_of_order(law, raster, workers, zones, None)
}

/// [`pipeline_with_zones`] at order 1 (`limiter` `None`) or 2.
pub fn pipeline_with_zones_of_order(
    law: &FrictionLaw,
    raster: &Raster2d,
    workers: Workers,
    zones: &FrictionZones,
    limiter: Option<Limiter>,
) -> Result<Pipeline<Raster2d, State2d>, String> {
    let cells = raster.nx() * raster.ny();
    let field = |f: &Option<Vec<f64>>, uniform: f64, k: usize| f.as_ref().map_or(uniform, |v| v[k]);
    let stages = match *law {
        FrictionLaw::Coulomb { mu } => {
            let laws = (0..cells).map(|k| Coulomb {
                mu: field(&zones.mu, mu, k),
            });
            stages(
                CellFriction::PerCell(laws.collect()),
                raster,
                workers,
                limiter,
            )
        }
        FrictionLaw::Voellmy { mu, xi } => {
            let laws = (0..cells).map(|k| Voellmy {
                mu: field(&zones.mu, mu, k),
                xi: field(&zones.xi, xi, k),
            });
            stages(
                CellFriction::PerCell(laws.collect()),
                raster,
                workers,
                limiter,
            )
        }
        FrictionLaw::MuI { .. } => return Err("the μ(I) law has no friction zones".into()),
    };
    Ok(Pipeline::new(stages))
}

impl Model for Granular2d {
    type Grid = Raster2d;
    type State = State2d;

    fn kind(&self) -> &'static str {
        "granular"
    }

    /// The sums (mass, kinetic energy) are formed band by band ([`crate::grid::raster::BAND_ROWS`] rows)
    /// and the bands' sums added in band order: the same bits on any number of threads,
    /// and with the tiles the step skips left out (they hold +0).
    fn diagnose(&self, raster: &Raster2d, state: &State2d) -> Diagnostics {
        let bands = self
            .workers
            .map_bands(raster.bands(), |k| self.band_diagnostics(raster, state, k));
        combine(raster, state, &bands)
    }

    /// The diagnostics and the copy of the state of t^n ([`Self::save_state`]) in one
    /// pass: a task per band forms its diagnostics and a task per stepped tile copies
    /// it (the same sums in the same order, the same copy).
    fn diagnose_and_save(
        &self,
        raster: &Raster2d,
        state: &State2d,
        backup: &mut State2d,
    ) -> Diagnostics {
        if !copies_stepped_tiles(backup, state) {
            self.save_state(backup, state);
            return self.diagnose(raster, state);
        }
        let tiles = &state.tiles;
        let (h, hu, hv) = (
            Disjoint::new(&mut backup.h[..]),
            Disjoint::new(&mut backup.hu[..]),
            Disjoint::new(&mut backup.hv[..]),
        );
        let bands = self.workers.map_bands_and_tiles(
            raster.bands(),
            |band| self.band_diagnostics(raster, state, band),
            tiles.stepped_by_load(),
            // SAFETY: tile t is this task's alone.
            |t| unsafe { copy_tile(tiles, t, (&h, &hu, &hv), state) },
        );
        backup.tiles.clone_from(tiles);
        combine(raster, state, &bands)
    }

    /// The copy in chunks of 2¹⁴ values (128 kB) on the run's threads: a plain copy
    /// is bound by memory bandwidth, which two cores share but do not halve. Once the
    /// backup holds a copy of the state with known tiles, only the tiles the last step
    /// changed (its stepped tiles, `state::tiles`) differ between the two: they alone
    /// are copied.
    fn save_state(&self, backup: &mut State2d, state: &State2d) {
        if !copies_stepped_tiles(backup, state) {
            let chunk = 1 << 14;
            self.workers.copy(chunk, &mut backup.h, &state.h);
            self.workers.copy(chunk, &mut backup.hu, &state.hu);
            self.workers.copy(chunk, &mut backup.hv, &state.hv);
            backup.tiles.clone_from(&state.tiles);
            return;
        }
        let tiles = &state.tiles;
        let (h, hu, hv) = (
            Disjoint::new(&mut backup.h[..]),
            Disjoint::new(&mut backup.hu[..]),
            Disjoint::new(&mut backup.hv[..]),
        );
        self.workers.tiles(tiles.stepped_by_load(), |_, t| {
            // SAFETY: tile t is this task's alone.
            unsafe { copy_tile(tiles, t, (&h, &hu, &hv), state) };
        });
        backup.tiles.clone_from(tiles);
    }

    /// The first cell with the largest speed of [`Self::diagnose`]: u² + v², or in the
    /// bed-normal frame the speed along the surface (which is not the fastest
    /// horizontal velocity where the bed's slope varies).
    fn fastest_cell(&self, raster: &Raster2d, state: &State2d) -> Option<usize> {
        let metric = raster.metric();
        let speed2 = |k: usize| {
            let h = state.h[k];
            let (u, v) = (velocity(h, state.hu[k]), velocity(h, state.hv[k]));
            match metric {
                Some(m) => m.speed(k, u, v),
                None => u * u + v * v,
            }
        };
        first_maximum((0..state.h.len()).map(speed2))
    }

    /// The cells of the stepped tiles, summed over the accepted steps.
    fn cell_updates(&self, state: &State2d) -> Option<u64> {
        Some(state.tiles.updates())
    }

    fn bed_layer(&self) -> &[f64] {
        &self.h_bed
    }

    fn workers(&self) -> Option<&Workers> {
        Some(&self.workers)
    }

    /// The top of the flow b + h and the thickness h.
    fn gauge_cell(&self, raster: &Raster2d, state: &State2d, i: usize) -> Option<(f64, f64)> {
        use crate::grid::Grid;
        let h = state.h[i];
        Some((raster.bed()[i] + h, h))
    }

    fn snapshot(
        &self,
        raster: &Raster2d,
        state: &State2d,
        t: f64,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let u: Vec<f64> = state
            .h
            .iter()
            .zip(&state.hu)
            .map(|(&h, &q)| velocity(h, q))
            .collect();
        let v: Vec<f64> = state
            .h
            .iter()
            .zip(&state.hv)
            .map(|(&h, &q)| velocity(h, q))
            .collect();
        // Wall cells (nodata of the DEM) are NaN in the output.
        let (h, u, v) = (
            raster.mask_walls(&state.h),
            raster.mask_walls(&u),
            raster.mask_walls(&v),
        );
        sink.snapshot(&SnapshotView {
            t,
            h: &h,
            u: &u,
            v: Some(&v),
            shape: Some((raster.ny(), raster.nx())),
            w: None,
            p_nh: None,
            layers: 1,
            extra: &[],
            layer_uv: None,
        })
    }
}

/// Whether cell `k` of thickness `h` counts for the kinetic energy (and so for the
/// settle stop) under `time.film_thickness` = `film`: always without one (`film` = 0,
/// the same bits as before the key existed), else when its normal thickness (c h in
/// the bed-normal frame) is at least `film`. The signal speed counts every cell: a
/// film left out of the CFL step outruns it and goes unstable (measured in
/// docs/gis.md, "When a hazard run stops").
fn film_counts(film: f64, raster: &Raster2d, k: usize, h: f64) -> bool {
    film == 0.0 || raster.metric().map_or(1.0, |m| m.cos[k]) * h >= film
}

/// The diagnostics of `state` from its bands' parts `bands`, added in band order.
fn combine(raster: &Raster2d, state: &State2d, bands: &[BandSums]) -> Diagnostics {
    band_sums::combine(bands, raster.cell_area(), || {
        (0..state.h.len()).find(|&k| {
            !(state.h[k].is_finite() && state.hu[k].is_finite() && state.hv[k].is_finite())
        })
    })
}

/// Whether [`Granular2d::save_state`] copies only the stepped tiles of `state` into
/// `backup`: the backup holds a copy of the state with known tiles of the same raster.
fn copies_stepped_tiles(backup: &State2d, state: &State2d) -> bool {
    state.tiles.is_known() && backup.tiles.known_as(&state.tiles)
}

/// Copies the cells of tile `t` of `state` into the backup's fields `(h, hu, hv)`.
///
/// # Safety
/// No other task reads or writes the backup's cells of tile `t` meanwhile.
unsafe fn copy_tile(
    tiles: &Tiles,
    t: usize,
    (h, hu, hv): (&Disjoint<f64>, &Disjoint<f64>, &Disjoint<f64>),
    state: &State2d,
) {
    for cells in tiles.row_segments(t) {
        h.slice(cells.clone())
            .copy_from_slice(&state.h[cells.clone()]);
        hu.slice(cells.clone())
            .copy_from_slice(&state.hu[cells.clone()]);
        hv.slice(cells.clone()).copy_from_slice(&state.hv[cells]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Coordinates, RasterSpec, Sides};
    use crate::numerics::StepClock;

    /// A 70 × 40 raster (3 × 3 tiles) on a plane of 30° with a wavy bed, walls west
    /// and south and outflow east and north, in `coordinates`, with a cone released
    /// near the west edge: its flow crosses tiles, drains at its fronts and leaves by
    /// the east side.
    fn cone(coordinates: Coordinates) -> (Raster2d, State2d) {
        let (nx, ny) = (70, 40);
        let sides = Sides {
            west: BoundaryKind::Wall,
            east: BoundaryKind::Outflow,
            south: BoundaryKind::Wall,
            north: BoundaryKind::Outflow,
        };
        let spec = RasterSpec {
            nx,
            ny,
            x_min: 0.0,
            x_max: 3.5,
            y_min: 0.0,
            y_max: 2.0,
            sides,
            coordinates,
            slope_deg: if coordinates == Coordinates::Local {
                30.0
            } else {
                0.0
            },
        };
        let bed = |x: f64, y: f64| match coordinates {
            Coordinates::Local => 0.02 * (3.0 * x).sin() * (2.0 * y).cos(),
            _ => -0.5 * x + 0.05 * (3.0 * x).sin() * (2.0 * y).cos(),
        };
        let b = (0..nx * ny)
            .map(|k| bed(spec.x(k % nx), spec.y(k / nx)))
            .collect();
        let raster = Raster2d::new(spec, b).unwrap();
        let h = (0..nx * ny)
            .map(|k| {
                let (x, y) = (raster.x(k % nx) - 0.5, raster.y(k / nx) - 0.9);
                (0.2 - 0.6 * (x * x + y * y).sqrt()).max(0.0)
            })
            .collect();
        let zero = vec![0.0; nx * ny];
        (raster, State2d::from_velocities(h, &zero, &zero))
    }

    /// Whether two states hold the same bits.
    fn same_bits(a: &State2d, b: &State2d) -> bool {
        let same = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits());
        same(&a.h, &b.h) && same(&a.hu, &b.hu) && same(&a.hv, &b.hv)
    }

    #[test]
    fn the_fused_order_one_stage_is_hyperbolic_then_friction_to_the_bit() {
        let law = Voellmy { mu: 0.2, xi: 500.0 };
        for coordinates in [Coordinates::Local, Coordinates::BedNormal] {
            for threads in [1, 2] {
                let (raster, s0) = cone(coordinates);
                let workers = Workers::new(threads).unwrap();
                let friction = CellFriction::Uniform(law);
                let mut fused = stages(friction.clone(), &raster, workers.clone(), None);
                assert_eq!(fused.len(), 1);
                assert_eq!(fused[0].name(), "hyperbolic+friction");
                let mut apart: Vec<Box<dyn Stage<Raster2d, State2d>>> = vec![
                    Box::new(HydrostaticStep2d::with_friction(
                        friction.clone(),
                        &raster,
                        workers.clone(),
                    )),
                    Box::new(FrictionStep2d::with_friction(friction, workers)),
                ];
                let (mut a, mut b) = (s0.clone(), s0);
                let model = Granular2d::new(&raster, 1e-3);
                let (mut stepped, mut t) = (Vec::new(), 0.0);
                for step in 0..150 {
                    let s = model.diagnose(&raster, &a).signal_speed;
                    let clock = StepClock::at(t, 0.4 * raster.dx().min(raster.dy()) / s);
                    t += clock.dt;
                    fused[0].apply(&raster, clock, &mut a).unwrap();
                    for stage in &mut apart {
                        stage.apply(&raster, clock, &mut b).unwrap();
                    }
                    assert!(
                        same_bits(&a, &b),
                        "{coordinates:?}, {threads} threads: step {step}"
                    );
                    // The flags the fused stage set as it wrote the tiles are those of
                    // a classification of every cell (`touch`).
                    let (nx, ny) = (raster.nx(), raster.ny());
                    let mut fresh = b.clone();
                    fresh.tiles.touch();
                    fresh.refresh_tiles(nx, ny);
                    a.refresh_tiles(nx, ny);
                    assert_eq!(a.tiles.stepped(), fresh.tiles.stepped(), "step {step}");
                    for t in 0..a.tiles.count() {
                        assert_eq!(a.tiles.is_visited(t), fresh.tiles.is_visited(t));
                    }
                    stepped.push(a.tiles.stepped().len());
                }
                // The flow crossed tiles: the stepped set grew from the release's.
                assert!(stepped.iter().max() > stepped.first(), "{stepped:?}");
            }
        }
    }

    #[test]
    fn diagnostics_with_the_copy_of_the_state_are_the_diagnostics_and_the_copy() {
        let law = Voellmy { mu: 0.2, xi: 500.0 };
        for threads in [1, 2] {
            let (raster, mut state) = cone(Coordinates::Local);
            let workers = Workers::new(threads).unwrap();
            let model = Granular2d::new(&raster, 1e-3).with_workers(workers.clone());
            let mut stage = stages(CellFriction::Uniform(law), &raster, workers, None);
            // The first copy is whole (unknown tiles), the later ones of stepped tiles.
            let mut backup = state.clone();
            backup.h.fill(7.0);
            for k in 0..40 {
                let d = model.diagnose_and_save(&raster, &state, &mut backup);
                let plain = model.diagnose(&raster, &state);
                assert_eq!(format!("{d:?}"), format!("{plain:?}"));
                assert!(same_bits(&backup, &state));
                let clock = StepClock::at(k as f64 * 1e-3, 1e-3);
                stage[0].apply(&raster, clock, &mut state).unwrap();
            }
        }
    }
}
