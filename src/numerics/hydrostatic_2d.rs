//! Step 1 on a raster: the hydrostatic Savage–Hutter system in two horizontal
//! dimensions,
//!
//!   ∂_t h + ∂_x(hu) + ∂_y(hv) = 0,
//!   ∂_t(hu) + ∂_x(hu²) + ∂_y(huv) + g_n h ∂_x(h + z) = 0,
//!   ∂_t(hv) + ∂_x(huv) + ∂_y(hv²) + g_n h ∂_y(h + z) = 0,
//!
//! (Savage & Hutter 1989 in two dimensions; the frames of the line, z = b − x tan θ and
//! g_n = g cos θ in local coordinates over a plane inclined along x, z = b and g_n = g
//! in Cartesian coordinates), by unsplit finite volumes:
//!
//!   U_ij ← U_ij − Δt/Δx (𝓕_{i+1/2,j} − 𝓕_{i−1/2,j} + 𝓢ˣ_ij)
//!               − Δt/Δy (𝓖_{i,j+1/2} − 𝓖_{i,j−1/2} + 𝓢ʸ_ij).
//!
//! Every x-face and every y-face is the 1-D face of [`super::hydrostatic`] along its
//! normal ([`super::face`]: hydrostatic reconstruction over b, Coulomb-aware ΔC with the
//! normal components, HLL/PVM diffusion, the own-depth split of the pressure source,
//! the emerging-bed rule at wet/dry fronts), with the tangential discharge carried by
//! the mass flux ([`super::face::transverse_flux`]). The near-dry rule (the gravity
//! part of the source taken back for the mass that left) uses the cell's new depth,
//! and the draining-time limiter (Bollermann et al. 2013) scales every outgoing flux
//! of a cell that would empty, with the outflow summed over its four faces. On a
//! state that does not depend on y, every y-face carries exactly nothing and each row
//! is the 1-D step to the bit (`tests/terrain_2d.rs`).
//!
//! Friction zones ([`CellFriction::PerCell`]): the ΔC threshold of a face is the μ of
//! the cell that the face's normal drive pushes mass out of (d_n > 0: the lower-index
//! cell), whose friction holds that mass; where both cells have the same law this is
//! the uniform face to the bit. A ghost takes its edge cell's law, a wall side the
//! flow side's.
//!
//! Boundaries: the edge faces see a ghost cell built from the edge cell (a wall
//! mirrors h and reverses the normal discharge, an outflow copies the cell), over the
//! raster's ghost bed. Wall cells inside the raster (nodata cells of a DEM,
//! [`crate::grid::raster`]) are handled face by face in the same way: the wall side
//! of a face is the mirror of the flow side (h, b, z and the tangential velocity
//! copied, the normal velocity reversed), the face's mass flux and with it the
//! tangential flux are zero (so no mass crosses, to the bit), and a face between two
//! walls carries nothing. A wall cell then keeps h = 0 and no discharge. The sweep
//! is compiled twice, with and without this test, and a raster without wall cells
//! runs the code without it.
//!
//! Work follows the flow: only the stepped tiles of the state (`state::tiles`: tiles of
//! 16 rows × 32 columns with a live cell, and their neighbours across an edge with
//! one) are swept; every other cell is dry with dry neighbours, which a sweep would
//! leave unchanged to the bit. A tile is one task on the run's threads: it computes
//! the y-faces under and over each of its rows (one row of halo on each side) and the
//! x-faces along them (one column of halo on each side), and writes its cells of the
//! new state into the step's own buffers, which are copied into the state's stepped
//! tiles at the end. The faces on the edge between two tiles are computed by both,
//! with the same operations on the same data. Each cell is seen by its four faces
//! through one view computed once per sweep (velocities, √h, bed, potential, its
//! drives along x and y and its speed): a y-face reads the views of the rows under and
//! over it, an x-face those of its row. Memory: the new state (3 values per cell), the
//! draining factors (1), per tile its smallest new thickness and flags, and per thread
//! two rows of y-faces and two rows of cell views of a tile's width.
//!
//! The limiter in two passes. The unlimited pass writes the new state and, from the
//! same four faces, every cell's draining factor θ = min(1, h/(Δt outflow)) where it is
//! not 1 (θ is 1 outside a step). Only if some new thickness is negative, the limited
//! pass follows: a face's fluxes times its donor's θ differ from the unlimited ones
//! only where θ ≠ 1 (a flux times 1 is the flux), so it recomputes just the cells next
//! to a draining cell (the cell and its four neighbours), face by face, and keeps the
//! unlimited values elsewhere: the same bits as a full second pass, at the cost of the
//! fronts only. The unlimited pass records which tiles hold a draining cell, so the
//! limited pass visits only the tiles next to one. The smallest new thickness is
//! combined over tiles as the first minimum in cell order, whatever order the threads
//! finish in: the same bits on any thread count.
//!
//! The CFL step: with the per-cell signal speed s = max(|u|, |v|) + √(g_n h) and
//! Δt = CFL · min(Δx, Δy)/s, Δt (s_x/Δx + s_y/Δy) ≤ 2 CFL; the unsplit update keeps
//! h ≥ 0 for CFL ≤ ½ (the limiter and the run loop's retry catch the rest).

use super::bed_normal::{self, face_sources, FaceFlux, FaceSide};
use super::face::{
    disk_friction, drained_fraction, interface_with_friction,
    interface_with_zoned_transverse_drive, layer_momentum_flux, mass_flux, transverse_flux, Side,
};
use super::friction_2d::{CellFriction, FrictionStep2d};
use super::muscl::Limiter;
use super::muscl_2d::{self, AxisSlopes, Mean, Reconstruction};
use super::workers::Disjoint;
use super::workers::Workers;
use super::{Stage, StageError, StepClock};
use crate::grid::raster::BAND_ROWS;
use crate::grid::{BedMetric, BoundaryKind, Raster2d};
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{velocity, H_DRY};
use crate::physics::GRAVITY;
use crate::state::tiles::{TileRunner, Tiles, TILE_COLS};
use crate::state::State2d;
use std::ops::Range;
use std::sync::Mutex;

/// A cell as its four faces see it, computed once per sweep: thickness, the
/// velocities u = hu/h and v = hv/h, √h, bed and potential, the drives along x
/// (u/Δt − g_n ∂_x(h + z), tangential to the y-faces) and along y (v/Δt − g_n ∂_y(h + z),
/// tangential to the x-faces) and the speed |(u, v)|. A view of a ghost row (under or
/// over the raster) is the edge cell with the ghost's bed and potential and the
/// boundary's sign on v; only its y-side is read.
///
/// (wx, wy) are the momenta per unit mass the faces carry: (u, v) in the flat frames,
/// the covariant components G (u, v) in the bed-normal frame ([`FaceSide`]).
#[derive(Debug, Clone, Copy, Default)]
struct CellView {
    h: f64,
    u: f64,
    v: f64,
    wx: f64,
    wy: f64,
    sqrt_h: f64,
    b: f64,
    z: f64,
    drive_x: f64,
    drive_y: f64,
    speed: f64,
    kappa: f64,
}

impl CellView {
    /// The cell as an x-face sees it (normal velocity u).
    #[inline(always)]
    fn x_side(&self) -> FaceSide {
        FaceSide {
            side: self.side(self.u, self.wx),
            t: self.wy,
            drive: self.drive_y,
            speed: self.speed,
            kappa: self.kappa,
        }
    }

    /// The cell as a y-face sees it (normal velocity v).
    #[inline(always)]
    fn y_side(&self) -> FaceSide {
        FaceSide {
            side: self.side(self.v, self.wy),
            t: self.wx,
            drive: self.drive_x,
            speed: self.speed,
            kappa: self.kappa,
        }
    }

    /// The monolayer side with normal velocity `normal` and normal momentum per unit
    /// mass `carried` ([`Side::monolayer`] where the two are equal).
    #[inline(always)]
    fn side(&self, normal: f64, carried: f64) -> Side {
        Side {
            h: self.h,
            u: normal,
            b: self.b,
            z: self.z,
            shear: 0.0,
            u_base: carried,
            sqrt_h: self.sqrt_h,
        }
    }
}

/// The speed |(u, v)| of a cell with velocity components `u` along x and `v` along y
/// (the same argument order wherever it is computed, so that both faces of a cell
/// see the same bits).
#[inline(always)]
fn cell_speed(u: f64, v: f64) -> f64 {
    u.hypot(v)
}

/// One thread's scratch for the tile it sweeps: the y-faces under and over the
/// current row of the tile and the views of the rows under and over them ([`TILE_COLS`]
/// each).
#[derive(Debug, Clone)]
struct TileScratch {
    below: Vec<FaceFlux>,
    above: Vec<FaceFlux>,
    /// The views of the ghost-inclusive rows under and over the y-faces `above`
    /// (each row's computed once per sweep).
    lower: Vec<CellView>,
    upper: Vec<CellView>,
}

/// The 2-D hydrostatic step, generic over the basal friction law (used in ΔC).
#[derive(Debug)]
pub struct HydrostaticStep2d<L: BasalFriction> {
    friction: CellFriction<L>,
    workers: Workers,
    h_new: Vec<f64>,
    hu_new: Vec<f64>,
    hv_new: Vec<f64>,
    /// Draining factors per cell, from the unlimited pass's faces: 1 outside a step,
    /// and within one wherever the unlimited pass did not write a θ ≠ 1.
    drain: Vec<f64>,
    /// Per tile: the smallest new thickness and its cell (first in cell order), and
    /// whether it has a draining cell (false outside a step).
    tile_worst: Vec<(f64, usize)>,
    tile_drains: Vec<bool>,
    /// The stepped tiles that the limited pass visits (a draining cell in them or in a
    /// tile next to them), allocated once.
    near_drains: Vec<u32>,
    /// One scratch per thread (each locked by its own thread only).
    scratch: Vec<Mutex<TileScratch>>,
    /// Order 2: the slopes of the second-order reconstruction ([`muscl_2d`]).
    recon: Option<Reconstruction>,
    /// The friction step applied to every cell as the new state is written
    /// ([`Self::then_friction`]); `None`: the caller's.
    friction_step: Option<FrictionStep2d<L>>,
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// The step on `raster` with one friction law `law`, its tiles run by `workers`.
    pub fn new(law: L, raster: &Raster2d, workers: Workers) -> Self {
        Self::with_friction(CellFriction::Uniform(law), raster, workers)
    }

    /// The step on `raster` with the friction of its cells (friction zones), its tiles
    /// run by `workers`.
    pub fn with_friction(friction: CellFriction<L>, raster: &Raster2d, workers: Workers) -> Self {
        let cells = raster.nx() * raster.ny();
        let tiles = raster.nx().div_ceil(TILE_COLS) * raster.ny().div_ceil(BAND_ROWS);
        let scratch = TileScratch {
            below: vec![FaceFlux::default(); TILE_COLS],
            above: vec![FaceFlux::default(); TILE_COLS],
            lower: vec![CellView::default(); TILE_COLS],
            upper: vec![CellView::default(); TILE_COLS],
        };
        let scratch = (0..workers.threads())
            .map(|_| Mutex::new(scratch.clone()))
            .collect();
        HydrostaticStep2d {
            friction,
            workers,
            h_new: vec![0.0; cells],
            hu_new: vec![0.0; cells],
            hv_new: vec![0.0; cells],
            drain: vec![1.0; cells],
            tile_worst: vec![(f64::INFINITY, 0); tiles],
            tile_drains: vec![false; tiles],
            near_drains: Vec::with_capacity(tiles),
            scratch,
            recon: None,
            friction_step: None,
        }
    }

    /// The step followed by the friction step `friction` in its last pass (the order-1
    /// pipeline's hyperbolic → friction as one stage, named "hyperbolic+friction"):
    /// each cell of the new state gets the friction update of
    /// [`FrictionStep2d::cell`] as it is written, and each stepped tile is classified
    /// in the same task (`state::tiles`, `write_classified`), with the same operations
    /// and bits as the two stages one after the other and one pass instead of three.
    pub fn then_friction(mut self, friction: FrictionStep2d<L>) -> Self {
        self.friction_step = Some(friction);
        self
    }

    /// The step with the second-order reconstruction of [`muscl_2d`] and `limiter`
    /// (the time integrator is the caller's: [`super::ssp_rk2::Heun2d`]).
    pub fn second_order(
        friction: CellFriction<L>,
        raster: &Raster2d,
        workers: Workers,
        limiter: Limiter,
    ) -> Self {
        let mut step = Self::with_friction(friction, raster, workers);
        step.recon = Some(Reconstruction::new(limiter, raster.nx() * raster.ny()));
        step
    }

    /// Bytes of scratch per cell that the step holds (new state, draining factors,
    /// per-tile results, the threads' face and view rows, at order 2 the slopes), for the memory budget of
    /// `docs/performance.md`.
    pub fn bytes_per_cell(&self) -> f64 {
        let cells = self.h_new.len() as f64;
        let per_tile = std::mem::size_of::<(f64, usize)>() + std::mem::size_of::<bool>();
        let rows = self.scratch.len()
            * TILE_COLS
            * (2 * std::mem::size_of::<FaceFlux>() + 2 * std::mem::size_of::<CellView>());
        // Order 2: the slopes along x and y of every cell.
        let slopes = match &self.recon {
            Some(_) => 2.0 * std::mem::size_of::<Option<AxisSlopes>>() as f64,
            None => 0.0,
        };
        (4.0 * 8.0 * cells + (per_tile * self.tile_worst.len() + rows) as f64) / cells + slopes
    }
}

/// The read-only data of one step; `BN`: the raster is in the bed-normal frame (the
/// flat frames' code is compiled without its branches); `O2`: order 2 (the order-1
/// code is compiled without the reconstruction's, so that it keeps its speed).
struct Ctx<'a, L: BasalFriction, const BN: bool, const O2: bool> {
    friction: &'a CellFriction<L>,
    raster: &'a Raster2d,
    metric: Option<&'a BedMetric>,
    h: &'a [f64],
    hu: &'a [f64],
    hv: &'a [f64],
    nx: usize,
    ny: usize,
    dt: f64,
    /// Order 2: the stage's slopes.
    recon: Option<&'a Reconstruction>,
}

/// A ghost-inclusive cell along one axis as the reconstruction reads it: its mean, the
/// cell it is (a ghost's: the edge cell), the boundary's sign on its normal velocity,
/// its bed and potential.
#[derive(Debug, Clone, Copy)]
struct MeanAt {
    mean: Mean,
    cell: usize,
    sign: f64,
    b: f64,
    z: f64,
}

/// A face: between ghost-inclusive columns c and c + 1 of row j (`X(c, j)`), or rows
/// r and r + 1 of column i (`Y(i, r)`).
#[derive(Debug, Clone, Copy)]
enum FacePos {
    X(usize, usize),
    Y(usize, usize),
}

/// The centres of an order-2 face's two cells, (h, b, z) each, for ΔC's drive and the
/// bed-normal face's geometry.
#[derive(Debug, Clone, Copy)]
struct Centres {
    l: (f64, f64, f64),
    r: (f64, f64, f64),
}

impl<'a, L: BasalFriction, const BN: bool, const O2: bool> Ctx<'a, L, BN, O2> {
    /// The bed's metric in the bed-normal frame, `None` (known at compile time) in
    /// the others.
    #[inline(always)]
    fn bed(&self) -> Option<&'a BedMetric> {
        if BN {
            self.metric
        } else {
            None
        }
    }

    /// The context of one pass over `state` on `raster` with step `dt`.
    fn new(
        friction: &'a CellFriction<L>,
        raster: &'a Raster2d,
        state: &'a State2d,
        dt: f64,
    ) -> Self {
        Ctx {
            friction,
            raster,
            metric: raster.metric(),
            h: &state.h,
            hu: &state.hu,
            hv: &state.hv,
            nx: raster.nx(),
            ny: raster.ny(),
            dt,
            recon: None,
        }
    }

    /// The context with the slopes `recon` (order 2).
    fn with_recon(mut self, recon: Option<&'a Reconstruction>) -> Self {
        self.recon = recon;
        self
    }

    /// The friction coefficient of ΔC at a face between the cells seen as `l` and `r`,
    /// at the face's Roe speed `speed` and mean depth `h`: the one place where the
    /// step reads the friction law ([`BasalFriction::face_mu`], from the cells' own
    /// speeds |(u, v)| and depths, so that a run invariant along one axis is the
    /// line's bit for bit). With friction zones, the law of the face's cell (`cells`,
    /// lower and higher index) that the normal drive `drive` pushes mass out of: the
    /// cell whose friction holds that mass.
    #[inline(always)]
    fn face_mu(
        &self,
        l: &FaceSide,
        r: &FaceSide,
        speed: f64,
        h: f64,
        drive: f64,
        cells: impl Fn() -> (usize, usize),
    ) -> f64 {
        let (cell_l, cell_r) = ((l.speed, l.side.h), (r.speed, r.side.h));
        let law = self.face_law(drive, cells);
        law.face_mu(cell_l, cell_r, speed, h, self.raster.g_n)
    }

    /// The friction law of a face between `cells` (lower and higher index): the one
    /// law, or with friction zones that of the cell the normal drive `drive` pushes
    /// mass out of (the cell whose friction holds that mass).
    #[inline(always)]
    fn face_law(&self, drive: f64, cells: impl Fn() -> (usize, usize)) -> L {
        match self.friction {
            CellFriction::Uniform(law) => *law,
            CellFriction::PerCell(laws) => {
                let (lo, hi) = cells();
                laws[if drive > 0.0 { lo } else { hi }]
            }
        }
    }

    /// The cells (row-major) of the x-face between ghost-inclusive columns `c` and
    /// `c + 1` of row `j` (a ghost takes its edge cell).
    #[inline(always)]
    fn x_cells(&self, c: usize, j: usize) -> (usize, usize) {
        let cell = |c: usize| j * self.nx + c.clamp(1, self.nx) - 1;
        (cell(c), cell(c + 1))
    }

    /// The cells of the y-face between ghost-inclusive rows `r` and `r + 1` of
    /// column i.
    #[inline(always)]
    fn y_cells(&self, i: usize, r: usize) -> (usize, usize) {
        let cell = |r: usize| (r.clamp(1, self.ny) - 1) * self.nx + i;
        (cell(r), cell(r + 1))
    }

    /// The free surface h + z of cell (i, j) seen from a cell whose surface is `eta`:
    /// a dry cell whose bed stands above it counts at `eta` (an emerging bed exerts
    /// no drive, as in the hydrostatic reconstruction).
    #[inline(always)]
    fn surface_seen(&self, i: usize, j: usize, eta: f64) -> f64 {
        let (h, z) = (
            self.h[j * self.nx + i],
            self.raster.z[self.raster.ghost_index(i + 1, j + 1)],
        );
        if h > H_DRY {
            h + z
        } else {
            z.min(eta)
        }
    }

    /// The drive u_t/Δt − g_n ∂_t(h + z) along an axis of cell (i, j) with the
    /// tangential velocity `t`: `along_x` for ∂_x (central differences over the
    /// neighbours, one-sided at the raster's edge and beside a wall cell; 0 on a
    /// single column or row).
    #[inline(always)]
    fn tangential_drive(&self, i: usize, j: usize, t: f64, along_x: bool) -> f64 {
        let (lo, hi, d) = self.neighbours(i, j, along_x);
        if let Some(m) = self.bed() {
            return self.covariant_drive(m, (i, j), t, along_x, (lo, hi, d));
        }
        if lo == hi {
            return t / self.dt;
        }
        let eta = self.h[j * self.nx + i] + self.raster.z[self.raster.ghost_index(i + 1, j + 1)];
        let (e_lo, e_hi) = if along_x {
            (self.surface_seen(lo, j, eta), self.surface_seen(hi, j, eta))
        } else {
            (self.surface_seen(i, lo, eta), self.surface_seen(i, hi, eta))
        };
        t / self.dt - self.raster.g_n * (e_hi - e_lo) / ((hi - lo) as f64 * d)
    }

    /// The neighbours (lo, hi) of cell (i, j) along an axis for a centred difference,
    /// and the cell width along it: one-sided at the raster's edge and beside a wall
    /// cell (nodata), lo = hi on a single column or row.
    #[inline(always)]
    fn neighbours(&self, i: usize, j: usize, along_x: bool) -> (usize, usize, f64) {
        let (k, n, d) = if along_x {
            (i, self.nx, self.raster.dx())
        } else {
            (j, self.ny, self.raster.dy())
        };
        let (mut lo, mut hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let wall = |m: usize| {
            let c = if along_x {
                j * self.nx + m
            } else {
                m * self.nx + i
            };
            self.raster.is_wall(c)
        };
        if wall(lo) {
            lo = k;
        }
        if wall(hi) {
            hi = k;
        }
        (lo, hi, d)
    }

    /// The tangential drive of the bed-normal frame: the covariant acceleration
    /// t/Δt − g (c² ∂H + ∂b) along an axis of cell (i, j) with the covariant velocity
    /// component `t` (the face's form, [`Self::bed_normal_face`]), H the thickness
    /// per horizontal area; ∂H by the differences of [`Self::neighbours`] (a dry
    /// neighbour has H = 0: the bed is smooth at the cell's scale, no step to emerge).
    #[inline(always)]
    fn covariant_drive(
        &self,
        m: &BedMetric,
        (i, j): (usize, usize),
        t: f64,
        along_x: bool,
        (lo, hi, d): (usize, usize, f64),
    ) -> f64 {
        let cell = j * self.nx + i;
        let slope = if along_x { m.gx[cell] } else { m.gy[cell] };
        let dh = if lo == hi {
            0.0
        } else if along_x {
            (self.h[j * self.nx + hi] - self.h[j * self.nx + lo]) / ((hi - lo) as f64 * d)
        } else {
            (self.h[hi * self.nx + i] - self.h[lo * self.nx + i]) / ((hi - lo) as f64 * d)
        };
        let c = m.cos[cell];
        t / self.dt - GRAVITY * (c * c * dh + slope)
    }

    /// Ghost-inclusive column `c` of row j as the reconstruction along x reads it (a
    /// ghost: the edge cell with the boundary's sign on u, over the ghost bed).
    #[inline(always)]
    fn x_mean(&self, c: usize, j: usize) -> MeanAt {
        let nx = self.nx;
        let sides = self.raster.sides();
        let (cell, sign) = if c == 0 {
            (j * nx, sides.west.discharge_sign())
        } else if c == nx + 1 {
            (j * nx + nx - 1, sides.east.discharge_sign())
        } else {
            (j * nx + c - 1, 1.0)
        };
        let h = self.h[cell];
        let (u, v) = (velocity(h, self.hu[cell]), velocity(h, self.hv[cell]));
        self.mean_at(cell, sign, self.raster.ghost_index(c, j + 1), (sign * u, v))
    }

    /// Column i, ghost-inclusive row `r`, as the reconstruction along y reads it.
    #[inline(always)]
    fn y_mean(&self, i: usize, r: usize) -> MeanAt {
        let (nx, ny) = (self.nx, self.ny);
        let sides = self.raster.sides();
        let (cell, sign) = if r == 0 {
            (i, sides.south.discharge_sign())
        } else if r == ny + 1 {
            ((ny - 1) * nx + i, sides.north.discharge_sign())
        } else {
            ((r - 1) * nx + i, 1.0)
        };
        let h = self.h[cell];
        let (u, v) = (velocity(h, self.hu[cell]), velocity(h, self.hv[cell]));
        self.mean_at(cell, sign, self.raster.ghost_index(i + 1, r), (sign * v, u))
    }

    /// The [`MeanAt`] of `cell` with velocities (normal, tangential) `(n, t)` over the
    /// bed at ghost-ring index `g`.
    #[inline(always)]
    fn mean_at(&self, cell: usize, sign: f64, g: usize, (n, t): (f64, f64)) -> MeanAt {
        let h = self.h[cell];
        let b = self.raster.b_ghost[g];
        MeanAt {
            mean: Mean {
                h,
                n,
                t,
                eta: h + b,
            },
            cell,
            sign,
            b,
            z: self.raster.z[g],
        }
    }

    /// The slopes along x of ghost-inclusive column `c` of row j (`None`: first
    /// order). A dry cell is first order without a look at the stored slopes (those of
    /// cells outside the stepped tiles are stale); a wall's ghost mirrors its edge
    /// cell's, an outflow's is first order.
    #[inline(always)]
    fn x_slopes(&self, c: usize, j: usize) -> Option<AxisSlopes> {
        let rec = self.recon?;
        let sides = self.raster.sides();
        if c == 0 {
            return (sides.west == BoundaryKind::Wall)
                .then(|| self.x_slopes(1, j).map(AxisSlopes::mirrored))
                .flatten();
        }
        if c == self.nx + 1 {
            return (sides.east == BoundaryKind::Wall)
                .then(|| self.x_slopes(self.nx, j).map(AxisSlopes::mirrored))
                .flatten();
        }
        let cell = j * self.nx + c - 1;
        if self.h[cell] > H_DRY {
            rec.x[cell]
        } else {
            None
        }
    }

    /// The slopes along y of column i, ghost-inclusive row `r` ([`Self::x_slopes`]).
    #[inline(always)]
    fn y_slopes(&self, i: usize, r: usize) -> Option<AxisSlopes> {
        let rec = self.recon?;
        let sides = self.raster.sides();
        if r == 0 {
            return (sides.south == BoundaryKind::Wall)
                .then(|| self.y_slopes(i, 1).map(AxisSlopes::mirrored))
                .flatten();
        }
        if r == self.ny + 1 {
            return (sides.north == BoundaryKind::Wall)
                .then(|| self.y_slopes(i, self.ny).map(AxisSlopes::mirrored))
                .flatten();
        }
        let cell = (r - 1) * self.nx + i;
        if self.h[cell] > H_DRY {
            rec.y[cell]
        } else {
            None
        }
    }

    /// The slopes along x and y of interior cell (i, j) ([`muscl_2d`]): none where the
    /// cell is dry or slower than its static friction's impulse per step,
    /// speed ≤ Δt g_n μ_s (g_n = g cos θ and the normal thickness in the bed-normal
    /// frame), and none along an axis with a dry neighbour.
    fn cell_slopes(&self, limiter: Limiter, i: usize, j: usize) -> [Option<AxisSlopes>; 2] {
        let cell = j * self.nx + i;
        let h = self.h[cell];
        if h <= H_DRY || h.is_nan() {
            return [None, None];
        }
        let (u, v) = (velocity(h, self.hu[cell]), velocity(h, self.hv[cell]));
        let (speed, g_n, h_n) = match self.metric {
            Some(m) => (m.speed(cell, u, v), GRAVITY * m.cos[cell], m.cos[cell] * h),
            None => (cell_speed(u, v), self.raster.g_n, h),
        };
        let law = self.friction.at(cell);
        if speed <= self.dt * g_n * law.mu(0.0, h_n, g_n * h_n) {
            return [None, None];
        }
        let along_x = |c: usize| self.x_mean(c, j).mean;
        let along_y = |r: usize| self.y_mean(i, r).mean;
        [
            muscl_2d::axis_slopes(limiter, along_x(i), along_x(i + 1), along_x(i + 2)),
            muscl_2d::axis_slopes(limiter, along_y(j), along_y(j + 1), along_y(j + 2)),
        ]
    }

    /// The side of the edge `e` of the cell read as `at`, seen by a face along x
    /// (`along_x`) or y, with the tangential drive (and in the bed-normal frame the
    /// centrifugal term) of the cell's own side `base`.
    #[inline(always)]
    fn edge_side(&self, at: &MeanAt, e: Mean, base: &FaceSide, along_x: bool) -> FaceSide {
        let (n, t) = if e.h > H_DRY { (e.n, e.t) } else { (0.0, 0.0) };
        let b = e.eta - e.h;
        let sqrt_h = e.h.sqrt();
        if let Some(m) = self.bed() {
            // The covariant momenta of the edge's horizontal velocity in the cell's
            // metric, the ghost's sign on the normal ones (as `covariant_side`).
            let unsigned = at.sign * n;
            let (ue, ve) = if along_x {
                (unsigned, t)
            } else {
                (t, unsigned)
            };
            let (wx, wy) = m.lower(at.cell, ue, ve);
            let (carried, tc) = if along_x { (wx, wy) } else { (wy, wx) };
            return FaceSide {
                side: Side {
                    h: e.h,
                    u: n,
                    b,
                    z: b,
                    shear: 0.0,
                    u_base: at.sign * carried,
                    sqrt_h,
                },
                t: tc,
                drive: base.drive,
                speed: m.speed(at.cell, ue, ve),
                kappa: base.kappa,
            };
        }
        FaceSide {
            side: Side {
                h: e.h,
                u: n,
                b,
                z: b + (at.z - at.b),
                shear: 0.0,
                u_base: n,
                sqrt_h,
            },
            t,
            drive: base.drive,
            speed: if along_x {
                cell_speed(n, t)
            } else {
                cell_speed(t, n)
            },
            kappa: 0.0,
        }
    }

    /// Order 2: the edge sides of the face at `pos` between the cells seen as `l` and
    /// `r`, and the cells' centres, where both cells are reconstructed along the face's
    /// normal; `None` (the means `l`, `r` as they are) otherwise.
    #[inline(always)]
    fn edge_sides(
        &self,
        pos: FacePos,
        l: &FaceSide,
        r: &FaceSide,
    ) -> Option<(FaceSide, FaceSide, Centres)> {
        let (ml, mr, sl, sr, along_x) = match pos {
            FacePos::X(c, j) => {
                let (sl, sr) = (self.x_slopes(c, j)?, self.x_slopes(c + 1, j)?);
                (self.x_mean(c, j), self.x_mean(c + 1, j), sl, sr, true)
            }
            FacePos::Y(i, r) => {
                let (sl, sr) = (self.y_slopes(i, r)?, self.y_slopes(i, r + 1)?);
                (self.y_mean(i, r), self.y_mean(i, r + 1), sl, sr, false)
            }
        };
        let (le, re) = (
            muscl_2d::edge(ml.mean, sl, true),
            muscl_2d::edge(mr.mean, sr, false),
        );
        Some((
            self.edge_side(&ml, le, l, along_x),
            self.edge_side(&mr, re, r, along_x),
            Centres {
                l: (ml.mean.h, ml.b, ml.z),
                r: (mr.mean.h, mr.b, mr.z),
            },
        ))
    }

    /// Order 2: the interior pressure forces of cell (i, j) along x and y and their
    /// gravity parts, [sˣ, bˣ, sʸ, bʸ] ([`muscl_2d::interior_force`]); zero along an
    /// axis where the cell or both its neighbours on it are first order (an edge
    /// facing a first-order neighbour is the mean: mixed faces). And whether the cell
    /// is reconstructed along both axes (then the near-dry rule is off: [`update_cell`]).
    #[inline(always)]
    fn interior(&self, i: usize, j: usize) -> ([f64; 4], bool) {
        let cell = j * self.nx + i;
        let c2 = self.bed().map(|m| m.cos[cell] * m.cos[cell]);
        let force = |own: Option<AxisSlopes>, lo: bool, hi: bool, mean: Mean| {
            let Some(s) = own else {
                return (0.0, 0.0);
            };
            if !(lo || hi) {
                return (0.0, 0.0);
            }
            let lower = if lo {
                muscl_2d::edge(mean, s, false)
            } else {
                mean
            };
            let upper = if hi {
                muscl_2d::edge(mean, s, true)
            } else {
                mean
            };
            muscl_2d::interior_force(self.raster.g_n, c2, lower, upper)
        };
        let (own_x, own_y) = (self.x_slopes(i + 1, j), self.y_slopes(i, j + 1));
        let smooth = own_x.is_some() && own_y.is_some();
        let (sx, bx) = force(
            own_x,
            self.x_slopes(i, j).is_some(),
            self.x_slopes(i + 2, j).is_some(),
            self.x_mean(i + 1, j).mean,
        );
        let (sy, by) = force(
            own_y,
            self.y_slopes(i, j).is_some(),
            self.y_slopes(i, j + 2).is_some(),
            self.y_mean(i, j + 1).mean,
        );
        ([sx, bx, sy, by], smooth)
    }

    /// A face that is no wall face: at order 2 on the edge sides where both cells are
    /// reconstructed ([`Self::edge_sides`]), else on the means.
    #[inline(always)]
    fn open_face<C: Fn() -> (usize, usize) + Copy>(
        &self,
        l: &FaceSide,
        r: &FaceSide,
        d: (f64, bool),
        cells: C,
        pos: FacePos,
    ) -> FaceFlux {
        if O2 {
            if let Some((le, re, centres)) = self.edge_sides(pos, l, r) {
                return self.face_flux(&le, &re, d, cells, Some(centres));
            }
        }
        self.face_flux(l, r, d, cells, None)
    }

    /// The view of interior cell (i, j): the same values as [`Self::x_side`] and
    /// [`Self::y_side`] give for it, except an empty cell's drives (left at 0, which
    /// give its faces the same bits).
    #[inline(always)]
    fn view(&self, i: usize, j: usize) -> CellView {
        let cell = j * self.nx + i;
        let g = self.raster.ghost_index(i + 1, j + 1);
        let h = self.h[cell];
        let (u, v) = (velocity(h, self.hu[cell]), velocity(h, self.hv[cell]));
        let mut view = CellView {
            h,
            u,
            v,
            wx: u,
            wy: v,
            sqrt_h: h.max(0.0).sqrt(),
            b: self.raster.b_ghost[g],
            z: self.raster.z[g],
            drive_x: 0.0,
            drive_y: 0.0,
            speed: 0.0,
            kappa: 0.0,
        };
        // An empty cell (h = +0) has u = v = 0 and weighs nothing (√h = 0) in the
        // faces' mean drive, which equals the one with its drive (every face sees
        // the same bits): its view is its bed.
        if h.to_bits() == 0 {
            return view;
        }
        if let Some(m) = self.bed() {
            // A dry cell has u = v = 0: its momenta, speed and centrifugal term are 0
            // (the metric's products would give ±0, which no face tells apart).
            if h > H_DRY {
                (view.wx, view.wy) = m.lower(cell, u, v);
                view.speed = m.speed(cell, u, v);
                view.kappa = m.normal_curvature(cell, u, v);
            }
        } else {
            view.speed = cell_speed(u, v);
        }
        view.drive_x = self.tangential_drive(i, j, view.wx, true);
        view.drive_y = self.tangential_drive(i, j, view.wy, false);
        view
    }

    /// The views of ghost-inclusive row `r` (0 and ny + 1 are ghosts: their y-sides
    /// are those of [`Self::y_side`]) from column `c0` on.
    fn views(&self, r: usize, c0: usize, row: &mut [CellView]) {
        if r >= 1 && r <= self.ny {
            for (k, view) in row.iter_mut().enumerate() {
                *view = self.view(c0 + k, r - 1);
            }
        } else {
            for (k, view) in row.iter_mut().enumerate() {
                let y = self.y_side(c0 + k, r);
                *view = CellView {
                    h: y.side.h,
                    u: y.t,
                    v: y.side.u,
                    wx: y.t,
                    wy: y.side.u_base,
                    sqrt_h: y.side.sqrt_h,
                    b: y.side.b,
                    z: y.side.z,
                    drive_x: y.drive,
                    drive_y: 0.0,
                    speed: y.speed,
                    kappa: y.kappa,
                };
            }
        }
    }

    /// The side of ghost-inclusive column `c` (0 and nx + 1 are ghosts) of row `j`
    /// seen by an x-face, its tangential velocity v and its drive along y.
    #[inline(always)]
    fn x_side(&self, c: usize, j: usize) -> FaceSide {
        let sides = self.raster.sides();
        let (cell, sign) = if c == 0 {
            (j * self.nx, sides.west.discharge_sign())
        } else if c == self.nx + 1 {
            (j * self.nx + self.nx - 1, sides.east.discharge_sign())
        } else {
            (j * self.nx + c - 1, 1.0)
        };
        let g = self.raster.ghost_index(c, j + 1);
        if let Some(m) = self.bed() {
            return self.covariant_side(m, cell, sign, g, true);
        }
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hu[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        let v = velocity(h, self.hv[cell]);
        FaceSide {
            side,
            t: v,
            drive: self.tangential_drive(cell % self.nx, j, v, false),
            speed: cell_speed(side.u, v),
            kappa: 0.0,
        }
    }

    /// [`Self::x_side`] (`x_face`) or [`Self::y_side`] of `cell` in the bed-normal frame,
    /// with the boundary's `sign` on the normal velocity and its momentum and the bed
    /// at ghost-ring index `g`.
    #[inline(always)]
    fn covariant_side(
        &self,
        m: &BedMetric,
        cell: usize,
        sign: f64,
        g: usize,
        x_face: bool,
    ) -> FaceSide {
        let h = self.h[cell];
        let (u, v) = (velocity(h, self.hu[cell]), velocity(h, self.hv[cell]));
        let (wx, wy) = m.lower(cell, u, v);
        let (normal, carried, t) = if x_face { (u, wx, wy) } else { (v, wy, wx) };
        let b = self.raster.b_ghost[g];
        let (i, j) = (cell % self.nx, cell / self.nx);
        FaceSide {
            side: Side {
                h,
                u: sign * normal,
                b,
                z: b,
                shear: 0.0,
                u_base: sign * carried,
                sqrt_h: h.max(0.0).sqrt(),
            },
            t,
            drive: self.tangential_drive(i, j, t, !x_face),
            speed: m.speed(cell, u, v),
            kappa: m.normal_curvature(cell, u, v),
        }
    }

    /// The side of column i, ghost-inclusive row `r` (0 and ny + 1 are ghosts), seen
    /// by a y-face, its tangential velocity u and its drive along x.
    #[inline(always)]
    fn y_side(&self, i: usize, r: usize) -> FaceSide {
        let sides = self.raster.sides();
        let (cell, sign) = if r == 0 {
            (i, sides.south.discharge_sign())
        } else if r == self.ny + 1 {
            ((self.ny - 1) * self.nx + i, sides.north.discharge_sign())
        } else {
            ((r - 1) * self.nx + i, 1.0)
        };
        let g = self.raster.ghost_index(i + 1, r);
        if let Some(m) = self.bed() {
            return self.covariant_side(m, cell, sign, g, false);
        }
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hv[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        let u = velocity(h, self.hu[cell]);
        FaceSide {
            side,
            t: u,
            drive: self.tangential_drive(i, cell / self.nx, u, true),
            speed: cell_speed(u, side.u),
            kappa: 0.0,
        }
    }

    /// Whether ghost-inclusive column `c` of row `j` is a wall (a ghost takes the edge
    /// cell's kind).
    #[inline(always)]
    fn x_wall(&self, c: usize, j: usize) -> bool {
        let i = c.clamp(1, self.nx) - 1;
        self.raster.is_wall(j * self.nx + i)
    }

    /// Whether column i of ghost-inclusive row `r` is a wall.
    #[inline(always)]
    fn y_wall(&self, i: usize, r: usize) -> bool {
        let j = r.clamp(1, self.ny) - 1;
        self.raster.is_wall(j * self.nx + i)
    }

    /// The fluxes of one face with sides `l`, `r` along its normal (velocities normal
    /// to the face); zero where nothing crosses. The 1-D monolayer face
    /// ([`super::face::monolayer_fluxes`]) with the disk threshold of ΔC, plus the
    /// tangential flux. `d` is the cell width across the face (an x-face where
    /// `along_x`), `cells` its cells.
    #[inline(always)]
    fn face_flux<C: Fn() -> (usize, usize) + Copy>(
        &self,
        l: &FaceSide,
        r: &FaceSide,
        (d, along_x): (f64, bool),
        cells: C,
        centres: Option<Centres>,
    ) -> FaceFlux {
        // Between two dry cells the kernel carries nothing (it returns at once); the
        // bed-normal face's geometry is not worth computing for it.
        if l.side.h <= H_DRY && r.side.h <= H_DRY {
            return FaceFlux::default();
        }
        if let Some(m) = self.bed() {
            return self.bed_normal_face(m, l, r, (d, along_x), cells, centres);
        }
        let mu_of = |speed: f64, h: f64, drive: f64| self.face_mu(l, r, speed, h, drive, cells);
        let (g_n, dt) = (self.raster.g_n, self.dt);
        let drives = (l.drive, r.drive);
        let (ls, rs) = (l.side, r.side);
        let found = match centres {
            None => interface_with_zoned_transverse_drive(mu_of, ls, rs, 0.0, drives, g_n, d, dt),
            Some(c) => {
                // Order 2: ΔC decides from the drive between the cell centres, as at
                // order 1 (`muscl`, "ΔC"): the part of the surface's drop between the
                // centres that the edges do not see is added to the face's drive.
                let centre = (c.r.0 + c.r.2) - (c.l.0 + c.l.2);
                let edges = (rs.h + rs.z) - (ls.h + ls.z);
                let missing = -g_n * (centre - edges) / d;
                let (wl, wr) = (ls.sqrt_h, rs.sqrt_h);
                let disk = |drive: f64, mu: f64| {
                    disk_friction(drive + missing, mu * g_n, (wl, wr), drives)
                };
                interface_with_friction(mu_of, ls, rs, 0.0, disk, (g_n, g_n), d, dt)
            }
        };
        match found {
            None => FaceFlux::default(),
            Some((c, sl, sr)) => {
                let t_l = if c.left_at_rest { 0.0 } else { l.t };
                let t_r = if c.right_at_rest { 0.0 } else { r.t };
                FaceFlux {
                    h: mass_flux(&c, sl, sr),
                    qn: layer_momentum_flux(&c, c.h_minus, c.h_plus, sl.u, sr.u),
                    qt: transverse_flux(&c, sl, sr, t_l, t_r),
                    ..face_sources(&c)
                }
            }
        }
    }

    /// A face in the bed-normal frame ([`bed_normal::face`], docs/numerics.md) with the
    /// geometry of its cells `cells` and, with friction zones, the law of the cell the
    /// normal drive pushes mass out of ([`Self::face_law`]).
    #[inline(always)]
    fn bed_normal_face<C: Fn() -> (usize, usize) + Copy>(
        &self,
        m: &BedMetric,
        l: &FaceSide,
        r: &FaceSide,
        (d, along_x): (f64, bool),
        cells: C,
        centres: Option<Centres>,
    ) -> FaceFlux {
        // The cells' geometry (a ghost's is its edge cell's): cos θ and the bed's
        // slope along the face.
        let (cl, cr) = cells();
        let slope_t = |c: usize| if along_x { m.gy[c] } else { m.gx[c] };
        let law_of = |drive: f64| self.face_law(drive, cells);
        let (cos, slopes) = ((m.cos[cl], m.cos[cr]), (slope_t(cl), slope_t(cr)));
        let centres = centres.map(|c| ((c.l.0, c.l.1), (c.r.0, c.r.1)));
        bed_normal::face(l, r, cos, slopes, law_of, centres, (d, self.dt))
    }

    /// A face with a wall on the left (`wall_l`), the right or both sides: the wall
    /// side mirrors the other (normal velocity reversed), no mass and no tangential
    /// momentum cross, and between two walls nothing does. The wall side takes the
    /// friction of the flow side's cell.
    #[inline(never)]
    fn wall_face(
        &self,
        l: FaceSide,
        r: FaceSide,
        (wall_l, wall_r): (bool, bool),
        d: (f64, bool),
        (lo, hi): (usize, usize),
    ) -> FaceFlux {
        let mirror = |s: FaceSide| FaceSide {
            side: Side {
                u: -s.side.u,
                u_base: -s.side.u_base,
                ..s.side
            },
            ..s
        };
        let (l, r, cells) = match (wall_l, wall_r) {
            (true, true) => return FaceFlux::default(),
            (true, false) => (mirror(r), r, (hi, hi)),
            (false, true) => (l, mirror(l), (lo, lo)),
            (false, false) => (l, r, (lo, hi)),
        };
        let f = self.face_flux(&l, &r, d, move || cells, None);
        FaceFlux {
            h: 0.0,
            qt: 0.0,
            ..f
        }
    }

    /// The face between sides `l` and `r` of the cells `cells`, with (`WALLS`) their
    /// wall kinds `walls`.
    #[inline(always)]
    fn face<const WALLS: bool, C: Fn() -> (usize, usize) + Copy>(
        &self,
        l: FaceSide,
        r: FaceSide,
        (wl, wr): (bool, bool),
        d: (f64, bool),
        (cells, pos): (C, FacePos),
    ) -> FaceFlux {
        if WALLS && (wl || wr) {
            self.wall_face(l, r, (wl, wr), d, cells())
        } else {
            self.open_face(&l, &r, d, cells, pos)
        }
    }

    /// The y-faces between two ghost-inclusive rows, the upper one `r + 1`, from
    /// their views, from column `c0` on.
    fn y_faces<const WALLS: bool>(
        &self,
        (r, c0): (usize, usize),
        lower: &[CellView],
        upper: &[CellView],
        row: &mut [FaceFlux],
    ) {
        let dy = self.raster.dy();
        for (k, ((f, lo), hi)) in row.iter_mut().zip(lower).zip(upper).enumerate() {
            let i = c0 + k;
            let walls = if WALLS {
                (self.y_wall(i, r), self.y_wall(i, r + 1))
            } else {
                (false, false)
            };
            let cells = || self.y_cells(i, r);
            let at = (cells, FacePos::Y(i, r));
            *f = self.face::<WALLS, _>(lo.y_side(), hi.y_side(), walls, (dy, false), at);
        }
    }

    /// Sweeps tile (`rows`, `cols`): for every cell, calls `cell(i, j, west, east,
    /// south, north)` with its four faces. `s` holds the face and view rows. The faces
    /// on the tile's edges are computed from the same views as the neighbouring
    /// tile's (the same operations on the same data): the same bits.
    #[inline(always)]
    fn sweep<
        const WALLS: bool,
        F: FnMut(usize, usize, &FaceFlux, &FaceFlux, &FaceFlux, &FaceFlux),
    >(
        &self,
        (rows, cols): (Range<usize>, Range<usize>),
        s: &mut TileScratch,
        mut cell: F,
    ) {
        let (nx, dx) = (self.nx, self.raster.dx());
        let (c0, c1) = (cols.start, cols.end);
        let w = c1 - c0;
        let TileScratch {
            below,
            above,
            lower,
            upper,
        } = s;
        let (mut below, mut above) = (&mut below[..w], &mut above[..w]);
        let (mut lower, mut upper) = (&mut lower[..w], &mut upper[..w]);
        self.views(rows.start, c0, lower);
        self.views(rows.start + 1, c0, upper);
        self.y_faces::<WALLS>((rows.start, c0), lower, upper, below);
        for j in rows {
            std::mem::swap(&mut lower, &mut upper);
            self.views(j + 2, c0, upper);
            self.y_faces::<WALLS>((j + 1, c0), lower, upper, above);
            // The row's own views (`lower`, ghost-inclusive row j + 1) for the tile's
            // columns; beyond them the neighbours' views, or the edge ghosts from
            // [`Self::x_side`].
            let row = &*lower;
            let x_face = |left: FaceSide, right: FaceSide, c: usize| {
                let walls = if WALLS {
                    (self.x_wall(c, j), self.x_wall(c + 1, j))
                } else {
                    (false, false)
                };
                let at = (|| self.x_cells(c, j), FacePos::X(c, j));
                self.face::<WALLS, _>(left, right, walls, (dx, true), at)
            };
            let mut left = if c0 == 0 {
                self.x_side(0, j)
            } else {
                self.view(c0 - 1, j).x_side()
            };
            let mut right = row[0].x_side();
            let mut west = x_face(left, right, c0);
            for i in c0..c1 {
                let next = if i + 1 < c1 {
                    row[i + 1 - c0].x_side()
                } else if i + 1 < nx {
                    self.view(i + 1, j).x_side()
                } else {
                    self.x_side(nx + 1, j)
                };
                (left, right) = (right, next);
                let east = x_face(left, right, i + 1);
                cell(i, j, &west, &east, &below[i - c0], &above[i - c0]);
                west = east;
            }
            std::mem::swap(&mut below, &mut above);
        }
    }

    /// The new state of `cell` from its four faces ([`update_cell`]). In the
    /// bed-normal frame the faces carry the covariant momenta H G u: the cell's are
    /// lowered, updated, given the geodesic source Δt H (∇b·u) ∇²b u of the
    /// bed's curvature (the term that keeps a mass on a curved bed on it with its
    /// energy, docs/numerics.md), and raised back to the horizontal discharges H u.
    #[inline(always)]
    fn update(&self, cell: usize, r: (f64, f64), faces: [&FaceFlux; 4]) -> (f64, f64, f64) {
        let old = (self.h[cell], self.hu[cell], self.hv[cell]);
        let interior = O2.then(|| self.interior(cell % self.nx, cell / self.nx));
        let Some(m) = self.bed() else {
            return update_cell(old, r, faces, interior);
        };
        bed_normal::update(m, cell, old, self.dt, |lowered| {
            update_cell(lowered, r, faces, interior)
        })
    }

    /// The four faces (west, east, south, north) of cell (i, j) of the limited pass,
    /// every flux scaled by its donor's draining factor in `theta` (a ghost donor
    /// has 1; a face beside a wall carries no mass and is not scaled). The sides and
    /// fluxes are those of [`Self::sweep`] (the same operations on the same data).
    #[inline(always)]
    fn limited_faces<const WALLS: bool>(
        &self,
        theta: &impl Fn(usize) -> f64,
        i: usize,
        j: usize,
    ) -> [FaceFlux; 4] {
        let (nx, ny) = (self.nx, self.ny);
        let (dx, dy) = (self.raster.dx(), self.raster.dy());
        let x_theta = |c: usize| {
            if c >= 1 && c <= nx {
                theta(j * nx + c - 1)
            } else {
                1.0
            }
        };
        let y_theta = |r: usize| {
            if r >= 1 && r <= ny {
                theta((r - 1) * nx + i)
            } else {
                1.0
            }
        };
        let donor = |f: FaceFlux, lo: f64, hi: f64| f.drained(if f.h > 0.0 { lo } else { hi });
        let x_face = |c: usize| {
            let (l, r, cells) = (self.x_side(c, j), self.x_side(c + 1, j), || {
                self.x_cells(c, j)
            });
            if WALLS {
                let (wl, wr) = (self.x_wall(c, j), self.x_wall(c + 1, j));
                if wl || wr {
                    return self.wall_face(l, r, (wl, wr), (dx, true), cells());
                }
            }
            donor(
                self.open_face(&l, &r, (dx, true), cells, FacePos::X(c, j)),
                x_theta(c),
                x_theta(c + 1),
            )
        };
        let y_face = |r: usize| {
            let (lo, hi, cells) = (self.y_side(i, r), self.y_side(i, r + 1), || {
                self.y_cells(i, r)
            });
            if WALLS {
                let (wl, wr) = (self.y_wall(i, r), self.y_wall(i, r + 1));
                if wl || wr {
                    return self.wall_face(lo, hi, (wl, wr), (dy, false), cells());
                }
            }
            donor(
                self.open_face(&lo, &hi, (dy, false), cells, FacePos::Y(i, r)),
                y_theta(r),
                y_theta(r + 1),
            )
        };
        // Ghost-inclusive column i + 1 and row j + 1.
        [x_face(i), x_face(i + 1), y_face(j), y_face(j + 1)]
    }
}

/// The new state of one cell from its old state and its four faces (west, east,
/// south, north), `r` = (Δt/Δx, Δt/Δy): (unclipped new thickness, h u, h v). At order
/// 2 `interior` holds the cell's interior forces along x and y and their gravity parts
/// ([`Ctx::interior`]), added to the faces' shares as on a line, and whether the cell
/// is reconstructed along both axes: such a cell (wet neighbours all round, moving)
/// keeps its whole gravity source. The near-dry rule evaluates the source at the new
/// thickness, a change of O(Δt) relative to it wherever the depth falls, which made
/// Heun's step first order in the interior of a smooth flow over a curved bed (the
/// observed order on Thacker's paraboloid fell from 2.1 to 1.45); fronts, whose cells
/// are first order, keep the rule.
#[inline(always)]
fn update_cell(
    old: (f64, f64, f64),
    r: (f64, f64),
    faces: [&FaceFlux; 4],
    interior: Option<([f64; 4], bool)>,
) -> (f64, f64, f64) {
    match interior {
        None => update_cell_with(old, r, faces, ([0.0; 4], false), false),
        Some(interior) => update_cell_with(old, r, faces, interior, true),
    }
}

/// [`update_cell`] with (`o2`) or without the interior forces `interior`.
#[inline(always)]
fn update_cell_with(
    (h_old, hu_old, hv_old): (f64, f64, f64),
    (rx, ry): (f64, f64),
    [w, e, so, no]: [&FaceFlux; 4],
    interior: ([f64; 4], bool),
    o2: bool,
) -> (f64, f64, f64) {
    // The x and y parts are summed before they are subtracted: a sum of two terms does
    // not depend on their order, so a state symmetric under x ↔ y (Δx = Δy) stays
    // symmetric to the bit.
    let hn = h_old - (rx * (e.h - w.h) + ry * (no.h - so.h));
    // Clip round-off below zero; `f64::max` would also turn a NaN into 0.
    let h = if hn < 0.0 { 0.0 } else { hn };
    let ([sx, bx, sy, by], smooth) = interior;
    let drained = if o2 && smooth {
        0.0
    } else {
        drained_fraction(h, h_old)
    };
    let (source_x, source_y) = if o2 {
        (
            e.share_l + w.share_r + sx - (e.body_l + w.body_r + bx) * drained,
            no.share_l + so.share_r + sy - (no.body_l + so.body_r + by) * drained,
        )
    } else {
        (
            e.share_l + w.share_r - (e.body_l + w.body_r) * drained,
            no.share_l + so.share_r - (no.body_l + so.body_r) * drained,
        )
    };
    let qu = hu_old - (rx * (e.qn - w.qn + source_x) + ry * (no.qt - so.qt));
    let qv = hv_old - (rx * (e.qt - w.qt) + ry * (no.qn - so.qn + source_y));
    if h <= H_DRY {
        (hn, 0.0, 0.0)
    } else {
        (hn, qu, qv)
    }
}

/// The draining factor θ = min(1, h/(Δt outflow over the four faces)) of a cell of
/// thickness `h` with the unlimited faces w, e, s, n (Bollermann et al. 2013).
#[inline(always)]
fn draining_factor(h: f64, (rx, ry): (f64, f64), [w, e, so, no]: [&FaceFlux; 4]) -> f64 {
    let need = rx * (e.h.max(0.0) + (-w.h).max(0.0)) + ry * (no.h.max(0.0) + (-so.h).max(0.0));
    if need > h {
        h.max(0.0) / need
    } else {
        1.0
    }
}

/// The smaller of two (thickness, cell) pairs, the lower cell on a tie: the first
/// minimum in cell order, whatever order the tiles are combined in.
#[inline(always)]
fn first_of(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    if b.0 < a.0 || (b.0 == a.0 && b.1 < a.1) {
        b
    } else {
        a
    }
}

/// The per-tile and per-cell outputs of a pass, written by the tile tasks at their own
/// tile's indices.
struct Outputs<'a> {
    h: Disjoint<'a, f64>,
    hu: Disjoint<'a, f64>,
    hv: Disjoint<'a, f64>,
    drain: Disjoint<'a, f64>,
    worst: Disjoint<'a, (f64, usize)>,
    drains: Disjoint<'a, bool>,
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// The outputs of a pass and the read-only data the tasks share.
    fn outputs(
        &mut self,
    ) -> (
        Outputs<'_>,
        &CellFriction<L>,
        &[Mutex<TileScratch>],
        &Workers,
        Option<&Reconstruction>,
    ) {
        let out = Outputs {
            h: Disjoint::new(&mut self.h_new),
            hu: Disjoint::new(&mut self.hu_new),
            hv: Disjoint::new(&mut self.hv_new),
            drain: Disjoint::new(&mut self.drain),
            worst: Disjoint::new(&mut self.tile_worst),
            drains: Disjoint::new(&mut self.tile_drains),
        };
        let recon = self.recon.as_ref();
        (out, &self.friction, &self.scratch, &self.workers, recon)
    }

    /// Order 2: the slopes of the cells of the stepped tiles ([`Ctx::cell_slopes`]),
    /// one task per tile.
    fn reconstruct(&mut self, raster: &Raster2d, dt: f64, state: &State2d) {
        let HydrostaticStep2d {
            friction,
            workers,
            recon,
            ..
        } = self;
        let Some(recon) = recon.as_mut() else {
            return;
        };
        let limiter = recon.limiter;
        let (x, y) = (Disjoint::new(&mut recon.x), Disjoint::new(&mut recon.y));
        let ctx = Ctx::<L, false, true>::new(friction, raster, state, dt);
        let (nx, tiles) = (raster.nx(), &state.tiles);
        workers.tiles(tiles.stepped_by_load(), |_, t| {
            let (rows, cols) = tiles.cells(t);
            for j in rows {
                for i in cols.clone() {
                    let [sx, sy] = ctx.cell_slopes(limiter, i, j);
                    // SAFETY: cell (i, j) is in tile t, this task's alone.
                    unsafe {
                        x.set(j * nx + i, sx);
                        y.set(j * nx + i, sy);
                    }
                }
            }
        });
    }

    /// The unlimited update pass over the stepped tiles into the new-state buffers
    /// (the thickness unclipped), with the draining factors θ ≠ 1 from the same faces;
    /// returns the smallest new thickness and its cell, first in cell order.
    fn update_pass(&mut self, raster: &Raster2d, dt: f64, state: &State2d) -> (f64, usize) {
        let o2 = self.recon.is_some();
        match (raster.walls().is_empty(), raster.metric().is_some(), o2) {
            (true, false, false) => self.update_pass_with::<false, false, false>(raster, dt, state),
            (false, false, false) => self.update_pass_with::<true, false, false>(raster, dt, state),
            (true, true, false) => self.update_pass_with::<false, true, false>(raster, dt, state),
            (false, true, false) => self.update_pass_with::<true, true, false>(raster, dt, state),
            (true, false, true) => self.update_pass_with::<false, false, true>(raster, dt, state),
            (false, false, true) => self.update_pass_with::<true, false, true>(raster, dt, state),
            (true, true, true) => self.update_pass_with::<false, true, true>(raster, dt, state),
            (false, true, true) => self.update_pass_with::<true, true, true>(raster, dt, state),
        }
    }

    /// [`Self::update_pass`] with (`WALLS`) or without the test for wall cells, in the
    /// bed-normal frame (`BN`) or another.
    fn update_pass_with<const WALLS: bool, const BN: bool, const O2: bool>(
        &mut self,
        raster: &Raster2d,
        dt: f64,
        state: &State2d,
    ) -> (f64, usize) {
        let nx = raster.nx();
        let r = (dt / raster.dx(), dt / raster.dy());
        let tiles = &state.tiles;
        let (out, friction, scratch, workers, recon) = self.outputs();
        let ctx = Ctx::<L, BN, O2>::new(friction, raster, state, dt).with_recon(recon);
        workers.tiles(tiles.stepped_by_load(), |thread, t| {
            let mut s = scratch[thread].lock().expect("a thread's own scratch");
            let mut worst = (f64::INFINITY, 0usize);
            let mut drains = false;
            ctx.sweep::<WALLS, _>(tiles.cells(t), &mut s, |i, j, w, e, so, no| {
                let cell = j * nx + i;
                let (hn, qu, qv) = ctx.update(cell, r, [w, e, so, no]);
                if hn < worst.0 {
                    worst = (hn, cell);
                }
                let theta = draining_factor(ctx.h[cell], r, [w, e, so, no]);
                // SAFETY: `cell` is in tile t, this task's alone.
                unsafe {
                    out.h.set(cell, hn);
                    out.hu.set(cell, qu);
                    out.hv.set(cell, qv);
                    if theta != 1.0 {
                        out.drain.set(cell, theta);
                        drains = true;
                    }
                }
            });
            // SAFETY: entry t is this task's alone.
            unsafe {
                out.worst.set(t, worst);
                out.drains.set(t, drains);
            }
        });
        self.worst(tiles)
    }

    /// The limited pass: every flux leaving a cell scaled by the cell's draining
    /// factor θ. Only the cells with a face whose donor has θ ≠ 1 (a draining cell and
    /// its four neighbours) change; the others keep the values of the unlimited pass,
    /// which are the same bits (a flux times θ = 1 is the flux). Returns the smallest
    /// new thickness and its cell, first in cell order.
    fn limited_pass(&mut self, raster: &Raster2d, dt: f64, state: &State2d) -> (f64, usize) {
        let o2 = self.recon.is_some();
        match (raster.walls().is_empty(), raster.metric().is_some(), o2) {
            (true, false, false) => {
                self.limited_pass_with::<false, false, false>(raster, dt, state)
            }
            (false, false, false) => {
                self.limited_pass_with::<true, false, false>(raster, dt, state)
            }
            (true, true, false) => self.limited_pass_with::<false, true, false>(raster, dt, state),
            (false, true, false) => self.limited_pass_with::<true, true, false>(raster, dt, state),
            (true, false, true) => self.limited_pass_with::<false, false, true>(raster, dt, state),
            (false, false, true) => self.limited_pass_with::<true, false, true>(raster, dt, state),
            (true, true, true) => self.limited_pass_with::<false, true, true>(raster, dt, state),
            (false, true, true) => self.limited_pass_with::<true, true, true>(raster, dt, state),
        }
    }

    /// [`Self::limited_pass`] with (`WALLS`) or without the test for wall cells, in the
    /// bed-normal frame (`BN`) or another.
    fn limited_pass_with<const WALLS: bool, const BN: bool, const O2: bool>(
        &mut self,
        raster: &Raster2d,
        dt: f64,
        state: &State2d,
    ) -> (f64, usize) {
        let (nx, ny) = (raster.nx(), raster.ny());
        let r = (dt / raster.dx(), dt / raster.dy());
        let tiles = &state.tiles;
        let near = self.tiles_near_drains(tiles);
        let (out, friction, _, workers, recon) = self.outputs();
        let ctx = Ctx::<L, BN, O2>::new(friction, raster, state, dt).with_recon(recon);
        // SAFETY (reads of `drain`): this pass does not write it.
        let theta = |k: usize| unsafe { out.drain.get(k) };
        workers.tiles(&near, |_, t| {
            let (rows, columns) = tiles.cells(t);
            let mut worst = (f64::INFINITY, 0usize);
            for j in rows {
                for i in columns.clone() {
                    let cell = j * nx + i;
                    let affected = theta(cell) != 1.0
                        || (i > 0 && theta(cell - 1) != 1.0)
                        || (i + 1 < nx && theta(cell + 1) != 1.0)
                        || (j > 0 && theta(cell - nx) != 1.0)
                        || (j + 1 < ny && theta(cell + nx) != 1.0);
                    if affected {
                        let [w, e, so, no] = ctx.limited_faces::<WALLS>(&theta, i, j);
                        let (hn, qu, qv) = ctx.update(cell, r, [&w, &e, &so, &no]);
                        // SAFETY: `cell` is in tile t, this task's alone.
                        unsafe {
                            out.h.set(cell, hn);
                            out.hu.set(cell, qu);
                            out.hv.set(cell, qv);
                        }
                    }
                    // SAFETY: as above.
                    let hn = unsafe { out.h.get(cell) };
                    if hn < worst.0 {
                        worst = (hn, cell);
                    }
                }
            }
            // SAFETY: entry t is this task's alone.
            unsafe { out.worst.set(t, worst) };
        });
        self.near_drains = near;
        self.worst(tiles)
    }

    /// The stepped tiles the limited pass may change, taken out of the stage (put back
    /// by the caller): a tile changes only if it or a tile next to it has a draining
    /// cell (the flags are false outside the stepped tiles). The others keep the
    /// unlimited pass's values and smallest thickness, and cost the pass no task.
    fn tiles_near_drains(&mut self, tiles: &Tiles) -> Vec<u32> {
        let mut near = std::mem::take(&mut self.near_drains);
        near.clear();
        let cols = tiles.cols();
        let rows_of_tiles = tiles.count() / cols.max(1);
        let drains = |t: usize| self.tile_drains[t];
        near.extend(tiles.stepped_by_load().iter().filter(|&&t| {
            let t = t as usize;
            let (band, col) = (t / cols, t % cols);
            drains(t)
                || (col > 0 && drains(t - 1))
                || (col + 1 < cols && drains(t + 1))
                || (band > 0 && drains(t - cols))
                || (band + 1 < rows_of_tiles && drains(t + cols))
        }));
        near
    }

    /// The smallest new thickness over the stepped tiles, first in cell order.
    fn worst(&self, tiles: &Tiles) -> (f64, usize) {
        tiles
            .stepped()
            .iter()
            .fold((f64::INFINITY, 0usize), |w, &t| {
                first_of(w, self.tile_worst[t as usize])
            })
    }

    /// Resets the draining factors and flags of the tiles that drained to 1 and false
    /// (their values outside a step).
    fn reset_drains(&mut self, tiles: &Tiles) {
        for &t in tiles.stepped() {
            let t = t as usize;
            if self.tile_drains[t] {
                self.tile_drains[t] = false;
                for cells in tiles.row_segments(t) {
                    self.drain[cells].fill(1.0);
                }
            }
        }
    }
}

impl<L: BasalFriction> Stage<Raster2d, State2d> for HydrostaticStep2d<L> {
    fn name(&self) -> &'static str {
        match self.friction_step {
            None => "hyperbolic",
            Some(_) => "hyperbolic+friction",
        }
    }

    fn apply(
        &mut self,
        raster: &Raster2d,
        clock: StepClock,
        state: &mut State2d,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        let nx = raster.nx();
        let workers = &self.workers;
        state.refresh_tiles_on(nx, raster.ny(), &|tiles, f| workers.tiles(tiles, f));
        self.reconstruct(raster, dt, state);
        let mut worst = self.update_pass(raster, dt, state);
        if worst.0 < 0.0 {
            worst = self.limited_pass(raster, dt, state);
        }
        self.reset_drains(&state.tiles);
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                cell: worst.1,
                h: worst.0,
            });
        }
        self.write_new_state(raster, dt, state);
        state.tiles.count_updates();
        Ok(())
    }
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// The new state into the stepped tiles of `state`, with round-off below zero
    /// (kept for the test of `apply`) clipped, one task per tile; the other tiles are
    /// unchanged. With [`Self::then_friction`] each cell also gets the friction step
    /// and each tile its flags as the task leaves it; without, the tiles are pending.
    fn write_new_state(&self, raster: &Raster2d, dt: f64, state: &mut State2d) {
        let State2d { h, hu, hv, tiles } = state;
        let (h, hu, hv) = (Disjoint::new(h), Disjoint::new(hu), Disjoint::new(hv));
        let (h_new, hu_new, hv_new) = (&self.h_new, &self.hu_new, &self.hv_new);
        let tile_worst = &self.tile_worst;
        let write = |tiles: &Tiles, t: usize| {
            let clip = tile_worst[t].0 < 0.0;
            for cells in tiles.row_segments(t) {
                // SAFETY: the cells are in tile t, this task's alone.
                let (h, hu, hv) = unsafe {
                    (
                        h.slice(cells.clone()),
                        hu.slice(cells.clone()),
                        hv.slice(cells.clone()),
                    )
                };
                h.copy_from_slice(&h_new[cells.clone()]);
                if clip {
                    h.iter_mut().filter(|h| **h < 0.0).for_each(|h| *h = 0.0);
                }
                hu.copy_from_slice(&hu_new[cells.clone()]);
                hv.copy_from_slice(&hv_new[cells.clone()]);
                if let Some(friction) = &self.friction_step {
                    for (i, k) in cells.enumerate() {
                        (hu[i], hv[i]) = friction.cell(raster, k, (hu[i], hv[i]), h[i], dt);
                    }
                }
            }
        };
        let run: TileRunner = &|list, f| self.workers.tiles(list, f);
        if self.friction_step.is_none() {
            run(tiles.stepped_by_load(), &|_, t| write(tiles, t));
            tiles.mark_pending();
            return;
        }
        // SAFETY (the reads): the cells are in tile t, written by this task above.
        let cell = |k: usize| unsafe { (h.get(k), hu.get(k), hv.get(k)) };
        tiles.write_classified(run, &|tiles, t| {
            write(tiles, t);
            tiles.bits(t, cell)
        });
    }
}
