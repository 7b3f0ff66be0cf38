//! The grid floor: the cells a model lives on, below `state/`, `numerics/` and
//! `model/` (it imports nothing above it but physical constants).
//!
//! Generic code (the run loop, gauges, the output of `/grid`, the stop rules' places)
//! sees a grid only through [`Grid`]: how many cells, where a cell's centre is, the
//! coordinate axes written to `/grid`, the bed, which cells and weights interpolate a
//! point, and the length of the CFL condition. The loops over faces are the stages',
//! written for one concrete grid type each:
//!
//! - [`Line`] ([`mod@line`]): the uniform 1-D grid of the layered and dilatant models, with
//!   its potential z, ghost beds and boundary kinds;
//! - [`CurvedLine`] ([`curved`]): a line whose bed angle θ(x) enters the equations (the
//!   two-layer submarine model, Fernández-Nieto et al. 2008, §4), with the angle terms of each face.
//!
//! - [`Raster2d`] ([`raster`]): the uniform 2-D raster of the 2-D Savage–Hutter model,
//!   row-major cells grouped in bands of whole rows (the tiles of its stages), with the
//!   bed's metric ([`BedMetric`], [`bed_metric`]) in the bed-normal frame.
//!
//! What a grid is on the map (its extent, cell sizes and, on a raster, its CRS) is one
//! value, [`GridSpec`] ([`spec`]), which the output carries to `/grid` unchanged.

pub mod bed_metric;
pub mod curved;
pub mod line;
pub mod raster;
pub mod spec;

pub use bed_metric::BedMetric;

pub use curved::CurvedLine;
pub use line::{Line, LineSpec};
pub use raster::{Raster2d, RasterSpec, Sides};
pub use spec::{GridSpec, LineGeometry, RasterGeometry};

/// Frame in which the shallow model is written (Garres-Díaz et al. 2021, §4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Along and normal to a reference plane of slope θ; gravity g cos θ normal to it.
    Local,
    /// Horizontal x, vertical z; the slope lives inside b(x) and gravity is g.
    Cartesian,
    /// Terrain-following on a raster (`numerics::hydrostatic_2d`, docs/numerics.md): the
    /// thickness normal to the local bed, the velocity tangent to it, g cos θ in the
    /// pressure and the friction, on the DEM's horizontal grid ([`BedMetric`]).
    BedNormal,
}

/// What happens at an edge of the domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundaryKind {
    /// Reflecting wall: ghost discharge opposite, thickness mirrored (Escalante et al. 2023, Remark 6).
    Wall,
    /// Free outflow: ghost state copied (homogeneous Neumann).
    Outflow,
}

impl BoundaryKind {
    /// Sign of a ghost cell's normal discharge: −1 at a wall (reversed), 1 at an
    /// outflow (copied).
    #[inline(always)]
    pub fn discharge_sign(self) -> f64 {
        match self {
            BoundaryKind::Wall => -1.0,
            BoundaryKind::Outflow => 1.0,
        }
    }
}

/// A position in the domain (m): x along a line (y = 0), (x, y) on a plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
}

/// Cells and weights that interpolate a cell field at a point: v = Σ w_k v\[cell_k\]
/// (one cell with weight 1 at a centre or outside the centres, two on a line, up to
/// four on a raster).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stencil {
    cells: [usize; 4],
    weights: [f64; 4],
    len: usize,
}

impl Stencil {
    /// The value of `cell` alone.
    pub fn one(cell: usize) -> Stencil {
        Stencil {
            cells: [cell, 0, 0, 0],
            weights: [1.0, 0.0, 0.0, 0.0],
            len: 1,
        }
    }

    /// w₀ v\[c₀\] + w₁ v\[c₁\].
    pub fn two(a: (usize, f64), b: (usize, f64)) -> Stencil {
        Stencil {
            cells: [a.0, b.0, 0, 0],
            weights: [a.1, b.1, 0.0, 0.0],
            len: 2,
        }
    }

    /// Up to four (cell, weight) pairs (a bilinear stencil on a raster).
    pub fn new(pairs: &[(usize, f64)]) -> Stencil {
        assert!(!pairs.is_empty() && pairs.len() <= 4, "one to four cells");
        let mut s = Stencil {
            cells: [0; 4],
            weights: [0.0; 4],
            len: pairs.len(),
        };
        for (k, &(c, w)) in pairs.iter().enumerate() {
            (s.cells[k], s.weights[k]) = (c, w);
        }
        s
    }

    /// The (cell, weight) pairs, in order.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.cells[..self.len]
            .iter()
            .copied()
            .zip(self.weights[..self.len].iter().copied())
    }

    /// The first cell (the one a single-cell stencil reads).
    pub fn first(&self) -> usize {
        self.cells[0]
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Never true (a stencil has at least one cell); for clippy's `len_without_is_empty`.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// What generic code needs of a grid. Cells are numbered 0..cells() (physical cells;
/// the ghost cells of a grid are its stages' business).
pub trait Grid: Send + 'static {
    /// Number of physical cells.
    fn cells(&self) -> usize;
    /// Centre of physical cell `cell` (0-based), e.g. to name where a step failed.
    fn centre(&self, cell: usize) -> Point;
    /// Names of the coordinate axes, written to `/grid` as arrays with one value per
    /// cell: `["x"]` on a line (`["x", "y"]` on a raster).
    fn axis_names(&self) -> &'static [&'static str];
    /// Coordinate `axis` (index into [`Grid::axis_names`]) of every cell centre.
    fn axis(&self, axis: usize) -> &[f64];
    /// Bed elevation at the centres (`/grid/b`), one value per cell.
    fn bed(&self) -> &[f64];
    /// The cells and weights that interpolate a cell field at `p` (gauges).
    fn locate(&self, p: Point) -> Stencil;
    /// Length in the CFL condition Δt ≤ CFL · length / speed (Δx on a line).
    fn cfl_length(&self) -> f64;
    /// The grid's extent, cell sizes and CRS (`/grid` attributes).
    fn grid_spec(&self) -> GridSpec;
    /// (ny, nx) of a raster, whose per-cell arrays are row-major; `None` on a line.
    fn shape(&self) -> Option<(usize, usize)> {
        None
    }
    /// Whether material can leave through a boundary (an `outflow` end of a line): the
    /// run then reports the fraction of the initial mass that left.
    fn has_outflow(&self) -> bool {
        false
    }
    /// Number of cells material can occupy: [`Grid::cells`] but the walls (nodata
    /// cells of a DEM), the denominator of the wet fraction.
    fn flow_cells(&self) -> usize {
        self.cells()
    }
}
