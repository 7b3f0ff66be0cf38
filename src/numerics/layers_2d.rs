//! Step 1 of the multilayer model on a raster: the hyperbolic (hydrostatic) problem of
//! `hydrostatic.rs` for N ≥ 1 layers in two horizontal dimensions,
//!
//!   ∂_t h + ∂_x(hū) + ∂_y(hv̄) = 0,
//!   ∂_t(hu_α) + ∂_x(hu_α²) + ∂_y(hu_α v_α) + g_n h ∂_x(h + z)
//!       = (u_{α+1/2} G_{α+1/2} − u_{α−1/2} G_{α−1/2})/l_α,
//!   ∂_t(hv_α) + ∂_x(hu_α v_α) + ∂_y(hv_α²) + g_n h ∂_y(h + z)
//!       = (v_{α+1/2} G_{α+1/2} − v_{α−1/2} G_{α−1/2})/l_α,
//!
//! with the mass exchange G_{α+1/2} = Σ_{β≤α} l_β ∇·(h((u, v)_β − (ū, v̄)))
//! (Fernández-Nieto et al. 2016, eq. 19, in two dimensions; Escalante et al. 2023,
//! eq. 5), by unsplit finite volumes:
//!
//!   U_ij ← U_ij − Δt/Δx (𝓕_{i+1/2,j} − 𝓕_{i−1/2,j} + 𝓢ˣ + 𝓑ˣ)
//!               − Δt/Δy (𝓖_{i,j+1/2} − 𝓖_{i,j−1/2} + 𝓢ʸ + 𝓑ʸ).
//!
//! Nothing of the layered numerics is written twice: every x-face and every y-face is
//! the line's face ([`super::face::interface_with_zoned_transverse_drive`], the kernel
//! of `hydrostatic.rs` and `hydrostatic_2d.rs`) along its normal, with
//! - the normal components as the line's u_α (ū, the shear term 3 Σ l_α (u_α − ū)² of
//!   the wave speed and the basal u_1 of ΔC from them), each layer's normal momentum
//!   flux the line's [`super::face::layer_momentum_flux`];
//! - the tangential component of each layer carried by that layer's upwinded flux
//!   ([`super::face::transverse_flux`] with the layer's normal velocity);
//! - the exchange term 𝓑 of the line (`super::hydrostatic::carried_exchange_terms`)
//!   for both components with the same ΔG, the jump of the normal discharges; each
//!   cell takes its own-depth share of it, as on the line;
//! - ΔC's friction a disk against the bottom layer's drive (normal and tangential:
//!   the static threshold of the viscous step's vector friction).
//!
//! N = 1 is the monolayer face of `hydrostatic_2d.rs` (the cells' own μ at the face,
//! no exchange). The update, the near-dry rule and the draining-time limiter
//! (Bollermann et al. 2013) are those of the line, with each cell's x and y parts
//! summed before they are subtracted (as `hydrostatic_2d.rs` does): on a state that
//! does not depend on y every y-face carries exactly nothing, and each row is the
//! line's step to the bit (`tests/multilayer_2d.rs`).
//!
//! Scope: order 1 in the Cartesian and local frames over a raster without wall cells
//! (the scenario validation refuses the others with a message naming the key).
//!
//! Work and threads: the step runs in row bands (`Raster2d::bands`) on the run's
//! [`Workers`]. A first pass computes every cell's view (layer velocities, means,
//! shears, drives), ghosts included; a band then computes the y-faces under and over
//! each of its rows and the x-faces along it into its thread's scratch and writes its
//! cells of the new state. A y-face on the edge between two bands is computed by both
//! with the same operations on the same data, so the bits do not depend on the number
//! of threads. If a new thickness is negative, a second sweep recomputes the faces
//! with each flux scaled by the draining factor of its donor (a flux times 1 is the
//! flux). Memory per cell: the view (10 + 2N values), the new state (1 + 2N) and the
//! draining factor (1); per thread, three rows of faces (7 + 4N values per face).

use super::face::{
    drained_fraction, interface_with_zoned_transverse_drive, layer_momentum_flux, mass_flux,
    transverse_flux, Side,
};
use super::hydrostatic::{carried_exchange_terms, exchange_terms, Fractions};
use super::workers::{Disjoint, Workers};
use super::{Stage, StageError, StepClock};
use crate::grid::{BoundaryKind, Coordinates, Raster2d};
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{sheared_celerity, velocity, H_DRY};
use crate::state::layered_raster::LayeredRaster;
use std::sync::Mutex;

/// Offsets in a cell's view: thickness, √h, bed, potential, the mean velocities
/// (ū, v̄), the shear terms of the wave speeds along x and y, the bottom layer's drives
/// along x and y (u_1/Δt − g_n ∂_x(h + z), v_1/Δt − g_n ∂_y(h + z)), then u_α and v_α.
const H: usize = 0;
const SQRT_H: usize = 1;
const B: usize = 2;
const Z: usize = 3;
const MEAN_U: usize = 4;
const MEAN_V: usize = 5;
const SHEAR_X: usize = 6;
const SHEAR_Y: usize = 7;
const DRIVE_X: usize = 8;
const DRIVE_Y: usize = 9;
const U: usize = 10;

/// Offsets in a face's record: mass flux, the pressure sources of the lower- and
/// higher-index cells and their gravity parts, the fractions of 𝓑 they take, then per
/// layer the normal momentum flux, the tangential flux and the exchange terms of the
/// normal and tangential components.
const F_H: usize = 0;
const SHARE_L: usize = 1;
const SHARE_R: usize = 2;
const BODY_L: usize = 3;
const BODY_R: usize = 4;
const EX_L: usize = 5;
const EX_R: usize = 6;
const F_N: usize = 7;

/// One thread's faces: the y-faces under and over the current row and its x-faces.
#[derive(Debug, Clone)]
struct Scratch {
    below: Vec<f64>,
    above: Vec<f64>,
    across: Vec<f64>,
}

/// The N-layer hyperbolic step on a raster, generic over the basal friction law (ΔC).
#[derive(Debug)]
pub struct LayersStep2d<L: BasalFriction> {
    law: L,
    layers: usize,
    workers: Workers,
    /// l_α, 1/l_α and Σ_{β≤α} l_β.
    l: Vec<f64>,
    inv_l: Vec<f64>,
    l_below: Vec<f64>,
    /// Views of the ghost-inclusive cells ((nx + 2)·(ny + 2), stride 10 + 2N).
    views: Vec<f64>,
    h_new: Vec<f64>,
    hu_new: Vec<f64>,
    hv_new: Vec<f64>,
    /// Draining factors per cell (1 where the cell does not empty).
    drain: Vec<f64>,
    /// Per band: the smallest new thickness and its cell (first in cell order).
    band_worst: Vec<(f64, usize)>,
    bands: Vec<u32>,
    scratch: Vec<Mutex<Scratch>>,
}

/// What a sweep reads: the raster, the views, the law, Δt.
struct Sweep<'a, L: BasalFriction> {
    raster: &'a Raster2d,
    law: L,
    n: usize,
    frac: Fractions<'a>,
    views: &'a [f64],
    dt: f64,
}

impl<L: BasalFriction> LayersStep2d<L> {
    /// The step for layer fractions `l` on `raster`, on the threads of `workers`.
    pub fn new(law: L, raster: &Raster2d, l: &[f64], workers: Workers) -> Self {
        let n = l.len();
        assert!(n >= 1);
        assert!(
            raster.coordinates() != Coordinates::BedNormal && raster.walls().is_empty(),
            "the layered raster step runs in the Cartesian and local frames without wall cells"
        );
        let (nx, ny) = (raster.nx(), raster.ny());
        let mut inv_l = vec![0.0; n];
        let mut l_below = vec![0.0; n];
        let mut sum = 0.0;
        for ((inv, below), l) in inv_l.iter_mut().zip(&mut l_below).zip(l) {
            *inv = 1.0 / l;
            sum += l;
            *below = sum;
        }
        let face = 7 + 4 * n;
        let scratch = Scratch {
            below: vec![0.0; nx * face],
            above: vec![0.0; nx * face],
            across: vec![0.0; (nx + 1) * face],
        };
        let threads = workers.threads();
        LayersStep2d {
            law,
            layers: n,
            workers,
            l: l.to_vec(),
            inv_l,
            l_below,
            views: vec![0.0; (nx + 2) * (ny + 2) * (10 + 2 * n)],
            h_new: vec![0.0; nx * ny],
            hu_new: vec![0.0; nx * ny * n],
            hv_new: vec![0.0; nx * ny * n],
            drain: vec![1.0; nx * ny],
            band_worst: vec![(f64::INFINITY, 0); raster.bands()],
            bands: (0..raster.bands() as u32).collect(),
            scratch: (0..threads).map(|_| Mutex::new(scratch.clone())).collect(),
        }
    }

    /// Bytes the step holds per cell of the raster (views, new state, draining
    /// factors; the per-thread scratch spread over the cells).
    pub fn bytes_per_cell(&self) -> f64 {
        let cells = self.h_new.len() as f64;
        let scratch: usize = self
            .scratch
            .iter()
            .map(|s| {
                let s = s.lock().unwrap();
                s.below.len() + s.above.len() + s.across.len()
            })
            .sum();
        let values = self.views.len()
            + self.h_new.len()
            + self.hu_new.len()
            + self.hv_new.len()
            + self.drain.len()
            + scratch;
        8.0 * values as f64 / cells
    }

    /// The views of every cell, then those of the ghost ring.
    fn fill_views(&mut self, raster: &Raster2d, dt: f64, state: &LayeredRaster) {
        let (nx, ny, n) = (raster.nx(), raster.ny(), self.layers);
        let stride = 10 + 2 * n;
        let l = &self.l;
        let views = Disjoint::new(&mut self.views);
        self.workers.tiles(&self.bands, |_, band| {
            let mut view = [0.0; 64];
            let mut big = Vec::new();
            let buf: &mut [f64] = if stride <= 64 {
                &mut view[..stride]
            } else {
                big.resize(stride, 0.0);
                &mut big
            };
            for j in raster.band_rows(band) {
                for i in 0..nx {
                    cell_view(raster, state, l, (i, j), dt, buf);
                    let at = raster.ghost_index(i + 1, j + 1) * stride;
                    for (k, v) in buf.iter().enumerate() {
                        // SAFETY: each band writes the views of its own rows.
                        unsafe { views.set(at + k, *v) };
                    }
                }
            }
        });
        // The ghost ring: the edge cell with the boundary's sign on the normal
        // discharges, over the ghost bed; its tangential drive is the edge cell's.
        let sides = raster.sides();
        let sign = |kind: BoundaryKind| match kind {
            BoundaryKind::Wall => -1.0,
            BoundaryKind::Outflow => 1.0,
        };
        let mut ghost = vec![0.0; stride];
        for j in 0..ny {
            for (c, i, s) in [(0, 0, sign(sides.west)), (nx + 1, nx - 1, sign(sides.east))] {
                ghost_view(raster, state, l, (i, j), (s, 1.0), &mut ghost);
                let edge = raster.ghost_index(i + 1, j + 1) * stride;
                ghost[DRIVE_Y] = self.views[edge + DRIVE_Y];
                let at = raster.ghost_index(c, j + 1) * stride;
                ghost[B] = raster.b_ghost[at / stride];
                ghost[Z] = raster.z[at / stride];
                self.views[at..at + stride].copy_from_slice(&ghost);
            }
        }
        for i in 0..nx {
            for (r, j, s) in [
                (0, 0, sign(sides.south)),
                (ny + 1, ny - 1, sign(sides.north)),
            ] {
                ghost_view(raster, state, l, (i, j), (1.0, s), &mut ghost);
                let edge = raster.ghost_index(i + 1, j + 1) * stride;
                ghost[DRIVE_X] = self.views[edge + DRIVE_X];
                let at = raster.ghost_index(i + 1, r) * stride;
                ghost[B] = raster.b_ghost[at / stride];
                ghost[Z] = raster.z[at / stride];
                self.views[at..at + stride].copy_from_slice(&ghost);
            }
        }
    }

    /// One sweep over the bands: the faces, the new state and (unlimited) the
    /// draining factors and each band's smallest new thickness.
    fn sweep(&mut self, raster: &Raster2d, dt: f64, state: &LayeredRaster, limited: bool) {
        let n = self.layers;
        let sweep = Sweep {
            raster,
            law: self.law,
            n,
            frac: Fractions {
                l: &self.l,
                inv: &self.inv_l,
                below: &self.l_below,
            },
            views: &self.views,
            dt,
        };
        let (nx, face) = (raster.nx(), 7 + 4 * n);
        let r = (dt / raster.dx(), dt / raster.dy());
        let h_new = Disjoint::new(&mut self.h_new);
        let hu_new = Disjoint::new(&mut self.hu_new);
        let hv_new = Disjoint::new(&mut self.hv_new);
        let worst = Disjoint::new(&mut self.band_worst);
        let drain_out = Disjoint::new(&mut self.drain);
        let drain = |cell: Option<usize>| match cell {
            // SAFETY: the limited sweep only reads the factors.
            Some(c) if limited => unsafe { drain_out.get(c) },
            _ => 1.0,
        };
        let scratch = &self.scratch;
        self.workers.tiles(&self.bands, |thread, band| {
            let mut s = scratch[thread].lock().unwrap();
            let Scratch {
                below,
                above,
                across,
            } = &mut *s;
            let rows = raster.band_rows(band);
            let mut band_worst = (f64::INFINITY, 0usize);
            sweep.y_faces(rows.start, below);
            if limited {
                sweep.limit_y(rows.start, below, &drain);
            }
            for j in rows {
                sweep.y_faces(j + 1, above);
                sweep.x_faces(j, across);
                if limited {
                    sweep.limit_y(j + 1, above, &drain);
                    sweep.limit_x(j, across, &drain);
                }
                for i in 0..nx {
                    let cell = j * nx + i;
                    let w = &across[i * face..(i + 1) * face];
                    let e = &across[(i + 1) * face..(i + 2) * face];
                    let so = &below[i * face..(i + 1) * face];
                    let no = &above[i * face..(i + 1) * face];
                    let h_old = state.h[cell];
                    let hn = h_old - (r.0 * (e[F_H] - w[F_H]) + r.1 * (no[F_H] - so[F_H]));
                    if hn < band_worst.0 {
                        band_worst = (hn, cell);
                    }
                    let h = if hn < 0.0 { 0.0 } else { hn };
                    // SAFETY: each band writes its own cells.
                    unsafe {
                        h_new.set(cell, h);
                        if !limited {
                            drain_out.set(cell, draining_factor(h_old, r, [w, e, so, no]));
                        }
                    }
                    let drained = drained_fraction(h, h_old);
                    let source_x = e[SHARE_L] + w[SHARE_R] - (e[BODY_L] + w[BODY_R]) * drained;
                    let source_y = no[SHARE_L] + so[SHARE_R] - (no[BODY_L] + so[BODY_R]) * drained;
                    let (qu, qv) = (&state.hu[cell * n..], &state.hv[cell * n..]);
                    for a in 0..n {
                        let (fn_, ft, en, et) =
                            (F_N + a, F_N + n + a, F_N + 2 * n + a, F_N + 3 * n + a);
                        let (u, v) = if h <= H_DRY {
                            (0.0, 0.0)
                        } else if n == 1 {
                            (
                                qu[a]
                                    - (r.0 * (e[fn_] - w[fn_] + source_x)
                                        + r.1 * (no[ft] - so[ft])),
                                qv[a]
                                    - (r.0 * (e[ft] - w[ft])
                                        + r.1 * (no[fn_] - so[fn_] + source_y)),
                            )
                        } else {
                            let ex_nx = e[EX_L] * e[en] + w[EX_R] * w[en];
                            let ex_tx = e[EX_L] * e[et] + w[EX_R] * w[et];
                            let ex_ny = no[EX_L] * no[en] + so[EX_R] * so[en];
                            let ex_ty = no[EX_L] * no[et] + so[EX_R] * so[et];
                            (
                                qu[a]
                                    - (r.0 * (e[fn_] - w[fn_] + source_x + ex_nx)
                                        + r.1 * (no[ft] - so[ft] + ex_ty)),
                                qv[a]
                                    - (r.0 * (e[ft] - w[ft] + ex_tx)
                                        + r.1 * (no[fn_] - so[fn_] + source_y + ex_ny)),
                            )
                        };
                        // SAFETY: each band writes its own cells.
                        unsafe {
                            hu_new.set(cell * n + a, u);
                            hv_new.set(cell * n + a, v);
                        }
                    }
                }
                std::mem::swap(below, above);
            }
            // SAFETY: one entry per band.
            unsafe { worst.set(band, band_worst) };
        });
    }

    /// The smallest new thickness and its cell: the first minimum in cell order.
    fn worst(&self) -> (f64, usize) {
        let mut worst = (f64::INFINITY, 0usize);
        for &w in &self.band_worst {
            if w.0 < worst.0 {
                worst = w;
            }
        }
        worst
    }
}

impl<L: BasalFriction> Sweep<'_, L> {
    #[inline(always)]
    fn view(&self, g: usize) -> &[f64] {
        let stride = 10 + 2 * self.n;
        &self.views[g * stride..(g + 1) * stride]
    }

    /// The y-faces of ghost-inclusive face row `r` (between rows r − 1 and r of the
    /// raster, i.e. ghost-inclusive rows r and r + 1).
    fn y_faces(&self, r: usize, out: &mut [f64]) {
        let (nx, face) = (self.raster.nx(), 7 + 4 * self.n);
        for i in 0..nx {
            let lo = self.view(self.raster.ghost_index(i + 1, r));
            let hi = self.view(self.raster.ghost_index(i + 1, r + 1));
            self.face(lo, hi, false, &mut out[i * face..(i + 1) * face]);
        }
    }

    /// The x-faces of row `j` (face k between ghost-inclusive columns k and k + 1).
    fn x_faces(&self, j: usize, out: &mut [f64]) {
        let (nx, face) = (self.raster.nx(), 7 + 4 * self.n);
        for k in 0..=nx {
            let lo = self.view(self.raster.ghost_index(k, j + 1));
            let hi = self.view(self.raster.ghost_index(k + 1, j + 1));
            self.face(lo, hi, true, &mut out[k * face..(k + 1) * face]);
        }
    }

    /// Scales the fluxes of y-face row `r` by the draining factors of their donors.
    fn limit_y(&self, r: usize, out: &mut [f64], drain: &impl Fn(Option<usize>) -> f64) {
        let (nx, ny, face) = (self.raster.nx(), self.raster.ny(), 7 + 4 * self.n);
        for i in 0..nx {
            let f = &mut out[i * face..(i + 1) * face];
            let donor = if f[F_H] > 0.0 { r } else { r + 1 };
            let cell = (donor >= 1 && donor <= ny).then(|| (donor - 1) * nx + i);
            self.scale(f, drain(cell));
        }
    }

    /// Scales the fluxes of the x-faces of row `j` by the draining factors of their
    /// donors.
    fn limit_x(&self, j: usize, out: &mut [f64], drain: &impl Fn(Option<usize>) -> f64) {
        let (nx, face) = (self.raster.nx(), 7 + 4 * self.n);
        for k in 0..=nx {
            let f = &mut out[k * face..(k + 1) * face];
            let donor = if f[F_H] > 0.0 { k } else { k + 1 };
            let cell = (donor >= 1 && donor <= nx).then(|| j * nx + donor - 1);
            self.scale(f, drain(cell));
        }
    }

    /// The mass flux and every layer's momentum fluxes times θ (the line's
    /// `limit_draining`: sources and exchange terms are not scaled).
    #[inline(always)]
    fn scale(&self, f: &mut [f64], theta: f64) {
        f[F_H] *= theta;
        for q in &mut f[F_N..F_N + 2 * self.n] {
            *q *= theta;
        }
    }

    /// One face between the views `lo` and `hi` (lower and higher index), an x-face
    /// (`along_x`: normal velocity u) or a y-face (normal v), written into `out`.
    #[inline(always)]
    fn face(&self, lo: &[f64], hi: &[f64], along_x: bool, out: &mut [f64]) {
        let n = self.n;
        let g_n = self.raster.g_n;
        let (mean, shear, drive_t, un, ut) = if along_x {
            (MEAN_U, SHEAR_X, DRIVE_Y, U, U + n)
        } else {
            (MEAN_V, SHEAR_Y, DRIVE_X, U + n, U)
        };
        let d = if along_x {
            self.raster.dx()
        } else {
            self.raster.dy()
        };
        let side = |v: &[f64]| Side {
            h: v[H],
            u: v[mean],
            b: v[B],
            z: v[Z],
            shear: v[shear],
            u_base: v[un],
            sqrt_h: v[SQRT_H],
        };
        let (ls, rs) = (side(lo), side(hi));
        let law = self.law;
        let found = if n == 1 {
            // The monolayer face: the cells' own μ at their speeds |(u, v)|.
            let cell_l = (lo[U].hypot(lo[U + 1]), lo[H]);
            let cell_r = (hi[U].hypot(hi[U + 1]), hi[H]);
            let mu_of = |speed: f64, h: f64, _: f64| law.face_mu(cell_l, cell_r, speed, h, g_n);
            let drives = (lo[drive_t], hi[drive_t]);
            interface_with_zoned_transverse_drive(mu_of, ls, rs, 0.0, drives, g_n, d, self.dt)
        } else {
            let mu_of = |speed: f64, h: f64, _: f64| law.mu(speed, h, g_n * h);
            let drives = (lo[drive_t], hi[drive_t]);
            interface_with_zoned_transverse_drive(mu_of, ls, rs, 0.0, drives, g_n, d, self.dt)
        };
        let Some((c, sl, sr)) = found else {
            out.fill(0.0);
            return;
        };
        out[F_H] = mass_flux(&c, sl, sr);
        out[SHARE_L] = c.share_left;
        out[SHARE_R] = c.share_right;
        out[BODY_L] = c.body_left;
        out[BODY_R] = c.body_right;
        out[EX_L] = c.exchange_left;
        out[EX_R] = c.exchange_right;
        let (un_l, un_r) = (&lo[un..un + n], &hi[un..un + n]);
        let (ut_l, ut_r) = (&lo[ut..ut + n], &hi[ut..ut + n]);
        let (fluxes, exchange) = out[F_N..].split_at_mut(2 * n);
        let seen = |u: f64, at_rest: bool| if at_rest { 0.0 } else { u };
        for a in 0..n {
            let (ul, ur) = (
                seen(un_l[a], c.left_at_rest),
                seen(un_r[a], c.right_at_rest),
            );
            let (tl, tr) = (
                seen(ut_l[a], c.left_at_rest),
                seen(ut_r[a], c.right_at_rest),
            );
            fluxes[a] = layer_momentum_flux(&c, c.h_minus, c.h_plus, ul, ur);
            let (lu, ru) = (Side { u: ul, ..sl }, Side { u: ur, ..sr });
            fluxes[n + a] = transverse_flux(&c, lu, ru, tl, tr);
        }
        if n == 1 {
            exchange.fill(0.0);
            return;
        }
        let (en, et) = exchange.split_at_mut(n);
        if c.left_at_rest || c.right_at_rest {
            // One side at rest, the other dry: no velocity anywhere, no exchange.
            en.fill(0.0);
            et.fill(0.0);
        } else {
            exchange_terms(self.frac, sl.h, sr.h, un_l, un_r, en);
            carried_exchange_terms(self.frac, (sl.h, sr.h), (un_l, un_r), (ut_l, ut_r), et);
        }
    }
}

/// The draining factor θ = min(1, h/(Δt outflow over the four faces)) of a cell of
/// thickness `h` with the unlimited faces w, e, s, n (Bollermann et al. 2013).
#[inline(always)]
fn draining_factor(h: f64, (rx, ry): (f64, f64), [w, e, so, no]: [&[f64]; 4]) -> f64 {
    let need =
        rx * (e[F_H].max(0.0) + (-w[F_H]).max(0.0)) + ry * (no[F_H].max(0.0) + (-so[F_H]).max(0.0));
    if need > h {
        h.max(0.0) / need
    } else {
        1.0
    }
}

/// The layer velocities of a column of thickness `h` with discharges `qx`, `qy`
/// (N each) times the signs `(sx, sy)`, into `out` (the view's layout from
/// [`MEAN_U`]): ū, v̄, the shear terms and u_α, v_α, as the line computes them
/// (`hydrostatic.rs`, `velocities`; N = 1: `Side::monolayer`).
#[inline(always)]
fn column_velocities(
    h: f64,
    (qx, qy): (&[f64], &[f64]),
    (sx, sy): (f64, f64),
    l: &[f64],
    out: &mut [f64],
) {
    let n = l.len();
    if n == 1 {
        let (u, v) = (velocity(h, sx * qx[0]), velocity(h, sy * qy[0]));
        out[MEAN_U] = u;
        out[MEAN_V] = v;
        out[SHEAR_X] = 0.0;
        out[SHEAR_Y] = 0.0;
        out[U] = u;
        out[U + 1] = v;
        return;
    }
    if h <= H_DRY {
        out[MEAN_U..U + 2 * n].fill(0.0);
        return;
    }
    let inv_h = 1.0 / h;
    for (k, (q, s)) in [(qx, sx), (qy, sy)].into_iter().enumerate() {
        let u = &mut out[U + k * n..U + (k + 1) * n];
        let mut mean = 0.0;
        for ((u, q), l) in u.iter_mut().zip(q).zip(l) {
            *u = (s * q) * inv_h;
            mean += l * *u;
        }
        let spread: f64 = u
            .iter()
            .zip(l)
            .map(|(u, l)| l * (u - mean) * (u - mean))
            .sum();
        out[MEAN_U + k] = mean;
        out[SHEAR_X + k] = 3.0 * spread;
    }
}

/// The view of interior cell (i, j) into `out`.
fn cell_view(
    raster: &Raster2d,
    state: &LayeredRaster,
    l: &[f64],
    (i, j): (usize, usize),
    dt: f64,
    out: &mut [f64],
) {
    let n = l.len();
    let cell = j * raster.nx() + i;
    let g = raster.ghost_index(i + 1, j + 1);
    let h = state.h[cell];
    out[H] = h;
    out[SQRT_H] = h.max(0.0).sqrt();
    out[B] = raster.b_ghost[g];
    out[Z] = raster.z[g];
    let q = (
        &state.hu[cell * n..(cell + 1) * n],
        &state.hv[cell * n..(cell + 1) * n],
    );
    column_velocities(h, q, (1.0, 1.0), l, out);
    // An empty cell weighs nothing in the faces' mean drive (√h = 0).
    if h.to_bits() == 0 {
        out[DRIVE_X] = 0.0;
        out[DRIVE_Y] = 0.0;
        return;
    }
    out[DRIVE_X] = drive(raster, state, (i, j), out[U], dt, true);
    out[DRIVE_Y] = drive(raster, state, (i, j), out[U + n], dt, false);
}

/// The view of a ghost beside edge cell (i, j) (bed, potential and tangential drive
/// set by the caller): the edge cell with the signs `s` on its discharges.
fn ghost_view(
    raster: &Raster2d,
    state: &LayeredRaster,
    l: &[f64],
    (i, j): (usize, usize),
    s: (f64, f64),
    out: &mut [f64],
) {
    let n = l.len();
    let cell = j * raster.nx() + i;
    let h = state.h[cell];
    out[H] = h;
    out[SQRT_H] = h.max(0.0).sqrt();
    let q = (
        &state.hu[cell * n..(cell + 1) * n],
        &state.hv[cell * n..(cell + 1) * n],
    );
    column_velocities(h, q, s, l, out);
    out[DRIVE_X] = 0.0;
    out[DRIVE_Y] = 0.0;
}

/// The bottom layer's drive t/Δt − g_n ∂(h + z) of cell (i, j) along x (`along_x`) or
/// y, by central differences (one-sided at the raster's edge, t/Δt on a single row or
/// column); a dry neighbour whose bed stands above the cell's surface counts at that
/// surface (an emerging bed exerts no drive), as in `hydrostatic_2d.rs`.
fn drive(
    raster: &Raster2d,
    state: &LayeredRaster,
    (i, j): (usize, usize),
    t: f64,
    dt: f64,
    along_x: bool,
) -> f64 {
    let nx = raster.nx();
    let (k, len, d) = if along_x {
        (i, nx, raster.dx())
    } else {
        (j, raster.ny(), raster.dy())
    };
    let (lo, hi) = (k.saturating_sub(1), (k + 1).min(len - 1));
    if lo == hi {
        return t / dt;
    }
    let z = |i: usize, j: usize| raster.z[raster.ghost_index(i + 1, j + 1)];
    let eta = state.h[j * nx + i] + z(i, j);
    let seen = |i: usize, j: usize| {
        let h = state.h[j * nx + i];
        if h > H_DRY {
            h + z(i, j)
        } else {
            z(i, j).min(eta)
        }
    };
    let (e_lo, e_hi) = if along_x {
        (seen(lo, j), seen(hi, j))
    } else {
        (seen(i, lo), seen(i, hi))
    };
    t / dt - raster.g_n * (e_hi - e_lo) / ((hi - lo) as f64 * d)
}

impl<L: BasalFriction> Stage<Raster2d, LayeredRaster> for LayersStep2d<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    /// Mass first; if a cell would empty, the fluxes are limited and the step swept
    /// again; the step is refused (state untouched) if a thickness is still negative
    /// beyond round-off.
    fn apply(
        &mut self,
        raster: &Raster2d,
        clock: StepClock,
        state: &mut LayeredRaster,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        debug_assert_eq!(state.layers, self.layers);
        self.fill_views(raster, dt, state);
        self.sweep(raster, dt, state, false);
        let mut worst = self.worst();
        if worst.0 < 0.0 {
            self.sweep(raster, dt, state, true);
            worst = self.worst();
        }
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                cell: worst.1,
                h: worst.0,
            });
        }
        std::mem::swap(&mut state.h, &mut self.h_new);
        std::mem::swap(&mut state.hu, &mut self.hu_new);
        std::mem::swap(&mut state.hv, &mut self.hv_new);
        Ok(())
    }
}

/// The largest signal speed of a layered raster state, max over the cells of
/// max(|ū| + c_x, |v̄| + c_y) with c = √(g_n h + 3 Σ l_α (u_α − ū)²) along each axis
/// (the outer wave speeds of a sheared column, as the faces bound them); the step
/// Δt = CFL min(Δx, Δy)/s keeps the unsplit update within its faces' waves.
pub fn signal_speed(raster: &Raster2d, state: &LayeredRaster) -> f64 {
    signal_speed_of(raster, state, 0..state.cells())
}

/// [`signal_speed`] over the cells `cells` alone (a band of a parallel pass).
pub fn signal_speed_of(
    raster: &Raster2d,
    state: &LayeredRaster,
    cells: std::ops::Range<usize>,
) -> f64 {
    let n = state.layers;
    let mut view = vec![0.0; 10 + 2 * n];
    let mut fastest = 0.0f64;
    for cell in cells {
        let h = state.h[cell];
        if h <= H_DRY {
            continue;
        }
        let q = (
            &state.hu[cell * n..(cell + 1) * n],
            &state.hv[cell * n..(cell + 1) * n],
        );
        column_velocities(h, q, (1.0, 1.0), &state.l, &mut view);
        let g_n = raster.g_n;
        let along_x = view[MEAN_U].abs() + sheared_celerity(g_n, h, view[SHEAR_X]);
        let along_y = view[MEAN_V].abs() + sheared_celerity(g_n, h, view[SHEAR_Y]);
        fastest = fastest.max(along_x.max(along_y));
    }
    fastest
}
