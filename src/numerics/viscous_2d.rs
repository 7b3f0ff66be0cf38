//! Step 2 of the multilayer model on a raster: the implicit μ(I) viscous columns of
//! `viscous.rs` with the velocity (u_α, v_α) of each layer (Fernández-Nieto et al.
//! 2016, eq. 24–28; Escalante et al. 2023, eq. 23–25), h fixed:
//!
//!   l_α (h (u, v)_α − (hu, hv)*_α) = Δt (K_{α−1/2} − K_{α+1/2}) / ρ,
//!   K_{α+1/2}/ρ = −ν_{α+1/2} ((u, v)_{α+1} − (u, v)_α) / h_{α+1/2},
//!   ν = μ(I) p / R(s),   s = |(u, v)_{α+1} − (u, v)_α| / h_{α+1/2},
//!
//! with ν frozen at t^n (`rheology.viscosity` = "frozen" or "lagged", the same for a
//! hydrostatic run). Each column is the line's: its coefficients come from the
//! column kernel of `viscous_columns.rs` (`ColumnRheology`) with the strain rates of
//! the vector shear, and its system — the same matrix for both components — is
//! eliminated with the two components as two lanes (`eliminate_down`,
//! `substitute_up`). At a Coulomb bed the bottom equation d (u, v)_1 = r − Δt σ s,
//! |s| ≤ 1, s = (u, v)_1/|(u, v)_1|, is solved as a vector: (u, v)_1 = 0 if
//! |r| ≤ Δt σ (the static threshold is a disk), else r (|r| − Δt σ)/(|r| d); where one
//! component of r is zero the scalar rule of the line acts on the other. The basal
//! shear rate is |(u, v)_1|/h_1 (2|(u, v)_1|/h_1 without slip). Where v ≡ 0 every
//! operation is the line's (`hypot(x, 0) = |x|`), to the bit (`tests/multilayer_2d.rs`).
//!
//! Cells thinner than [`THIN_LAYER`] take the monolayer's vector friction step
//! ([`vector_friction`], as `friction_2d.rs`) on the depth-averaged discharge, every
//! layer moving with it; a cell dry at t^n and wetted by step 1 freezes its coefficients
//! from the state after step 1 — both as on the line.
//!
//! Scope: the line's options without sidewall friction, the C-MSM strain rate and the
//! implicit viscosity (the scenario validation refuses these on a raster, naming the
//! key). Columns are independent: the step runs in row bands on the run's [`Workers`],
//! with the same bits on any number of threads.

use super::friction_2d::vector_friction;
use super::viscous::{BasalCondition, ViscosityTime, ViscousOptions, THIN_LAYER};
use super::viscous_columns::{column_fractions, eliminate_down, substitute_up, ColumnRheology};
use super::workers::{Disjoint, Workers};
use super::{Stage, StageError, StepClock};
use crate::grid::Raster2d;
use crate::physics::rheology::{coulomb_update, BasalFriction, LocalFriction};
use crate::physics::shallow::H_DRY;
use crate::state::layered_raster::LayeredRaster;
use std::sync::Mutex;

/// One thread's column scratch (N each): velocities, couplings, diagonals and
/// right-hand sides of the two components.
#[derive(Debug, Clone)]
struct Column {
    u: Vec<f64>,
    v: Vec<f64>,
    c: Vec<[f64; 2]>,
    d: Vec<[f64; 2]>,
    r: Vec<[f64; 2]>,
    /// The column's frozen coefficients and discharges while it is solved.
    coef: Vec<f64>,
    qu: Vec<f64>,
    qv: Vec<f64>,
}

/// The μ(I) viscous columns of a layered raster.
#[derive(Debug)]
pub struct ViscousColumns2d<L: BasalFriction + LocalFriction> {
    law: L,
    opts: ViscousOptions,
    layers: usize,
    workers: Workers,
    fractions: Fractions,
    /// Frozen at t^n, per cell and slot (N), cell-major: slot 0 the bed (μ_b, or ν_{1/2}
    /// without slip), slot α the interface ν_{α+1/2}; NaN in slot 0 of a cell dry at t^n.
    frozen: Vec<f64>,
    bands: Vec<u32>,
    scratch: Vec<Mutex<Column>>,
}

impl<L: BasalFriction + LocalFriction> ViscousColumns2d<L> {
    /// The step for layer fractions `l` (N ≥ 2) on `raster`. Refuses (panics on) the
    /// options the raster does not take; the scenario validation names them first.
    pub fn new(
        law: L,
        raster: &Raster2d,
        l: &[f64],
        opts: ViscousOptions,
        workers: Workers,
    ) -> Self {
        let n = l.len();
        assert!(n >= 2, "the viscous step is for N > 1 layers");
        assert!(
            opts.sidewall.is_none()
                && !opts.c_msm
                && !matches!(opts.viscosity, ViscosityTime::Implicit { .. }),
            "the raster's viscous columns take frozen viscosities without sidewall or C-MSM"
        );
        let (above, inv_sqrt_above, inv_gap) = column_fractions(l);
        let column = Column {
            u: vec![0.0; n],
            v: vec![0.0; n],
            c: vec![[0.0; 2]; n],
            d: vec![[0.0; 2]; n],
            r: vec![[0.0; 2]; n],
            coef: vec![0.0; n],
            qu: vec![0.0; n],
            qv: vec![0.0; n],
        };
        let threads = workers.threads();
        ViscousColumns2d {
            law,
            opts,
            layers: n,
            workers,
            fractions: Fractions {
                above,
                inv_sqrt_above,
                inv_gap,
            },
            frozen: vec![0.0; raster.nx() * raster.ny() * n],
            bands: (0..raster.bands() as u32).collect(),
            scratch: (0..threads).map(|_| Mutex::new(column.clone())).collect(),
        }
    }

    /// Bytes the step holds per cell (the frozen coefficients).
    pub fn bytes_per_cell(&self) -> f64 {
        8.0 * self.layers as f64
    }
}

/// The column sums of the layer fractions that the coefficients use
/// (`column_fractions`).
#[derive(Debug)]
struct Fractions {
    above: Vec<f64>,
    inv_sqrt_above: Vec<f64>,
    inv_gap: Vec<f64>,
}

/// What the bands read.
struct Ctx<'a, L> {
    rheology: ColumnRheology<'a, L>,
    inv_gap: &'a [f64],
    l: &'a [f64],
    g_n: f64,
}

impl<'a, L> Ctx<'a, L> {
    fn new(law: L, opts: ViscousOptions, f: &'a Fractions, l: &'a [f64], g_n: f64) -> Self {
        Ctx {
            rheology: ColumnRheology {
                law,
                opts,
                above: &f.above,
                inv_sqrt_above: &f.inv_sqrt_above,
            },
            inv_gap: &f.inv_gap,
            l,
            g_n,
        }
    }
}

impl<L: BasalFriction + LocalFriction> Ctx<'_, L> {
    /// The frozen coefficients of `cell` (thickness `h` > H_DRY) from its discharges,
    /// into `out` (N slots); `col` is scratch.
    #[inline(always)]
    fn freeze(&self, h: f64, (qu, qv): (&[f64], &[f64]), col: &mut Column, out: &mut [f64]) {
        let n = self.l.len();
        let inv_h = 1.0 / h;
        for a in 0..n {
            col.u[a] = qu[a] * inv_h;
            col.v[a] = qv[a] * inv_h;
        }
        let (u, v) = (&col.u, &col.v);
        let p_b = self.g_n * h;
        let law = self.rheology.law;
        let scale = law.inertial_scale(p_b);
        let nu_max = self.rheology.nu_max(h);
        let inv_h1 = inv_h / self.l[0];
        let shear = match self.rheology.opts.basal {
            BasalCondition::Coulomb => (u[0] * inv_h1).hypot(v[0] * inv_h1),
            BasalCondition::NoSlip => (2.0 * u[0] * inv_h1).hypot(2.0 * v[0] * inv_h1),
        };
        out[0] = self.rheology.bed(h, p_b, scale, nu_max, shear);
        for a in 1..n {
            let su = (u[a] - u[a - 1]) * inv_h * self.inv_gap[a];
            let sv = (v[a] - v[a - 1]) * inv_h * self.inv_gap[a];
            let (_, nu) = self
                .rheology
                .interface(a, (h, p_b, scale, nu_max), su.hypot(sv));
            out[a] = nu;
        }
    }

    /// Solves the column of thickness `h` with frozen coefficients `frozen`, updating
    /// its discharges `qu`, `qv` in place.
    #[inline(always)]
    fn solve(
        &self,
        h: f64,
        dt: f64,
        frozen: &[f64],
        (qu, qv): (&mut [f64], &mut [f64]),
        col: &mut Column,
    ) {
        let n = self.l.len();
        let dt_over_h = dt / h;
        col.c[0] = [0.0; 2];
        let couplings = col.c.iter_mut().zip(frozen).zip(self.inv_gap).skip(1);
        for ((c, nu), gap) in couplings {
            let c_a = dt_over_h * nu * gap;
            *c = [c_a, c_a];
        }
        for a in 0..n {
            let d = self.l[a] * h;
            col.d[a] = [d, d];
            col.r[a] = [self.l[a] * qu[a], self.l[a] * qv[a]];
        }
        let basal = self.rheology.opts.basal;
        if basal == BasalCondition::NoSlip {
            let extra = dt_over_h * frozen[0] * 2.0 / self.l[0];
            col.d[0][0] += extra;
            col.d[0][1] += extra;
        }
        eliminate_down(&col.c, &mut col.d, &mut col.r);
        let (r, d) = (col.r[0], col.d[0]);
        let bottom = match basal {
            BasalCondition::NoSlip => [r[0] / d[0], r[1] / d[1]],
            BasalCondition::Coulomb => {
                let impulse = dt * frozen[0] * self.g_n * h;
                disk_bottom(r, d, impulse)
            }
        };
        substitute_up(&col.c, &col.d, &col.r, bottom, |a, u| {
            qu[a] = h * u[0];
            qv[a] = h * u[1];
        });
    }
}

/// The bottom velocity (u, v)_1 from d (u, v)_1 = r − Δt σ s, s ∈ Sgn((u, v)_1), with the
/// Coulomb impulse Δt σ = `impulse`: the scalar rule where a component of r is zero
/// (the line's `coulomb_update`), else the disk.
#[inline(always)]
fn disk_bottom(r: [f64; 2], d: [f64; 2], impulse: f64) -> [f64; 2] {
    if r[1] == 0.0 {
        return [coulomb_update(r[0], impulse) / d[0], r[1] / d[1]];
    }
    if r[0] == 0.0 {
        return [r[0] / d[0], coulomb_update(r[1], impulse) / d[1]];
    }
    let m = r[0].hypot(r[1]);
    if impulse >= m {
        return [0.0, 0.0];
    }
    let scale = (m - impulse) / m;
    [r[0] * scale / d[0], r[1] * scale / d[1]]
}

impl<L: BasalFriction + LocalFriction> Stage<Raster2d, LayeredRaster> for ViscousColumns2d<L> {
    fn name(&self) -> &'static str {
        "viscous"
    }

    fn prepare(&mut self, raster: &Raster2d, _: StepClock, state: &LayeredRaster) {
        let n = self.layers;
        let ctx = Ctx::new(self.law, self.opts, &self.fractions, &state.l, raster.g_n);
        let nx = raster.nx();
        let frozen = Disjoint::new(&mut self.frozen);
        let scratch = &self.scratch;
        self.workers.tiles(&self.bands, |thread, band| {
            let mut col = scratch[thread].lock().unwrap();
            let col = &mut *col;
            let mut out = std::mem::take(&mut col.coef);
            for j in raster.band_rows(band) {
                for cell in j * nx..(j + 1) * nx {
                    let h = state.h[cell];
                    if h > H_DRY {
                        let q = (
                            &state.hu[cell * n..(cell + 1) * n],
                            &state.hv[cell * n..(cell + 1) * n],
                        );
                        ctx.freeze(h, q, col, &mut out);
                    } else {
                        // Dry at t^n: frozen when step 1 has wetted it.
                        out[0] = f64::NAN;
                    }
                    for (a, v) in out.iter().enumerate() {
                        // SAFETY: each band writes its own cells.
                        unsafe { frozen.set(cell * n + a, *v) };
                    }
                }
            }
            col.coef = out;
        });
    }

    fn apply(
        &mut self,
        raster: &Raster2d,
        clock: StepClock,
        state: &mut LayeredRaster,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        let n = self.layers;
        let ctx = Ctx::new(self.law, self.opts, &self.fractions, &state.l, raster.g_n);
        let (nx, g_n, law, l) = (raster.nx(), raster.g_n, self.law, &state.l);
        let frozen = &self.frozen;
        let h = &state.h;
        let (hu, hv) = (Disjoint::new(&mut state.hu), Disjoint::new(&mut state.hv));
        let scratch = &self.scratch;
        self.workers.tiles(&self.bands, |thread, band| {
            let mut col = scratch[thread].lock().unwrap();
            let col = &mut *col;
            let (mut coef, mut qu, mut qv) = (
                std::mem::take(&mut col.coef),
                std::mem::take(&mut col.qu),
                std::mem::take(&mut col.qv),
            );
            for j in raster.band_rows(band) {
                let row = j * nx..(j + 1) * nx;
                for (cell, &hc) in row.clone().zip(&h[row]) {
                    // SAFETY: each band reads and writes its own cells.
                    unsafe {
                        for a in 0..n {
                            qu[a] = hu.get(cell * n + a);
                            qv[a] = hv.get(cell * n + a);
                        }
                    }
                    if hc <= H_DRY {
                        qu.fill(0.0);
                        qv.fill(0.0);
                    } else if hc < THIN_LAYER {
                        // The monolayer's friction step at the new speed, as on the line.
                        let mean = |q: &[f64]| -> f64 { q.iter().zip(l).map(|(q, l)| q * l).sum() };
                        let (x, y) = vector_friction(&law, mean(&qu), mean(&qv), hc, dt, g_n);
                        qu.fill(x);
                        qv.fill(y);
                    } else {
                        coef.copy_from_slice(&frozen[cell * n..(cell + 1) * n]);
                        if coef[0].is_nan() {
                            // Dry at t^n, wetted by step 1: its coefficients come from
                            // this state.
                            ctx.freeze(hc, (&qu, &qv), col, &mut coef);
                        }
                        ctx.solve(hc, dt, &coef, (&mut qu, &mut qv), col);
                    }
                    // SAFETY: each band writes its own cells.
                    unsafe {
                        for a in 0..n {
                            hu.set(cell * n + a, qu[a]);
                            hv.set(cell * n + a, qv[a]);
                        }
                    }
                }
            }
            (col.coef, col.qu, col.qv) = (coef, qu, qv);
        });
        Ok(())
    }
}
