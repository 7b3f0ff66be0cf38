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
//! Work is done by bands of whole rows ([`crate::grid::raster`]): a band computes the
//! y-faces under and over each of its rows (one row of halo on each side) and the
//! x-faces along them, and writes its rows of the new state into the step's own
//! buffers, which are swapped with the state's at the end (no copy). The y-faces at the
//! edge between two bands are computed by both, with the same operations on the same
//! data. Each cell's velocities and √h are computed once per sweep (its y-side, turned
//! to x for the x-faces). Memory: the new state (3 values per cell), the draining
//! factors (1) and two rows of y-faces per band.
//!
//! The limiter in two passes. The unlimited pass writes the new state and, from the
//! same four faces, every cell's draining factor θ = min(1, h/(Δt outflow)). Only if
//! some new thickness is negative, the limited pass follows: a face's fluxes times its
//! donor's θ differ from the unlimited ones only where θ ≠ 1 (a flux times 1 is the
//! flux), so it recomputes just the cells next to a draining cell (the cell and its
//! four neighbours), face by face, and keeps the unlimited values elsewhere: the same
//! bits as a full second pass, at the cost of the fronts only.
//!
//! The CFL step: with the per-cell signal speed s = max(|u|, |v|) + √(g_n h) and
//! Δt = CFL · min(Δx, Δy)/s, Δt (s_x/Δx + s_y/Δy) ≤ 2 CFL; the unsplit update keeps
//! h ≥ 0 for CFL ≤ ½ (the limiter and the run loop's retry catch the rest).

use super::face::{
    drained_fraction, interface, layer_momentum_flux, mass_flux, transverse_flux, Side,
};
use super::workers::Workers;
use super::{Stage, StageError};
use crate::grid::raster::BAND_ROWS;
use crate::grid::Raster2d;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::State2d;

/// What one face gives its two cells: mass flux, normal and tangential momentum
/// fluxes, the pressure sources of the lower-index (l) and higher-index (r) cell and
/// their gravity parts.
#[derive(Debug, Clone, Copy, Default)]
struct FaceFlux {
    h: f64,
    qn: f64,
    qt: f64,
    share_l: f64,
    share_r: f64,
    body_l: f64,
    body_r: f64,
}

impl FaceFlux {
    /// The fluxes scaled by the donor's draining factor θ (sources unchanged).
    #[inline(always)]
    fn drained(mut self, theta: f64) -> FaceFlux {
        self.h *= theta;
        self.qn *= theta;
        self.qt *= theta;
        self
    }
}

/// One band's scratch: the y-faces under and over the current row, and the smallest
/// new thickness of the band with its cell.
#[derive(Debug, Clone)]
struct BandScratch {
    below: Vec<FaceFlux>,
    above: Vec<FaceFlux>,
    /// The sides that the y-faces see in the rows under and over them (each row's
    /// computed once per sweep).
    lower: Vec<(Side, f64)>,
    upper: Vec<(Side, f64)>,
    worst: (f64, usize),
}

/// The 2-D hydrostatic step, generic over the basal friction law (used in ΔC).
#[derive(Debug)]
pub struct HydrostaticStep2d<L: BasalFriction> {
    law: L,
    workers: Workers,
    h_new: Vec<f64>,
    hu_new: Vec<f64>,
    hv_new: Vec<f64>,
    /// Draining factors per cell, written only when a cell would empty.
    drain: Vec<f64>,
    scratch: Vec<BandScratch>,
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// The step on `raster`, its bands run by `workers`.
    pub fn new(law: L, raster: &Raster2d, workers: Workers) -> Self {
        let (nx, cells) = (raster.nx(), raster.nx() * raster.ny());
        let band = BandScratch {
            below: vec![FaceFlux::default(); nx],
            above: vec![FaceFlux::default(); nx],
            lower: vec![(Side::monolayer(0.0, 0.0, 0.0, 0.0), 0.0); nx],
            upper: vec![(Side::monolayer(0.0, 0.0, 0.0, 0.0), 0.0); nx],
            worst: (f64::INFINITY, 0),
        };
        HydrostaticStep2d {
            law,
            workers,
            h_new: vec![0.0; cells],
            hu_new: vec![0.0; cells],
            hv_new: vec![0.0; cells],
            drain: vec![1.0; cells],
            scratch: vec![band; raster.bands()],
        }
    }

    /// Bytes of scratch per cell that the step holds (new state, draining factors,
    /// face rows), for the memory budget of `docs/performance.md`.
    pub fn bytes_per_cell(&self) -> f64 {
        let cells = self.h_new.len() as f64;
        let faces: usize = self
            .scratch
            .iter()
            .map(|s| {
                (s.below.len() + s.above.len()) * std::mem::size_of::<FaceFlux>()
                    + (s.lower.len() + s.upper.len()) * std::mem::size_of::<(Side, f64)>()
            })
            .sum();
        (4.0 * 8.0 * cells + faces as f64) / cells
    }
}

/// The read-only data of one step.
struct Ctx<'a, L> {
    law: L,
    raster: &'a Raster2d,
    h: &'a [f64],
    hu: &'a [f64],
    hv: &'a [f64],
    nx: usize,
    ny: usize,
    dt: f64,
    /// Draining factors of the donors (limited pass only).
    theta: Option<&'a [f64]>,
}

impl<L: BasalFriction> Ctx<'_, L> {
    /// The side of ghost-inclusive column `c` (0 and nx + 1 are ghosts) of row `j`
    /// seen by an x-face, and its tangential velocity v.
    #[inline(always)]
    fn x_side(&self, c: usize, j: usize) -> (Side, f64) {
        let sides = self.raster.sides();
        let (cell, sign) = if c == 0 {
            (j * self.nx, sides.west.discharge_sign())
        } else if c == self.nx + 1 {
            (j * self.nx + self.nx - 1, sides.east.discharge_sign())
        } else {
            (j * self.nx + c - 1, 1.0)
        };
        let g = self.raster.ghost_index(c, j + 1);
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hu[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        (side, velocity(h, self.hv[cell]))
    }

    /// The side of column i, ghost-inclusive row `r` (0 and ny + 1 are ghosts), seen
    /// by a y-face, and its tangential velocity u.
    #[inline(always)]
    fn y_side(&self, i: usize, r: usize) -> (Side, f64) {
        let sides = self.raster.sides();
        let (cell, sign) = if r == 0 {
            (i, sides.south.discharge_sign())
        } else if r == self.ny + 1 {
            ((self.ny - 1) * self.nx + i, sides.north.discharge_sign())
        } else {
            ((r - 1) * self.nx + i, 1.0)
        };
        let g = self.raster.ghost_index(i + 1, r);
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hv[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        (side, velocity(h, self.hu[cell]))
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

    /// Draining factor of the donor of a face between ghost-inclusive cells `lo` and
    /// `hi` (`None` for a ghost), by the sign of the mass flux.
    #[inline(always)]
    fn donor_theta(&self, flux: f64, lo: Option<usize>, hi: Option<usize>) -> f64 {
        let Some(theta) = self.theta else {
            return 1.0;
        };
        let donor = if flux > 0.0 { lo } else { hi };
        donor.map_or(1.0, |c| theta[c])
    }

    /// The sides of ghost-inclusive row `r` as the y-faces see them.
    fn y_sides(&self, r: usize, row: &mut [(Side, f64)]) {
        for (i, side) in row.iter_mut().enumerate() {
            *side = self.y_side(i, r);
        }
    }

    /// The y-faces between ghost-inclusive rows `r` and `r + 1` from their sides.
    fn y_faces<const WALLS: bool>(
        &self,
        r: usize,
        lower: &[(Side, f64)],
        upper: &[(Side, f64)],
        row: &mut [FaceFlux],
    ) {
        let (g_n, dy) = (self.raster.g_n, self.raster.dy());
        for (i, ((f, lo), hi)) in row.iter_mut().zip(lower).zip(upper).enumerate() {
            if WALLS {
                let (wl, wr) = (self.y_wall(i, r), self.y_wall(i, r + 1));
                if wl || wr {
                    *f = wall_face(&self.law, *lo, *hi, wl, wr, g_n, dy, self.dt);
                    continue;
                }
            }
            *f = face_flux(&self.law, lo.0, hi.0, lo.1, hi.1, g_n, dy, self.dt);
        }
    }

    /// The four faces (west, east, south, north) of cell (i, j), every flux scaled by
    /// its donor's draining factor: the faces of the limited pass, one cell at a time.
    /// The sides and fluxes are those of [`Self::sweep`] (same functions, same data).
    #[inline(always)]
    fn limited_faces(&self, i: usize, j: usize) -> [FaceFlux; 4] {
        let (nx, ny, g_n) = (self.nx, self.ny, self.raster.g_n);
        let (dx, dy) = (self.raster.dx(), self.raster.dy());
        let x_cell = |c: usize| (c >= 1 && c <= nx).then(|| j * nx + c - 1);
        let y_cell = |r: usize| (r >= 1 && r <= ny).then(|| (r - 1) * nx + i);
        let x_face = |c: usize| {
            let (l, r) = (self.x_side(c, j), self.x_side(c + 1, j));
            let (wl, wr) = (self.x_wall(c, j), self.x_wall(c + 1, j));
            if wl || wr {
                return wall_face(&self.law, l, r, wl, wr, g_n, dx, self.dt);
            }
            let f = face_flux(&self.law, l.0, r.0, l.1, r.1, g_n, dx, self.dt);
            f.drained(self.donor_theta(f.h, x_cell(c), x_cell(c + 1)))
        };
        let y_face = |r: usize| {
            let (lo, hi) = (self.y_side(i, r), self.y_side(i, r + 1));
            let (wl, wr) = (self.y_wall(i, r), self.y_wall(i, r + 1));
            if wl || wr {
                return wall_face(&self.law, lo, hi, wl, wr, g_n, dy, self.dt);
            }
            let f = face_flux(&self.law, lo.0, hi.0, lo.1, hi.1, g_n, dy, self.dt);
            f.drained(self.donor_theta(f.h, y_cell(r), y_cell(r + 1)))
        };
        // Ghost-inclusive column i + 1 and row j + 1.
        [x_face(i), x_face(i + 1), y_face(j), y_face(j + 1)]
    }

    /// Sweeps the rows of band `k`: for every cell, calls `cell(i, j, west, east,
    /// south, north)` with its four faces. `s` holds the face rows.
    #[inline(always)]
    fn sweep<
        const WALLS: bool,
        F: FnMut(usize, usize, &FaceFlux, &FaceFlux, &FaceFlux, &FaceFlux),
    >(
        &self,
        k: usize,
        s: &mut BandScratch,
        mut cell: F,
    ) {
        let (nx, g_n, dx) = (self.nx, self.raster.g_n, self.raster.dx());
        let rows = self.raster.band_rows(k);
        self.y_sides(rows.start, &mut s.lower);
        self.y_sides(rows.start + 1, &mut s.upper);
        self.y_faces::<WALLS>(rows.start, &s.lower, &s.upper, &mut s.below);
        for j in rows {
            std::mem::swap(&mut s.lower, &mut s.upper);
            self.y_sides(j + 2, &mut s.upper);
            self.y_faces::<WALLS>(j + 1, &s.lower, &s.upper, &mut s.above);
            // The x-face between ghost-inclusive columns c and c + 1.
            let x_face = |left: (Side, f64), right: (Side, f64), c: usize| {
                if WALLS {
                    let (wl, wr) = (self.x_wall(c, j), self.x_wall(c + 1, j));
                    if wl || wr {
                        return wall_face(&self.law, left, right, wl, wr, g_n, dx, self.dt);
                    }
                }
                face_flux(
                    &self.law, left.0, right.0, left.1, right.1, g_n, dx, self.dt,
                )
            };
            // Interior columns: the row's own y-sides (`s.lower`) turned to x: the
            // same h, velocities, √h, b and z, the roles of u and v exchanged.
            let row = &s.lower[..nx];
            let mut left = self.x_side(0, j);
            let mut right = across(row[0]);
            let mut west = x_face(left, right, 0);
            for i in 0..nx {
                let next = if i + 1 < nx {
                    across(row[i + 1])
                } else {
                    self.x_side(nx + 1, j)
                };
                (left, right) = (right, next);
                let east = x_face(left, right, i + 1);
                cell(i, j, &west, &east, &s.below[i], &s.above[i]);
                west = east;
            }
            std::mem::swap(&mut s.below, &mut s.above);
        }
    }
}

/// The side of an interior cell as an x-face sees it, from the side a y-face sees
/// (`Ctx::y_side`): the normal and tangential velocities exchanged. The same values as
/// `Ctx::x_side` (its discharge sign is 1 inside the raster).
#[inline(always)]
fn across((side, u): (Side, f64)) -> (Side, f64) {
    (
        Side {
            u,
            u_base: u,
            ..side
        },
        side.u,
    )
}

/// The fluxes of one face with sides `l`, `r` along its normal (velocities normal to
/// the face) and tangential velocities `t_l`, `t_r`; zero where nothing crosses. The
/// 1-D monolayer face ([`super::face::monolayer_fluxes`]) plus the tangential flux.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn face_flux<L: BasalFriction>(
    law: &L,
    l: Side,
    r: Side,
    t_l: f64,
    t_r: f64,
    g_n: f64,
    d: f64,
    dt: f64,
) -> FaceFlux {
    let mu_of = |speed: f64, h: f64| law.mu(speed, h, g_n * h);
    match interface(mu_of, l, r, 0.0, g_n, d, dt) {
        None => FaceFlux::default(),
        Some((c, l, r)) => {
            let t_l = if c.left_at_rest { 0.0 } else { t_l };
            let t_r = if c.right_at_rest { 0.0 } else { t_r };
            FaceFlux {
                h: mass_flux(&c, l, r),
                qn: layer_momentum_flux(&c, c.h_minus, c.h_plus, l.u, r.u),
                qt: transverse_flux(&c, l, r, t_l, t_r),
                share_l: c.share_left,
                share_r: c.share_right,
                body_l: c.body_left,
                body_r: c.body_right,
            }
        }
    }
}

/// A face with a wall on the left (`wall_l`), the right or both sides: the wall side
/// mirrors the other (normal velocity reversed), no mass and no tangential momentum
/// cross, and between two walls nothing does.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn wall_face<L: BasalFriction>(
    law: &L,
    l: (Side, f64),
    r: (Side, f64),
    wall_l: bool,
    wall_r: bool,
    g_n: f64,
    d: f64,
    dt: f64,
) -> FaceFlux {
    let mirror = |(s, t): (Side, f64)| {
        (
            Side {
                u: -s.u,
                u_base: -s.u_base,
                ..s
            },
            t,
        )
    };
    let (l, r) = match (wall_l, wall_r) {
        (true, true) => return FaceFlux::default(),
        (true, false) => (mirror(r), r),
        (false, true) => (l, mirror(l)),
        (false, false) => (l, r),
    };
    let f = face_flux(law, l.0, r.0, l.1, r.1, g_n, d, dt);
    FaceFlux {
        h: 0.0,
        qt: 0.0,
        ..f
    }
}

/// The new state of one cell from its four faces (west, east, south, north):
/// (unclipped new thickness, clipped thickness, h u, h v).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn update_cell(
    h_old: f64,
    hu_old: f64,
    hv_old: f64,
    (rx, ry): (f64, f64),
    w: &FaceFlux,
    e: &FaceFlux,
    so: &FaceFlux,
    no: &FaceFlux,
) -> (f64, f64, f64, f64) {
    let hn = h_old - rx * (e.h - w.h) - ry * (no.h - so.h);
    // Clip round-off below zero; `f64::max` would also turn a NaN into 0.
    let h = if hn < 0.0 { 0.0 } else { hn };
    let drained = drained_fraction(h, h_old);
    let source_x = e.share_l + w.share_r - (e.body_l + w.body_r) * drained;
    let source_y = no.share_l + so.share_r - (no.body_l + so.body_r) * drained;
    let qu = hu_old - rx * (e.qn - w.qn + source_x) - ry * (no.qt - so.qt);
    let qv = hv_old - rx * (e.qt - w.qt) - ry * (no.qn - so.qn + source_y);
    if h <= H_DRY {
        (hn, h, 0.0, 0.0)
    } else {
        (hn, h, qu, qv)
    }
}

/// The draining factor θ = min(1, h/(outflow over the four faces)) of a cell of
/// thickness `h` with the unlimited faces w, e, s, n.
#[inline(always)]
fn draining_factor(
    h: f64,
    (rx, ry): (f64, f64),
    w: &FaceFlux,
    e: &FaceFlux,
    so: &FaceFlux,
    no: &FaceFlux,
) -> f64 {
    let need = rx * (e.h.max(0.0) + (-w.h).max(0.0)) + ry * (no.h.max(0.0) + (-so.h).max(0.0));
    if need > h {
        h.max(0.0) / need
    } else {
        1.0
    }
}

/// The smallest value of `h_new` and its index (the first in order), `offset` added.
fn first_minimum(h_new: &[f64], offset: usize) -> (f64, usize) {
    let mut worst = (f64::INFINITY, 0usize);
    for (k, &h) in h_new.iter().enumerate() {
        if h < worst.0 {
            worst = (h, offset + k);
        }
    }
    worst
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// The unlimited update pass into the new-state buffers, with the draining factor
    /// of every cell from the same faces; returns the smallest new thickness and its
    /// cell, first in cell order. The new-state buffers hold the unclipped thickness.
    fn update_pass(&mut self, raster: &Raster2d, dt: f64, state: &State2d) -> (f64, usize) {
        if raster.walls().is_empty() {
            self.update_pass_with::<false>(raster, dt, state)
        } else {
            self.update_pass_with::<true>(raster, dt, state)
        }
    }

    /// [`Self::update_pass`] with (`WALLS`) or without the test for wall cells.
    fn update_pass_with<const WALLS: bool>(
        &mut self,
        raster: &Raster2d,
        dt: f64,
        state: &State2d,
    ) -> (f64, usize) {
        let nx = raster.nx();
        let r = (dt / raster.dx(), dt / raster.dy());
        let ctx = Ctx {
            law: self.law,
            raster,
            h: &state.h,
            hu: &state.hu,
            hv: &state.hv,
            nx,
            ny: raster.ny(),
            dt,
            theta: None,
        };
        let outputs = (
            self.h_new.as_mut_slice(),
            self.hu_new.as_mut_slice(),
            self.hv_new.as_mut_slice(),
            self.drain.as_mut_slice(),
        );
        self.workers.bands4(
            BAND_ROWS * nx,
            outputs,
            &mut self.scratch,
            |k, (h_new, hu_new, hv_new, drain), s| {
                let offset = k * BAND_ROWS * nx;
                let mut worst = (f64::INFINITY, 0usize);
                ctx.sweep::<WALLS, _>(k, s, |i, j, w, e, so, no| {
                    let cell = j * nx + i;
                    let local = cell - offset;
                    let h_old = ctx.h[cell];
                    let (hn, _, qu, qv) =
                        update_cell(h_old, ctx.hu[cell], ctx.hv[cell], r, w, e, so, no);
                    if hn < worst.0 {
                        worst = (hn, cell);
                    }
                    // The unclipped value for the positivity test.
                    (h_new[local], hu_new[local], hv_new[local]) = (hn, qu, qv);
                    drain[local] = draining_factor(h_old, r, w, e, so, no);
                });
                s.worst = worst;
            },
        );
        self.worst()
    }

    /// The limited pass: every flux leaving a cell scaled by the cell's draining
    /// factor θ. Only the cells with a face whose donor has θ ≠ 1 (a draining cell and
    /// its four neighbours) change; the others keep the values of the unlimited pass,
    /// which are the same bits (a flux times θ = 1 is the flux). Returns the smallest
    /// new thickness and its cell, first in cell order.
    fn limited_pass(&mut self, raster: &Raster2d, dt: f64, state: &State2d) -> (f64, usize) {
        let (nx, ny) = (raster.nx(), raster.ny());
        let r = (dt / raster.dx(), dt / raster.dy());
        let ctx = Ctx {
            law: self.law,
            raster,
            h: &state.h,
            hu: &state.hu,
            hv: &state.hv,
            nx,
            ny,
            dt,
            theta: Some(self.drain.as_slice()),
        };
        let theta = self.drain.as_slice();
        let outputs = (
            self.h_new.as_mut_slice(),
            self.hu_new.as_mut_slice(),
            self.hv_new.as_mut_slice(),
        );
        self.workers.bands3(
            BAND_ROWS * nx,
            outputs,
            &mut self.scratch,
            |k, (h_new, hu_new, hv_new), s| {
                let offset = k * BAND_ROWS * nx;
                for j in raster.band_rows(k) {
                    let row = &theta[j * nx..(j + 1) * nx];
                    let below = (j > 0).then(|| &theta[(j - 1) * nx..j * nx]);
                    let above = (j + 1 < ny).then(|| &theta[(j + 1) * nx..(j + 2) * nx]);
                    if row
                        .iter()
                        .chain(below.into_iter().flatten())
                        .chain(above.into_iter().flatten())
                        .all(|&t| t == 1.0)
                    {
                        continue;
                    }
                    for i in 0..nx {
                        let affected = row[i] != 1.0
                            || (i > 0 && row[i - 1] != 1.0)
                            || (i + 1 < nx && row[i + 1] != 1.0)
                            || below.is_some_and(|b| b[i] != 1.0)
                            || above.is_some_and(|a| a[i] != 1.0);
                        if !affected {
                            continue;
                        }
                        let [w, e, so, no] = ctx.limited_faces(i, j);
                        let cell = j * nx + i;
                        let local = cell - offset;
                        let (hn, _, qu, qv) = update_cell(
                            ctx.h[cell],
                            ctx.hu[cell],
                            ctx.hv[cell],
                            r,
                            &w,
                            &e,
                            &so,
                            &no,
                        );
                        (h_new[local], hu_new[local], hv_new[local]) = (hn, qu, qv);
                    }
                }
                s.worst = first_minimum(h_new, offset);
            },
        );
        self.worst()
    }

    /// The smallest new thickness over the bands, combined in band order.
    fn worst(&self) -> (f64, usize) {
        let mut worst = (f64::INFINITY, 0usize);
        for s in &self.scratch {
            if s.worst.0 < worst.0 {
                worst = s.worst;
            }
        }
        worst
    }
}

impl<L: BasalFriction> Stage<Raster2d, State2d> for HydrostaticStep2d<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    fn apply(&mut self, raster: &Raster2d, dt: f64, state: &mut State2d) -> Result<(), StageError> {
        let mut worst = self.update_pass(raster, dt, state);
        if worst.0 < 0.0 {
            worst = self.limited_pass(raster, dt, state);
        }
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                cell: worst.1,
                h: worst.0,
            });
        }
        // Round-off below zero, kept for the test above, is clipped now.
        if worst.0 < 0.0 {
            for h in &mut self.h_new {
                if *h < 0.0 {
                    *h = 0.0;
                }
            }
        }
        std::mem::swap(&mut state.h, &mut self.h_new);
        std::mem::swap(&mut state.hu, &mut self.hu_new);
        std::mem::swap(&mut state.hv, &mut self.hv_new);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Coordinates, RasterSpec, Sides};
    use crate::physics::rheology::Coulomb;

    /// Thin fast layers next to dry cells on a bumpy plane: cells that drain in one step
    /// in every band, at the raster's edges and at the edges between bands.
    fn draining_case(nx: usize, ny: usize) -> (Raster2d, State2d) {
        let spec = RasterSpec {
            nx,
            ny,
            x_min: 0.0,
            x_max: 1.0,
            y_min: 0.0,
            y_max: 1.0,
            sides: Sides {
                west: BoundaryKind::Wall,
                east: BoundaryKind::Outflow,
                south: BoundaryKind::Outflow,
                north: BoundaryKind::Wall,
            },
            coordinates: Coordinates::Local,
            slope_deg: 25.0,
        };
        let bed = (0..nx * ny)
            .map(|k| 0.01 * ((k * 7919) % 13) as f64)
            .collect();
        let raster = Raster2d::new(spec, bed).unwrap();
        let wet = |k: usize| !(k * 31 + k / nx).is_multiple_of(5);
        let h = (0..nx * ny)
            .map(|k| {
                if wet(k) {
                    1e-3 * (1 + k % 3) as f64
                } else {
                    0.0
                }
            })
            .collect();
        let u: Vec<f64> = (0..nx * ny).map(|k| 3.0 - (k % 7) as f64).collect();
        let v: Vec<f64> = (0..nx * ny).map(|k| (k % 5) as f64 - 2.0).collect();
        (raster, State2d::from_velocities(h, &u, &v))
    }

    #[test]
    fn limited_pass_around_draining_cells_has_the_bits_of_a_full_limited_pass() {
        let (nx, ny) = (23, 2 * BAND_ROWS + 5);
        let (raster, state) = draining_case(nx, ny);
        let law = Coulomb { mu: 0.3 };
        let dt = 0.2 * raster.dx();
        for threads in [1, 2] {
            let workers = Workers::new(threads).unwrap();
            let mut step = HydrostaticStep2d::new(law, &raster, workers);
            let worst = step.update_pass(&raster, dt, &state);
            assert!(worst.0 < 0.0, "the case drains");
            let draining = step.drain.iter().filter(|&&t| t != 1.0).count();
            assert!(
                draining > 10 && draining < nx * ny / 2,
                "{draining} draining cells"
            );
            let worst = step.limited_pass(&raster, dt, &state);
            // Reference: every cell from its four limited faces.
            let ctx = Ctx {
                law,
                raster: &raster,
                h: &state.h,
                hu: &state.hu,
                hv: &state.hv,
                nx,
                ny,
                dt,
                theta: Some(step.drain.as_slice()),
            };
            let r = (dt / raster.dx(), dt / raster.dy());
            let mut reference = (f64::INFINITY, 0usize);
            for j in 0..ny {
                for i in 0..nx {
                    let [w, e, so, no] = ctx.limited_faces(i, j);
                    let cell = j * nx + i;
                    let (hn, _, qu, qv) = update_cell(
                        state.h[cell],
                        state.hu[cell],
                        state.hv[cell],
                        r,
                        &w,
                        &e,
                        &so,
                        &no,
                    );
                    let got = (step.h_new[cell], step.hu_new[cell], step.hv_new[cell]);
                    assert_eq!(
                        (got.0.to_bits(), got.1.to_bits(), got.2.to_bits()),
                        (hn.to_bits(), qu.to_bits(), qv.to_bits()),
                        "cell ({i}, {j}), {threads} thread(s)"
                    );
                    if hn < reference.0 {
                        reference = (hn, cell);
                    }
                }
            }
            assert_eq!(worst, reference);
        }
    }
}
