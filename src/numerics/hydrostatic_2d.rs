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
//! data. Memory: the new state (3 values per cell), the draining factors (1, used only
//! when a cell would empty) and two rows of y-faces per band.
//!
//! The CFL step: with the per-cell signal speed s = max(|u|, |v|) + √(g_n h) and
//! Δt = CFL · min(Δx, Δy)/s, Δt (s_x/Δx + s_y/Δy) ≤ 2 CFL; the unsplit update keeps
//! h ≥ 0 for CFL ≤ ½ (the limiter and the run loop's retry catch the rest).

use super::face::{
    drained_fraction, interface_with_transverse_drive, layer_momentum_flux, mass_flux,
    transverse_flux, Side,
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

/// A cell as a face sees it: the side along the face's normal, the tangential
/// velocity, and the tangential drive u_t/Δt − g_n ∂_t(h + z) of the cell (for the
/// disk threshold of ΔC, [`super::face::interface_with_transverse_drive`]).
type FaceSide = (Side, f64, f64);

/// One band's scratch: the y-faces under and over the current row, and the smallest
/// new thickness of the band with its cell.
#[derive(Debug, Clone)]
struct BandScratch {
    below: Vec<FaceFlux>,
    above: Vec<FaceFlux>,
    /// The sides that the y-faces see in the rows under and over them (each row's
    /// computed once per sweep).
    lower: Vec<FaceSide>,
    upper: Vec<FaceSide>,
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
            lower: vec![(Side::monolayer(0.0, 0.0, 0.0, 0.0), 0.0, 0.0); nx],
            upper: vec![(Side::monolayer(0.0, 0.0, 0.0, 0.0), 0.0, 0.0); nx],
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
                    + (s.lower.len() + s.upper.len()) * std::mem::size_of::<FaceSide>()
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

impl<'a, L: BasalFriction> Ctx<'a, L> {
    /// The context of one pass over `state` on `raster` with step `dt`, reading the
    /// draining factors `theta` in the limited pass.
    fn new(
        law: L,
        raster: &'a Raster2d,
        state: &'a State2d,
        dt: f64,
        theta: Option<&'a [f64]>,
    ) -> Self {
        Ctx {
            law,
            raster,
            h: &state.h,
            hu: &state.hu,
            hv: &state.hv,
            nx: raster.nx(),
            ny: raster.ny(),
            dt,
            theta,
        }
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
        let eta = self.h[j * self.nx + i] + self.raster.z[self.raster.ghost_index(i + 1, j + 1)];
        let (k, n, d) = if along_x {
            (i, self.nx, self.raster.dx())
        } else {
            (j, self.ny, self.raster.dy())
        };
        let (mut lo, mut hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
        // A wall neighbour (nodata) is an edge of the raster: one-sided there.
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
        if lo == hi {
            return t / self.dt;
        }
        let (e_lo, e_hi) = if along_x {
            (self.surface_seen(lo, j, eta), self.surface_seen(hi, j, eta))
        } else {
            (self.surface_seen(i, lo, eta), self.surface_seen(i, hi, eta))
        };
        t / self.dt - self.raster.g_n * (e_hi - e_lo) / ((hi - lo) as f64 * d)
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
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hu[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        let v = velocity(h, self.hv[cell]);
        (side, v, self.tangential_drive(cell % self.nx, j, v, false))
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
        let h = self.h[cell];
        let side = Side::monolayer(
            h,
            sign * self.hv[cell],
            self.raster.b_ghost[g],
            self.raster.z[g],
        );
        let u = velocity(h, self.hu[cell]);
        (side, u, self.tangential_drive(i, cell / self.nx, u, true))
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
    fn y_sides(&self, r: usize, row: &mut [FaceSide]) {
        for (i, side) in row.iter_mut().enumerate() {
            *side = self.y_side(i, r);
        }
    }

    /// The y-faces between ghost-inclusive rows `r` and `r + 1` from their sides.
    fn y_faces<const WALLS: bool>(
        &self,
        r: usize,
        lower: &[FaceSide],
        upper: &[FaceSide],
        row: &mut [FaceFlux],
    ) {
        let (g_n, dy) = (self.raster.g_n, self.raster.dy());
        let cell = |r: usize, i: usize| (r >= 1 && r <= self.ny).then(|| (r - 1) * self.nx + i);
        for (i, ((f, lo), hi)) in row.iter_mut().zip(lower).zip(upper).enumerate() {
            if WALLS {
                let (wl, wr) = (self.y_wall(i, r), self.y_wall(i, r + 1));
                if wl || wr {
                    *f = wall_face(&self.law, *lo, *hi, wl, wr, g_n, dy, self.dt);
                    continue;
                }
            }
            *f = face_flux(&self.law, lo, hi, g_n, dy, self.dt);
            if self.theta.is_some() {
                *f = f.drained(self.donor_theta(f.h, cell(r, i), cell(r + 1, i)));
            }
        }
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
            let x_cell = |c: usize| (c >= 1 && c <= nx).then(|| j * nx + c - 1);
            let x_face = |left: FaceSide, right: FaceSide, c: usize| {
                if WALLS {
                    let (wl, wr) = (self.x_wall(c, j), self.x_wall(c + 1, j));
                    if wl || wr {
                        return wall_face(&self.law, left, right, wl, wr, g_n, dx, self.dt);
                    }
                }
                let f = face_flux(&self.law, &left, &right, g_n, dx, self.dt);
                if self.theta.is_none() {
                    f
                } else {
                    f.drained(self.donor_theta(f.h, x_cell(c), x_cell(c + 1)))
                }
            };
            let mut left = self.x_side(0, j);
            let mut right = self.x_side(1, j);
            let mut west = x_face(left, right, 0);
            for i in 0..nx {
                (left, right) = (right, self.x_side(i + 2, j));
                let east = x_face(left, right, i + 1);
                cell(i, j, &west, &east, &s.below[i], &s.above[i]);
                west = east;
            }
            std::mem::swap(&mut s.below, &mut s.above);
        }
    }
}

/// The fluxes of one face with sides `l`, `r` along its normal (velocities normal to
/// the face), their tangential velocities and drives; zero where nothing crosses. The
/// 1-D monolayer face ([`super::face::monolayer_fluxes`]) with the disk threshold of
/// ΔC, plus the tangential flux.
#[inline(always)]
fn face_flux<L: BasalFriction>(
    law: &L,
    &(l, t_l, d_l): &FaceSide,
    &(r, t_r, d_r): &FaceSide,
    g_n: f64,
    d: f64,
    dt: f64,
) -> FaceFlux {
    // The threshold of the line's faces (`BasalFriction::face_mu`: μ(I) from the cells'
    // own speeds |(u, v)| and depths), so that a run invariant along one axis is the
    // line's bit for bit (hypot(u, 0) = |u|).
    let (cell_l, cell_r) = ((l.u.hypot(t_l), l.h), (r.u.hypot(t_r), r.h));
    let mu_of = |speed: f64, h: f64| law.face_mu(cell_l, cell_r, speed, h, g_n);
    match interface_with_transverse_drive(mu_of, l, r, 0.0, (d_l, d_r), g_n, d, dt) {
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
    l: FaceSide,
    r: FaceSide,
    wall_l: bool,
    wall_r: bool,
    g_n: f64,
    d: f64,
    dt: f64,
) -> FaceFlux {
    let mirror = |(s, t, d): FaceSide| {
        (
            Side {
                u: -s.u,
                u_base: -s.u_base,
                ..s
            },
            t,
            d,
        )
    };
    let (l, r) = match (wall_l, wall_r) {
        (true, true) => return FaceFlux::default(),
        (true, false) => (mirror(r), r),
        (false, true) => (l, mirror(l)),
        (false, false) => (l, r),
    };
    let f = face_flux(law, &l, &r, g_n, d, dt);
    FaceFlux {
        h: 0.0,
        qt: 0.0,
        ..f
    }
}

impl<L: BasalFriction> HydrostaticStep2d<L> {
    /// One update pass (fluxes, limited by `theta` if given) into the new-state
    /// buffers; returns the smallest new thickness and its cell, first in cell order.
    fn update_pass(
        &mut self,
        raster: &Raster2d,
        dt: f64,
        state: &State2d,
        limited: bool,
    ) -> (f64, usize) {
        if raster.walls().is_empty() {
            self.update_pass_with::<false>(raster, dt, state, limited)
        } else {
            self.update_pass_with::<true>(raster, dt, state, limited)
        }
    }

    /// [`Self::update_pass`] with (`WALLS`) or without the test for wall cells.
    fn update_pass_with<const WALLS: bool>(
        &mut self,
        raster: &Raster2d,
        dt: f64,
        state: &State2d,
        limited: bool,
    ) -> (f64, usize) {
        let nx = raster.nx();
        let (rx, ry) = (dt / raster.dx(), dt / raster.dy());
        let ctx = Ctx::new(
            self.law,
            raster,
            state,
            dt,
            limited.then_some(self.drain.as_slice()),
        );
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
                let mut worst = (f64::INFINITY, 0usize);
                ctx.sweep::<WALLS, _>(k, s, |i, j, w, e, so, no| {
                    let cell = j * nx + i;
                    let local = cell - offset;
                    let h_old = ctx.h[cell];
                    // The x and y parts are summed before they are subtracted: a sum of
                    // two terms does not depend on their order, so a state symmetric
                    // under x ↔ y (Δx = Δy) stays symmetric to the bit.
                    let hn = h_old - (rx * (e.h - w.h) + ry * (no.h - so.h));
                    if hn < worst.0 {
                        worst = (hn, cell);
                    }
                    // Clip round-off below zero; `f64::max` would also turn a NaN into 0.
                    let h = if hn < 0.0 { 0.0 } else { hn };
                    let drained = drained_fraction(h, h_old);
                    let source_x = e.share_l + w.share_r - (e.body_l + w.body_r) * drained;
                    let source_y = no.share_l + so.share_r - (no.body_l + so.body_r) * drained;
                    let qu = ctx.hu[cell] - (rx * (e.qn - w.qn + source_x) + ry * (no.qt - so.qt));
                    let qv = ctx.hv[cell] - (rx * (e.qt - w.qt) + ry * (no.qn - so.qn + source_y));
                    h_new[local] = h;
                    (hu_new[local], hv_new[local]) = if h <= H_DRY { (0.0, 0.0) } else { (qu, qv) };
                    // The unclipped value for the positivity test.
                    if hn < 0.0 {
                        h_new[local] = hn;
                    }
                });
                s.worst = worst;
            },
        );
        self.worst()
    }

    /// The draining factors θ = min(1, h/(outflow over the four faces)).
    fn drain_pass(&mut self, raster: &Raster2d, dt: f64, state: &State2d) {
        if raster.walls().is_empty() {
            self.drain_pass_with::<false>(raster, dt, state);
        } else {
            self.drain_pass_with::<true>(raster, dt, state);
        }
    }

    /// [`Self::drain_pass`] with (`WALLS`) or without the test for wall cells.
    fn drain_pass_with<const WALLS: bool>(&mut self, raster: &Raster2d, dt: f64, state: &State2d) {
        let nx = raster.nx();
        let (rx, ry) = (dt / raster.dx(), dt / raster.dy());
        let ctx = Ctx::new(self.law, raster, state, dt, None);
        self.workers.bands1(
            BAND_ROWS * nx,
            &mut self.drain,
            &mut self.scratch,
            |k, drain, s| {
                let offset = k * BAND_ROWS * nx;
                ctx.sweep::<WALLS, _>(k, s, |i, j, w, e, so, no| {
                    let cell = j * nx + i;
                    let need = rx * (e.h.max(0.0) + (-w.h).max(0.0))
                        + ry * (no.h.max(0.0) + (-so.h).max(0.0));
                    let h = ctx.h[cell];
                    drain[cell - offset] = if need > h { h.max(0.0) / need } else { 1.0 };
                });
            },
        );
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
        let mut worst = self.update_pass(raster, dt, state, false);
        if worst.0 < 0.0 {
            self.drain_pass(raster, dt, state);
            worst = self.update_pass(raster, dt, state, true);
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
