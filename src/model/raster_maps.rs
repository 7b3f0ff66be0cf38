//! The maps of a raster run and what is derived from them, gathered over every
//! accepted state ([`Tracker`]):
//!
//! - `h_max` = max_t h(x, y, t) over every state (so h_max ≥ the deposit everywhere);
//! - `speed_max` = max_t |(hu, hv)|/h over the states where h > h_f, the flow
//!   threshold `output.front_threshold` (0 where never reached: a film thinner than
//!   h_f has no meaningful velocity);
//! - `arrival_time` = the first t with h > h_f (NaN where never reached; 0 inside the
//!   release);
//! - `deposit` = h at the end of the run;
//! - `ppr` = max_t ρ|u|², the peak pressure (Pa) of the avalanche-hazard literature
//!   (the dynamic pressure of the flow), ρ = φ_s ρ_s the bulk density of the material.
//!   Since ρ is constant and |u| ≥ 0, max_t ρ|u|² = ρ (max_t |u|)² = ρ · speed_max²
//!   cell by cell, so it costs no work per step: it is formed when the maps are
//!   written.
//!
//! In the bed-normal frame (`domain.coordinates = "bed_normal"`) h in `h_max`, the
//! flow threshold and `deposit` is the thickness normal to the bed, c H (the state's H
//! per horizontal area times cos θ), and the speed is the speed along the surface
//! √(uᵀ G u) ([`crate::grid::BedMetric`]), so that `ppr` is ρ|u|² of the flow along the
//! bed: the meanings of AvaFrame's and RAMMS's pft, pfv and ppr.
//!
//! Over an erodible bed h_i (`initial.erodible_bed`, grains at rest on the bed), h
//! above stands for the thickness above it, h − h_i, as for the front of a line: a bed
//! at rest is no flow (its maps stay 0), and the deposit is negative where the flow
//! eroded the bed.
//!
//! The maps are written with every snapshot (as they stand, `deposit` then being the
//! snapshot's h) and once more at the end.
//!
//! The area reached A(t) = Δx Δy · #{cells reached by t} is a per-step series. The
//! runout and the travel angle are measured along the main flow direction d: the unit
//! vector from the centre of mass of the release, c₀ = Σ h₀ x / Σ h₀, to that of the
//! final state, c₁ (or +x when c₁ is within half a cell of c₀, e.g. a radial collapse
//! on a flat bed). With s = (x − c₀)·d, the top of the release is its cell (h₀ > h_f)
//! of least s and the runout point the reached cell of largest s. In world
//! coordinates (X, Y, Z) — (x, y, b) in Cartesian coordinates, (x cos θ + b sin θ, y,
//! −x sin θ + b cos θ) over a reference plane of slope θ — the runout length L is the
//! horizontal distance from the top to the runout point along the horizontal direction
//! of d, and the travel angle α = atan((Z_top − Z_runout)/L) (Heim 1932's Fahrböschung, the angle of the line
//! from the top of the release to the farthest point reached).

use std::borrow::Cow;

use crate::gis::path::{PathField, PathSpec};
use crate::gis::profile::{self, Profile};
use crate::grid::raster::Raster2d;
use crate::grid::Grid;
use crate::model::tracker::Tracker;
use crate::numerics::workers::{Disjoint, Workers};
use crate::output::maps::MAPS;
use crate::output::{CellField, OutputError, OutputSink, RunMaps};
use crate::state::layered_2d::State2d;

/// The maps of one raster run (allocated once, updated in place).
#[derive(Debug, Clone)]
pub struct RasterMaps {
    threshold: f64,
    /// Bulk density ρ (kg/m³) of the peak pressure.
    density: f64,
    h_max: Vec<f64>,
    speed_max: Vec<f64>,
    arrival: Vec<f64>,
    /// The initial thickness (the release), kept for the runout.
    h0: Vec<f64>,
    /// The erodible bed h_i per cell; empty without one.
    h_bed: Vec<f64>,
    reached: usize,
    area: Vec<f64>,
    /// The run's pool: the maps are updated tile by tile (band by band before the first
    /// step) on its threads.
    workers: Workers,
    /// Cells first reached in each stepped tile during one update (an integer count: the
    /// sum does not depend on the order).
    part_reached: Vec<usize>,
    /// `output.path`: the runout along a thalweg line (`gis::path`).
    path: Option<PathSpec>,
}

impl RasterMaps {
    /// Maps for `cells` cells with the flow threshold `threshold` (m) and the bulk
    /// density `density` (kg/m³) of the peak pressure.
    pub fn new(cells: usize, threshold: f64, density: f64) -> RasterMaps {
        RasterMaps {
            threshold,
            density,
            h_max: vec![0.0; cells],
            speed_max: vec![0.0; cells],
            arrival: vec![f64::NAN; cells],
            h0: Vec::new(),
            h_bed: Vec::new(),
            reached: 0,
            area: Vec::new(),
            workers: Workers::serial(),
            part_reached: Vec::new(),
            path: None,
        }
    }

    /// The runout is also measured along `path` (`output.path`).
    pub fn with_path(mut self, path: Option<PathSpec>) -> RasterMaps {
        self.path = path;
        self
    }

    /// The runout along the path and the maxima of the profiles (`/summary` `path_*`)
    /// and the profiles (`/path/*`, `gis::profile`), when there is a path.
    fn path_results(&self, grid: &Raster2d) -> (Vec<(&'static str, f64)>, Option<Profile>) {
        let Some(spec) = &self.path else {
            return (Vec::new(), None);
        };
        let pft = grid.mask_walls(&self.h_max);
        let ppr = self.peak_pressure();
        let ppr = grid.mask_walls(&ppr);
        let pfv = grid.mask_walls(&self.speed_max);
        let values = match spec.field {
            PathField::Pft => &pft,
            PathField::Ppr => &ppr,
        };
        let theta = grid.plane_theta();
        let cell = |k: usize| {
            let p = grid.centre(k);
            let b = grid.bed()[k];
            [
                p.x * theta.cos() + b * theta.sin(),
                p.y,
                -p.x * theta.sin() + b * theta.cos(),
            ]
        };
        let half = spec.width.map_or(f64::INFINITY, |w| 0.5 * w);
        let within = |k: usize| {
            let c = cell(k);
            spec.line.project([c[0], c[1]]).1 <= half
        };
        let profile = profile::along(
            &spec.line,
            half,
            grid.dx().min(grid.dy()),
            values.len(),
            |k| (!grid.is_wall(k)).then(|| cell(k)),
            [&pft, &pfv, &ppr],
        );
        let maxima = [
            ("path_max_pft", profile::max(&profile.pft)),
            ("path_max_pfv", profile::max(&profile.pfv)),
            ("path_max_ppr", profile::max(&profile.ppr)),
        ];
        let found = crate::gis::path::runout(
            &spec.line,
            cell,
            values.len(),
            |k| values[k] > spec.threshold && within(k),
            |k| self.h0[k] > self.threshold && within(k),
        );
        let Some(r) = found else {
            let mut s = vec![("path_runout_length", f64::NAN)];
            s.extend(maxima);
            return (s, Some(profile));
        };
        let mut s = vec![
            ("path_runout_s", r.runout_s),
            ("path_release_top_s", r.top_s),
            ("path_runout_length", r.length),
            ("path_runout_angle_deg", r.angle_deg),
            ("path_runout_x", r.runout_xy[0]),
            ("path_runout_y", r.runout_xy[1]),
        ];
        s.extend(maxima);
        (s, Some(profile))
    }

    /// The maps updated on the threads of `workers` (the step's pool): each cell's maps
    /// depend on that cell alone and the count of cells reached is an integer sum, so
    /// the maps are the same bits for any thread count.
    pub fn with_workers(mut self, workers: Workers) -> RasterMaps {
        self.workers = workers;
        self
    }

    /// The maps over the erodible bed `h_bed` (one per cell): they count the thickness
    /// above it.
    pub fn with_erodible_bed(mut self, h_bed: Vec<f64>) -> RasterMaps {
        self.h_bed = h_bed;
        self
    }

    /// The thickness above the erodible bed, h − h_i (h itself without one).
    fn above<'a>(&self, h: &'a [f64]) -> Cow<'a, [f64]> {
        if self.h_bed.is_empty() {
            Cow::Borrowed(h)
        } else {
            Cow::Owned(h.iter().zip(&self.h_bed).map(|(h, b)| h - b).collect())
        }
    }

    /// Area reached, runout and travel angle at the end (the `/summary` numbers).
    fn runout(&self, grid: &Raster2d, h1: &[f64]) -> Vec<(&'static str, f64)> {
        let centre = |h: &[f64]| {
            let (mut m, mut mx, mut my) = (0.0, 0.0, 0.0);
            for (k, &h) in h.iter().enumerate() {
                let p = grid.centre(k);
                if h.is_finite() {
                    m += h;
                    mx += h * p.x;
                    my += h * p.y;
                }
            }
            (mx / m, my / m)
        };
        let c0 = centre(&self.h0);
        let c1 = centre(h1);
        let (ex, ey) = (c1.0 - c0.0, c1.1 - c0.1);
        let len = ex.hypot(ey);
        let (dx, dy) = if len.is_finite() && len > 0.5 * grid.dx().min(grid.dy()) {
            (ex / len, ey / len)
        } else {
            (1.0, 0.0)
        };
        let s = |k: usize| {
            let p = grid.centre(k);
            (p.x - c0.0) * dx + (p.y - c0.1) * dy
        };
        let top = (0..self.h0.len())
            .filter(|&k| self.h0[k] > self.threshold)
            .min_by(|&a, &b| s(a).total_cmp(&s(b)));
        let front = (0..self.arrival.len())
            .filter(|&k| self.arrival[k].is_finite())
            .max_by(|&a, &b| s(a).total_cmp(&s(b)));
        let theta = grid.plane_theta();
        let world = |k: usize| {
            let p = grid.centre(k);
            let b = grid.bed()[k];
            (
                p.x * theta.cos() + b * theta.sin(),
                p.y,
                -p.x * theta.sin() + b * theta.cos(),
            )
        };
        // The horizontal direction of d, along which the runout is measured.
        let (hx, hy) = (dx * theta.cos(), dy);
        let norm = hx.hypot(hy);
        let (length, angle, front_xy, top_xy) = match (top, front) {
            (Some(t), Some(f)) => {
                let (a, b) = (world(t), world(f));
                let l = ((b.0 - a.0) * hx + (b.1 - a.1) * hy) / norm;
                let angle = (a.2 - b.2).atan2(l).to_degrees();
                let (pt, pf) = (grid.centre(t), grid.centre(f));
                (l, angle, (pf.x, pf.y), (pt.x, pt.y))
            }
            _ => (
                f64::NAN,
                f64::NAN,
                (f64::NAN, f64::NAN),
                (f64::NAN, f64::NAN),
            ),
        };
        vec![
            ("area_reached", self.reached as f64 * grid.cell_area()),
            ("runout_length", length),
            ("travel_angle_deg", angle),
            ("flow_direction_x", dx),
            ("flow_direction_y", dy),
            ("runout_x", front_xy.0),
            ("runout_y", front_xy.1),
            ("release_top_x", top_xy.0),
            ("release_top_y", top_xy.1),
        ]
    }
}

impl Tracker<Raster2d, State2d> for RasterMaps {
    fn observe(&mut self, grid: &Raster2d, state: &State2d, t: f64) {
        if self.h0.is_empty() {
            self.h0 = self.above(&state.h).into_owned();
        }
        let thr = self.threshold;
        let RasterMaps {
            h_max,
            speed_max,
            arrival,
            h_bed,
            workers,
            part_reached,
            ..
        } = self;
        let (h, hu, hv, h_bed) = (&state.h, &state.hu, &state.hv, &h_bed[..]);
        let (metric, tiles, nx) = (grid.metric(), &state.tiles, grid.nx());
        let (h_max, speed_max, arrival) = (
            Disjoint::new(&mut h_max[..]),
            Disjoint::new(&mut speed_max[..]),
            Disjoint::new(&mut arrival[..]),
        );
        // The maps of cell k; whether it arrived (first over h_f) now.
        // SAFETY (every access below): a task visits the cells of its own tile or band.
        let visit = |k: usize| -> bool {
            let mut above = if h_bed.is_empty() {
                h[k]
            } else {
                h[k] - h_bed[k]
            };
            if let Some(m) = metric {
                above *= m.cos[k];
            }
            // Nothing changes where there is no flow (h_max ≥ 0): such a cell costs the
            // read of h alone, not of the maps.
            if above <= 0.0 {
                return false;
            }
            let before = unsafe { h_max.get(k) };
            if above > before {
                unsafe { h_max.set(k, above) };
            }
            if above > thr {
                // √(hu² + hv²) rather than `hypot`: a libm call per wet cell was most of
                // the tracker's cost; momenta are far from overflow.
                let speed = match metric {
                    None => (hu[k] * hu[k] + hv[k] * hv[k]).sqrt() / h[k],
                    Some(m) => m.speed(k, hu[k] / h[k], hv[k] / h[k]),
                };
                if speed > unsafe { speed_max.get(k) } {
                    unsafe { speed_max.set(k, speed) };
                }
                // Reached before ⇔ h_max > h_f before (h_max, never NaN, is the largest h
                // above the bed seen, the arrival its first time over h_f): the arrival
                // map is read only on the first arrival.
                if before <= thr {
                    unsafe { arrival.set(k, t) };
                    return true;
                }
            }
            false
        };
        if tiles.is_known() {
            // Only the cells of the tiles the last step changed, one task per tile (the
            // threads share the flow's tiles): the maps of the others stand.
            part_reached.resize(tiles.count(), 0);
            let reached = Disjoint::new(&mut part_reached[..]);
            workers.tiles(tiles.stepped_by_load(), |_, t| {
                let n = tiles
                    .row_segments(t)
                    .flatten()
                    .filter(|&k| visit(k))
                    .count();
                // SAFETY: entry t is this task's alone.
                unsafe { reached.set(t, n) };
            });
            self.reached += tiles
                .stepped()
                .iter()
                .map(|&t| self.part_reached[t as usize])
                .sum::<usize>();
        } else {
            // Before the first step (once): every cell, band by band.
            let reached = workers.map_bands(grid.bands(), |band| {
                let rows = grid.band_rows(band);
                (rows.start * nx..rows.end * nx)
                    .filter(|&k| visit(k))
                    .count()
            });
            self.reached += reached.iter().sum::<usize>();
        }
        self.area.push(self.reached as f64 * grid.cell_area());
    }

    fn write(
        &self,
        grid: &Raster2d,
        state: &State2d,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let above = self.above(&state.h);
        let normal = normal_thickness(grid, &above);
        let values = self.values(grid, &normal);
        let ppr = self.ppr_description();
        let maps = Self::fields(&values, &ppr);
        let mut scalars = Vec::new();
        let mut path = None;
        if !self.h0.is_empty() {
            scalars = self.runout(grid, &above);
            let (s, p) = self.path_results(grid);
            scalars.extend(s);
            path = p;
        }
        scalars.push(("density", self.density));
        let profile: Vec<(&str, &str, &[f64])> = match &path {
            None => Vec::new(),
            Some(p) => vec![
                ("s", "m", &p.s),
                ("x", "m", &p.x),
                ("y", "m", &p.y),
                ("z", "m", &p.z),
                ("pft_max", "m", &p.pft),
                ("pfv_max", "m/s", &p.pfv),
                ("ppr_max", "Pa", &p.ppr),
            ],
        };
        sink.maps(&RunMaps {
            maps: &maps,
            series: &[("area_reached", "m^2", &self.area)],
            scalars: &scalars,
            profile: &profile,
        })
    }

    fn scalars(&self, grid: &Raster2d, state: &State2d) -> Vec<(&'static str, f64)> {
        if self.h0.is_empty() {
            Vec::new()
        } else {
            let mut s = self.runout(grid, &self.above(&state.h));
            s.extend(self.path_results(grid).0);
            s
        }
    }

    fn write_so_far(
        &self,
        grid: &Raster2d,
        state: &State2d,
        sink: &mut dyn OutputSink,
    ) -> Result<(), OutputError> {
        let above = self.above(&state.h);
        let normal = normal_thickness(grid, &above);
        let values = self.values(grid, &normal);
        let ppr = self.ppr_description();
        sink.maps_so_far(&Self::fields(&values, &ppr))
    }
}

/// The thickness normal to the bed c H of the thicknesses per horizontal area `h` in
/// the bed-normal frame; `h` itself in the other frames.
fn normal_thickness<'a>(grid: &Raster2d, h: &'a [f64]) -> Cow<'a, [f64]> {
    match grid.metric() {
        None => Cow::Borrowed(h),
        Some(m) => Cow::Owned(h.iter().zip(&m.cos).map(|(h, c)| h * c).collect()),
    }
}

impl RasterMaps {
    /// ρ · speed_max², cell by cell (see the module docs).
    fn peak_pressure(&self) -> Vec<f64> {
        self.speed_max
            .iter()
            .map(|&s| self.density * s * s)
            .collect()
    }

    /// The maps' values in their file order, `deposit` being `h` (above the erodible
    /// bed); wall (nodata) cells
    /// are NaN.
    fn values<'a>(&'a self, grid: &Raster2d, h: &'a [f64]) -> [Cow<'a, [f64]>; 5] {
        [
            grid.mask_walls(&self.h_max),
            grid.mask_walls(&self.speed_max),
            Cow::Owned(grid.mask_walls(&self.peak_pressure()).into_owned()),
            grid.mask_walls(&self.arrival),
            grid.mask_walls(h),
        ]
    }

    /// The maps with their names, units and descriptions, in file order
    /// ([`crate::output::maps::MAPS`]); `ppr` is described with the density the run
    /// used.
    fn fields<'a>(values: &'a [Cow<'a, [f64]>; 5], ppr: &'a str) -> [CellField<'a>; 5] {
        std::array::from_fn(|i| {
            let map = &MAPS[i];
            CellField {
                name: map.dataset,
                units: map.units,
                description: if map.dataset == "ppr" {
                    ppr
                } else {
                    map.description
                },
                data: &values[i],
            }
        })
    }

    /// The description of the `ppr` map, which names the density (ASCII, as the
    /// units are).
    fn ppr_description(&self) -> String {
        format!(
            "{}, with the flow density rho = {} kg/m^3 (material.phi x material.rho_s)",
            MAPS[2].description, self.density
        )
    }
}
