//! The raster: a uniform 2-D grid of nx × ny rectangular cells (x along i, y along j),
//! for the Savage–Hutter model in two horizontal dimensions.
//!
//! Cells V_{ij} = [x_{i−1/2}, x_{i+1/2}] × [y_{j−1/2}, y_{j+1/2}] of widths Δx, Δy,
//! numbered row-major, cell = j·nx + i. The frames are those of the line
//! ([`super::Line`]): in local coordinates over a reference plane of slope θ along x
//! the potential is z = b(x, y) − x tan θ and g_n = g cos θ; in Cartesian coordinates
//! z = b(x, y) and g_n = g.
//!
//! The bed and the potential carry a ghost ring ((nx + 2)·(ny + 2), index
//! (j + 1)(nx + 2) + i + 1 for cell (i, j)): a wall mirrors the edge cell (no step at
//! the wall), an outflow continues the reference plane with the edge bed, as on a line.
//!
//! Walls inside the raster. A cell may be a **wall** (a nodata cell of the DEM): it
//! holds no mass, and each face between it and a cell of flow is reflective, the
//! wall side being the mirror of the flow side (same h, b and z, the normal discharge
//! reversed), as at a wall side of the domain. The mask ([`Raster2d::walls`]) is
//! empty when the raster has no wall cell, and the stages then take their code path
//! without walls. The bed of a wall cell is NaN in [`Grid::bed`] (written as such) and
//! 0 in the ghost-ring arrays, which no face reads there.
//!
//! Bands and tiles. The cells are grouped in bands of [`BAND_ROWS`] whole rows (the last
//! band may be shorter), and each band in tiles of `state::tiles::TILE_COLS` columns:
//! the units of work of the 2-D stages whatever the thread count, so that every
//! per-band reduction is summed in the same order and a run gives the same bits on 1,
//! 2 or 4 threads. A tile reads one row and one column of halo on each side (its
//! neighbours' cells, or the boundary rule at the domain's edge) and writes only its
//! own cells; a decomposition across machines would exchange those halos. Which tiles
//! a step visits is the state's (`state::tiles`).

use super::{BedMetric, BoundaryKind, Coordinates, Grid, GridSpec, Point, RasterGeometry, Stencil};
use crate::physics::GRAVITY;
use std::ops::Range;

/// Rows per band (tile) of the 2-D stages: fixed, so that the partition, and with it
/// every reduction, is independent of the number of threads.
pub const BAND_ROWS: usize = 16;

/// The boundary kind of each side of a raster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sides {
    /// x = x_min.
    pub west: BoundaryKind,
    /// x = x_max.
    pub east: BoundaryKind,
    /// y = y_min.
    pub south: BoundaryKind,
    /// y = y_max.
    pub north: BoundaryKind,
}

impl Sides {
    /// Every side of the same kind.
    pub fn all(kind: BoundaryKind) -> Sides {
        Sides {
            west: kind,
            east: kind,
            south: kind,
            north: kind,
        }
    }
}

/// What a raster is built from; the bed is sampled at the cell centres.
#[derive(Debug, Clone, PartialEq)]
pub struct RasterSpec {
    pub nx: usize,
    pub ny: usize,
    pub x_min: f64,
    pub x_max: f64,
    pub y_min: f64,
    pub y_max: f64,
    pub sides: Sides,
    pub coordinates: Coordinates,
    /// Slope θ (degrees) of the reference plane along x (local coordinates; 0 in
    /// Cartesian coordinates).
    pub slope_deg: f64,
}

impl RasterSpec {
    /// Δx = (x_max − x_min)/nx.
    pub fn dx(&self) -> f64 {
        (self.x_max - self.x_min) / self.nx as f64
    }

    /// Δy = (y_max − y_min)/ny.
    pub fn dy(&self) -> f64 {
        (self.y_max - self.y_min) / self.ny as f64
    }

    /// Centre x_i = x_min + (i + ½)Δx of column i.
    pub fn x(&self, i: usize) -> f64 {
        super::line::cell_centre(self.x_min, self.dx(), i)
    }

    /// Centre y_j = y_min + (j + ½)Δy of row j.
    pub fn y(&self, j: usize) -> f64 {
        super::line::cell_centre(self.y_min, self.dy(), j)
    }
}

/// A uniform raster with its bed, potential, gravity and boundary kinds.
#[derive(Debug, Clone)]
pub struct Raster2d {
    spec: RasterSpec,
    dx: f64,
    dy: f64,
    /// Centres of every cell, row-major (nx·ny each): `/grid/x`, `/grid/y`.
    x: Vec<f64>,
    y: Vec<f64>,
    /// Bed over the reference plane at the centres, row-major (nx·ny).
    b: Vec<f64>,
    /// Bed over the reference plane with the ghost ring ((nx + 2)·(ny + 2)).
    pub b_ghost: Vec<f64>,
    /// Potential z = b + b̃ with the ghost ring ((nx + 2)·(ny + 2)).
    pub z: Vec<f64>,
    /// Gravity normal to the reference plane.
    pub g_n: f64,
    /// Slope of the reference plane along x (radians).
    pub theta: f64,
    /// Wall cells (row-major, nx·ny), or empty when there is none.
    walls: Vec<bool>,
    /// The bed's gradient, cos θ and curvature in the bed-normal frame, else `None`.
    metric: Option<BedMetric>,
    /// Where the raster is on the map: the extent of `spec` without CRS, or the
    /// scenario's ([`Raster2d::georeferenced`]).
    geometry: RasterGeometry,
}

impl Raster2d {
    /// Builds the raster of `spec` with the bed `bed` sampled at the centres
    /// (row-major, nx·ny values). Refuses an empty raster, an empty or inverted
    /// extent, a wrong number of bed values and a non-finite bed.
    pub fn new(spec: RasterSpec, bed: Vec<f64>) -> Result<Raster2d, String> {
        Raster2d::with_walls(spec, bed, Vec::new())
    }

    /// [`Raster2d::new`] with wall cells: `walls` is empty (no wall) or one flag per
    /// cell (row-major); the bed of a wall cell may be NaN. Refuses a mask of the
    /// wrong length and a raster that is all walls.
    pub fn with_walls(
        spec: RasterSpec,
        mut bed: Vec<f64>,
        mut walls: Vec<bool>,
    ) -> Result<Raster2d, String> {
        let (nx, ny) = (spec.nx, spec.ny);
        if !walls.is_empty() {
            if walls.len() != nx * ny {
                return Err(format!(
                    "the wall mask has {} values for {nx} × {ny} cells",
                    walls.len()
                ));
            }
            if walls.iter().all(|&w| w) {
                return Err("every cell of the raster is a wall".into());
            }
            if !walls.iter().any(|&w| w) {
                walls = Vec::new();
            }
        }
        let is_wall = |k: usize| !walls.is_empty() && walls[k];
        if nx == 0 || ny == 0 {
            return Err(format!("a raster needs cells in x and y, got {nx} × {ny}"));
        }
        if !(spec.x_max > spec.x_min && spec.y_max > spec.y_min) {
            return Err(format!(
                "the raster's extent [{}, {}] × [{}, {}] is empty",
                spec.x_min, spec.x_max, spec.y_min, spec.y_max
            ));
        }
        if bed.len() != nx * ny {
            return Err(format!(
                "the bed has {} values for {nx} × {ny} cells",
                bed.len()
            ));
        }
        if let Some(k) = (0..bed.len()).position(|k| !bed[k].is_finite() && !is_wall(k)) {
            return Err(format!(
                "the bed is not finite at cell (i, j) = ({}, {})",
                k % nx,
                k / nx
            ));
        }
        // The bed at the centres, as output (NaN on walls), and as the ghost-ring
        // arrays hold it (0 on walls).
        let output_bed = (!walls.is_empty()).then(|| {
            let mut output = bed.clone();
            for k in (0..bed.len()).filter(|&k| is_wall(k)) {
                bed[k] = 0.0;
                output[k] = f64::NAN;
            }
            output
        });
        let (dx, dy) = (spec.dx(), spec.dy());
        let theta = spec.slope_deg.to_radians();
        let (g_n, tan_theta) = match spec.coordinates {
            Coordinates::Local => (GRAVITY * theta.cos(), theta.tan()),
            Coordinates::Cartesian | Coordinates::BedNormal => (GRAVITY, 0.0),
        };
        let metric = (spec.coordinates == Coordinates::BedNormal)
            .then(|| BedMetric::new(nx, ny, dx, dy, &bed, &walls));
        let plane = |x: f64| -x * tan_theta;
        let xc: Vec<f64> = (0..nx).map(|i| spec.x(i)).collect();
        let yc: Vec<f64> = (0..ny).map(|j| spec.y(j)).collect();
        let mut x = Vec::with_capacity(nx * ny);
        let mut y = Vec::with_capacity(nx * ny);
        for &yj in &yc {
            x.extend_from_slice(&xc);
            y.extend(std::iter::repeat_n(yj, nx));
        }
        let stride = nx + 2;
        let mut b_ghost = vec![0.0; stride * (ny + 2)];
        let mut z = vec![0.0; stride * (ny + 2)];
        for j in 0..ny {
            for i in 0..nx {
                let k = (j + 1) * stride + i + 1;
                b_ghost[k] = bed[j * nx + i];
                z[k] = bed[j * nx + i] + plane(xc[i]);
            }
            // West and east ghosts, as the line's (`Line::with_spacing`).
            let (west, east) = ((j + 1) * stride, (j + 1) * stride + nx + 1);
            let (b0, b1) = (bed[j * nx], bed[j * nx + nx - 1]);
            b_ghost[west] = b0;
            b_ghost[east] = b1;
            z[west] = match spec.sides.west {
                BoundaryKind::Wall => z[west + 1],
                BoundaryKind::Outflow => b0 + plane(xc[0] - dx),
            };
            z[east] = match spec.sides.east {
                BoundaryKind::Wall => z[east - 1],
                BoundaryKind::Outflow => b1 + plane(xc[nx - 1] + dx),
            };
        }
        // South and north ghost rows: the plane does not vary along y, so a wall and an
        // outflow both see the edge row's bed (corners included).
        let (first, last) = (stride, ny * stride);
        let south: Vec<f64> = z[first..first + stride].to_vec();
        let north: Vec<f64> = z[last..last + stride].to_vec();
        z[..stride].copy_from_slice(&south);
        z[(ny + 1) * stride..].copy_from_slice(&north);
        let south: Vec<f64> = b_ghost[first..first + stride].to_vec();
        let north: Vec<f64> = b_ghost[last..last + stride].to_vec();
        b_ghost[..stride].copy_from_slice(&south);
        b_ghost[(ny + 1) * stride..].copy_from_slice(&north);
        if let Some(m) = &metric {
            // In the bed-normal frame an outflow continues the bed's slope (the edge
            // cell's gradient), so that a flow on a slope cut by the edge leaves it; a
            // wall keeps the edge cell's bed. The potential is the bed.
            let ghost = |kind: BoundaryKind, edge: f64, slope: f64| match kind {
                BoundaryKind::Wall => edge,
                BoundaryKind::Outflow => edge + slope,
            };
            for j in 0..ny {
                let (c0, c1) = (j * nx, j * nx + nx - 1);
                let row = (j + 1) * stride;
                b_ghost[row] = ghost(spec.sides.west, bed[c0], -m.gx[c0] * dx);
                b_ghost[row + nx + 1] = ghost(spec.sides.east, bed[c1], m.gx[c1] * dx);
            }
            for i in 0..nx {
                let (c0, c1) = (i, (ny - 1) * nx + i);
                b_ghost[i + 1] = ghost(spec.sides.south, bed[c0], -m.gy[c0] * dy);
                b_ghost[(ny + 1) * stride + i + 1] =
                    ghost(spec.sides.north, bed[c1], m.gy[c1] * dy);
            }
            z.copy_from_slice(&b_ghost);
        }
        let geometry =
            RasterGeometry::of_extent(nx, ny, [spec.x_min, spec.x_max], [spec.y_min, spec.y_max]);
        Ok(Raster2d {
            geometry,
            spec,
            dx,
            dy,
            x,
            y,
            b: output_bed.unwrap_or(bed),
            b_ghost,
            z,
            g_n,
            theta,
            walls,
            metric,
        })
    }

    /// The raster placed on the map by `geometry` (the scenario's: a DEM's grid exactly
    /// as read, with its CRS); the cells stay those of the [`RasterSpec`]. Refuses a
    /// geometry of another number of cells.
    pub fn georeferenced(mut self, geometry: RasterGeometry) -> Result<Raster2d, String> {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        if (geometry.nx, geometry.ny) != (nx, ny) {
            return Err(format!(
                "a geometry of {} × {} cells for a raster of {nx} × {ny}",
                geometry.nx, geometry.ny
            ));
        }
        self.geometry = geometry;
        Ok(self)
    }

    /// The slope θ (radians) of the reference plane of the local frame; 0 in the frames
    /// without one (Cartesian, bed-normal: the terrain is all in the bed).
    pub fn plane_theta(&self) -> f64 {
        match self.spec.coordinates {
            Coordinates::Local => self.theta,
            Coordinates::Cartesian | Coordinates::BedNormal => 0.0,
        }
    }

    /// The raster without the centrifugal term in the basal normal stress of the
    /// bed-normal frame (`domain.curvature = false`; nothing changes in the others).
    pub fn without_friction_curvature(mut self) -> Raster2d {
        if let Some(m) = &mut self.metric {
            m.in_friction = false;
        }
        self
    }

    /// The bed's metric in the bed-normal frame (`None` in the other frames).
    #[inline(always)]
    pub fn metric(&self) -> Option<&BedMetric> {
        self.metric.as_ref()
    }

    pub fn spec(&self) -> &RasterSpec {
        &self.spec
    }
    pub fn nx(&self) -> usize {
        self.spec.nx
    }
    pub fn ny(&self) -> usize {
        self.spec.ny
    }
    pub fn dx(&self) -> f64 {
        self.dx
    }
    pub fn dy(&self) -> f64 {
        self.dy
    }
    /// Centre of column i.
    pub fn x(&self, i: usize) -> f64 {
        self.spec.x(i)
    }
    /// Centre of row j.
    pub fn y(&self, j: usize) -> f64 {
        self.spec.y(j)
    }
    pub fn sides(&self) -> Sides {
        self.spec.sides
    }
    pub fn coordinates(&self) -> Coordinates {
        self.spec.coordinates
    }
    /// Cell area Δx Δy.
    pub fn cell_area(&self) -> f64 {
        self.dx * self.dy
    }

    /// Index of cell (i, j) in the ghost-ring arrays (`b_ghost`, `z`); i and j may be
    /// −1 (as `usize` wrapping is avoided: pass i + 1, j + 1).
    #[inline(always)]
    pub fn ghost_index(&self, i_plus_1: usize, j_plus_1: usize) -> usize {
        j_plus_1 * (self.spec.nx + 2) + i_plus_1
    }

    /// The wall cells (row-major), or an empty slice when there is none.
    pub fn walls(&self) -> &[bool] {
        &self.walls
    }

    /// Whether cell `cell` (row-major) is a wall.
    #[inline(always)]
    pub fn is_wall(&self, cell: usize) -> bool {
        !self.walls.is_empty() && self.walls[cell]
    }

    /// `values` (one per cell) with NaN on the wall cells: borrowed as they are when
    /// the raster has no wall.
    pub fn mask_walls<'a>(&self, values: &'a [f64]) -> std::borrow::Cow<'a, [f64]> {
        if self.walls.is_empty() {
            return std::borrow::Cow::Borrowed(values);
        }
        let masked = values
            .iter()
            .zip(&self.walls)
            .map(|(&v, &w)| if w { f64::NAN } else { v })
            .collect();
        std::borrow::Cow::Owned(masked)
    }

    /// Number of bands ([`BAND_ROWS`] rows each, the last one shorter).
    pub fn bands(&self) -> usize {
        self.spec.ny.div_ceil(BAND_ROWS)
    }

    /// Rows of band `k`.
    pub fn band_rows(&self, k: usize) -> Range<usize> {
        let start = k * BAND_ROWS;
        start..(start + BAND_ROWS).min(self.spec.ny)
    }
}

impl Grid for Raster2d {
    fn cells(&self) -> usize {
        self.spec.nx * self.spec.ny
    }

    fn centre(&self, cell: usize) -> Point {
        Point {
            x: self.x[cell],
            y: self.y[cell],
        }
    }

    fn axis_names(&self) -> &'static [&'static str] {
        &["x", "y"]
    }

    fn axis(&self, axis: usize) -> &[f64] {
        match axis {
            0 => &self.x,
            1 => &self.y,
            _ => panic!("a raster has two axes"),
        }
    }

    fn bed(&self) -> &[f64] {
        &self.b
    }

    fn shape(&self) -> Option<(usize, usize)> {
        Some((self.spec.ny, self.spec.nx))
    }

    fn flow_cells(&self) -> usize {
        self.cells() - self.walls.iter().filter(|&&w| w).count()
    }

    fn has_outflow(&self) -> bool {
        let s = self.spec.sides;
        [s.west, s.east, s.south, s.north].contains(&BoundaryKind::Outflow)
    }

    /// Bilinear interpolation between the four centres around `p` (the edge cells'
    /// values outside them).
    fn locate(&self, p: Point) -> Stencil {
        let nx = self.spec.nx;
        let xs: Vec<f64> = (0..nx).map(|i| self.x(i)).collect();
        let ys: Vec<f64> = (0..self.spec.ny).map(|j| self.y(j)).collect();
        let (i, wx) = super::line::interpolate(&xs, self.dx, p.x);
        let (j, wy) = super::line::interpolate(&ys, self.dy, p.y);
        let mut pairs = [(0usize, 0.0f64); 4];
        let mut n = 0;
        for (dj, fy) in [(0, 1.0 - wy), (1, wy)] {
            for (di, fx) in [(0, 1.0 - wx), (1, wx)] {
                let w = fx * fy;
                if w != 0.0 {
                    pairs[n] = ((j + dj) * nx + i + di, w);
                    n += 1;
                }
            }
        }
        Stencil::new(&pairs[..n])
    }

    fn cfl_length(&self) -> f64 {
        self.dx.min(self.dy)
    }

    fn grid_spec(&self) -> GridSpec {
        GridSpec::Raster(self.geometry.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(nx: usize, ny: usize) -> RasterSpec {
        RasterSpec {
            nx,
            ny,
            x_min: 0.0,
            x_max: 2.0,
            y_min: -1.0,
            y_max: 1.0,
            sides: Sides::all(BoundaryKind::Wall),
            coordinates: Coordinates::Local,
            slope_deg: 30.0,
        }
    }

    #[test]
    fn cells_are_row_major_with_the_plane_in_the_potential() {
        let r = Raster2d::new(spec(4, 3), (0..12).map(|k| k as f64).collect()).unwrap();
        assert_eq!(r.cells(), 12);
        assert_eq!(r.centre(5), Point { x: 0.75, y: 0.0 });
        assert_eq!(r.shape(), Some((3, 4)));
        let tan = 30f64.to_radians().tan();
        let k = r.ghost_index(2, 2);
        assert_eq!(r.z[k], 5.0 - 0.75 * tan);
        // A wall mirrors the edge cell's potential.
        assert_eq!(r.z[r.ghost_index(0, 2)], r.z[r.ghost_index(1, 2)]);
        assert_eq!(r.z[r.ghost_index(2, 0)], r.z[r.ghost_index(2, 1)]);
    }

    #[test]
    fn bad_rasters_are_refused() {
        assert!(Raster2d::new(spec(0, 3), vec![]).is_err());
        assert!(Raster2d::new(spec(2, 2), vec![0.0; 3]).is_err());
        assert!(Raster2d::new(spec(2, 2), vec![0.0, 0.0, f64::NAN, 0.0]).is_err());
    }

    #[test]
    fn bilinear_stencil_weights_sum_to_one() {
        let r = Raster2d::new(spec(4, 4), vec![0.0; 16]).unwrap();
        let s = r.locate(Point { x: 0.6, y: 0.1 });
        assert_eq!(s.len(), 4);
        let total: f64 = s.pairs().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-14);
        assert_eq!(r.locate(Point { x: 0.25, y: -0.75 }), Stencil::one(0));
    }
}
