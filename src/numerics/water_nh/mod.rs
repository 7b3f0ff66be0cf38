//! The non-hydrostatic pressure of the submarine model's water: a projection of the
//! water column over the moving grain surface, after the two-layer step
//! ([`super::two_layer`]) of Fernández-Nieto et al. 2008.
//!
//! **Model.** The water above the interface z_b = b + H₂cos²θ, of vertical depth
//! d = H₁cos²θ, is cut into M layers of depth l_α d (l_α = 1/M), with horizontal
//! velocities u_α, mean vertical velocities w_α and the non-hydrostatic pressure (over
//! water density) p_{α−1/2} at the base of each layer, p_{M+1/2} = 0 at the surface:
//! the multilayer non-hydrostatic system of Fernández-Nieto et al. 2018 (its discrete
//! form: Escalante et al. 2023, eq. 9, [`MultilayerOperator`]), whose pressure terms are
//!
//!   ∂_t(h_α u_α) = −∂_x(h_α p_α) + p_{α+1/2} ∂_x Z_{α+1/2} − p_{α−1/2} ∂_x Z_{α−1/2},
//!   ∂_t(h_α w_α) = p_{α−1/2} − p_{α+1/2},
//!
//! with Z_{α+1/2} = z_b + L_{α+1/2} d, and whose constraints are the incompressibility
//! of each layer with the kinematic condition at the moving bottom,
//! w_{1/2} = ∂_t z_b + u_1 ∂_x z_b (Stelling & Zijlema 2003; Ma, Shi & Kirby 2012):
//!
//!   (w_1 − ∂_t z_b) − u_1 ∂_x z_b + ½ h_1 ∂_x u_1 = 0,
//!   (w_α − w_{α−1}) − (u_α − u_{α−1}) ∂_x Z_{α−1/2} + ½ (h_α ∂_x u_α + h_{α−1} ∂_x u_{α−1}) = 0.
//!
//! Only the first constraint sees the bottom's motion, and only through w_1 − ∂_t z_b;
//! the others hold differences of w. So with the shifted vertical velocities
//! w̃_α = w_α − ∂_t z_b (the same shift in every layer) the constraints are those of a
//! fixed bed at z_b, and the pressure force on w is unchanged by the shift: the moving
//! bottom is the fixed-bed projection of the shifted state, shifted back.
//!
//! **Time step** (a non-incremental projection, Chorin's; the pressure is implicit):
//! 1. the two-layer step advances H₁, Q₁ (the depth mean U₁ = Σ l_α u_α), H₂, Q₂ with
//!    the hydrostatic pressures; the layer deviations u'_α = u_α − U₁ and w_α are advected by U₁
//!    (first-order upwind, `advect`; the other transport terms of the deviations,
//!    u'_α ∂_x u'_α and the exchange through the layer interfaces, are neglected:
//!    quadratic in the deviations, they vanish for linear waves, docs/numerics.md);
//! 2. the discrete bottom rate ż_b = (z_b^{n+1} − z_b^n)/Δt from the grain thicknesses
//!    before and after step 1;
//! 3. the projection on the water column: with the state
//!    (d, d u_α, d (w_α − ż_b)) and the bed z_b^{n+1}, the impulses Π = Δt p^{n+1} solve
//!    A Π = −𝒞 (A = 𝒯ᵀM⁻¹𝒯, banded Cholesky, exact), the correction 𝒯Π is added, and
//!    U₁, u'_α, w_α = w̃_α + ż_b are read back: Q₁ ← Q₁ + H₁ Σ l_α δu_α, and the moving
//!    grains' Q₂ ← Q₂ + δQ₂ ([`grains`]). H₁ and H₂ are not touched, so both volumes
//!    stay exactly those of step 1.
//!
//! **Grains.** The coupling goes both ways: the grains move the water through the
//! kinematic condition of the moving bottom (ż_b above) and feel the water's
//! hydrostatic pressure in the two-layer step; the moving grains take part in the
//! projection ([`grains`]): the interface pressure p_{1/2} pushes them,
//! δQ₂ = −r A₁ H₂ cos θ ∂_x Π, and the rate of that push enters the bottom constraint,
//! so the water's added mass is implicit (an explicit, lagged force is unstable once
//! the added mass exceeds the grains', docs/numerics.md). The coupled system keeps
//! A's band. Grains held by the Coulomb rule, and grain films thinner than the water
//! operator's wet threshold, are a fixed bottom.
//!
//! On a sloping bed the projection is written with the vertical depths d = H₁cos²θ and
//! the velocities U₁ of the two-layer model (docs/numerics.md); on a flat bed it is the
//! multilayer system exactly.

pub mod grains;

use super::banded::BandedCholesky;
use super::projection::monolayer::wet_threshold;
use super::projection::multilayer::MultilayerOperator;
use super::projection::{PressureSolver, ProjectionOperator};
use super::{Stage, StageError, StepClock};
use crate::grid::CurvedLine;
use crate::physics::two_layer::H_DRY_TWO_LAYER;
use crate::state::layered::{fill_tracer_ghosts, LayeredState, Tracer, HW};
use crate::state::{TwoLayerState, WaterColumn};
use grains::{push_grains, CoupledRows};

/// The projection of the water column, with its operator, solver and scratch column.
#[derive(Debug)]
pub struct WaterProjection {
    layers: usize,
    l: Vec<f64>,
    op: MultilayerOperator,
    solver: BandedCholesky,
    /// The water column in the multilayer model's variables (scratch, every step).
    column: LayeredState,
    /// Impulses Π = Δt p^{n+1} (face-major).
    pi: Vec<f64>,
    /// z_b at t^n and at t^{n+1} (with ghosts).
    zb_old: Vec<f64>,
    zb: Vec<f64>,
    /// ż_b per cell (with ghosts).
    zb_rate: Vec<f64>,
    /// r A₁: the weight of the interface pressure in the grains' momentum
    /// ([`grains`]; 0: the grains do not feel the non-hydrostatic pressure).
    coupling: f64,
    /// κ_i of the grains that take part in the projection, per cell with ghosts.
    kappa: Vec<f64>,
    /// The grains' terms of the system per face ([`CoupledRows::face_terms`]).
    diag: Vec<f64>,
    lower: Vec<f64>,
    /// The faces outside which `diag` and `lower` are 0.
    grain_faces: std::ops::Range<usize>,
    /// Grain layers of vertical thickness below this take no part (the water
    /// operator's wet threshold, [`wet_threshold`]).
    film: f64,
}

/// z_b = b + H₂cos²θ per cell with ghosts.
fn bottom(g: &CurvedLine, s: &TwoLayerState, zb: &mut [f64]) {
    for (((z, &b), &h2), &c2) in zb.iter_mut().zip(&g.line.b_ghost).zip(&s.h2).zip(&g.cos2) {
        *z = b + h2 * c2;
    }
}

impl WaterProjection {
    /// The projection of `layers` water layers on `g`, the grains feeling the
    /// interface pressure with the weight `coupling` = r A₁ of the two-layer model
    /// ([`grains`]; 0 leaves the grains out: the one-way coupling, for comparison).
    pub fn new(g: &CurvedLine, layers: usize, coupling: f64) -> Self {
        assert!(layers >= 1);
        let nx = g.line.nx;
        let l = vec![1.0 / layers as f64; layers];
        let mut column = LayeredState::from_profiles(&g.line, &l, &vec![0.0; nx], &vec![0.0; nx]);
        column.add_nonhydrostatic(&vec![0.0; nx]);
        WaterProjection {
            layers,
            op: MultilayerOperator::new(&g.line, &l),
            l,
            solver: BandedCholesky::new(layers, nx + 1),
            column,
            pi: vec![0.0; (nx + 1) * layers],
            zb_old: vec![0.0; nx + 2],
            zb: vec![0.0; nx + 2],
            zb_rate: vec![0.0; nx + 2],
            coupling,
            kappa: vec![0.0; nx + 2],
            diag: vec![0.0; nx + 1],
            lower: vec![0.0; nx + 1],
            grain_faces: 0..0,
            film: wet_threshold(g.line.dx),
        }
    }

    pub fn layers(&self) -> usize {
        self.layers
    }

    /// The water column of `state` at rest with zero pressure, for this stage.
    pub fn water_at_rest(&self, nx: usize) -> WaterColumn {
        WaterColumn::at_rest(nx, self.layers)
    }

    /// Records z_b^n (call with the state at t^n, before the two-layer step).
    pub fn record_bottom(&mut self, g: &CurvedLine, s: &TwoLayerState) {
        bottom(g, s, &mut self.zb_old);
    }

    /// The projection of the water of `s` over the bottom recorded by
    /// [`record_bottom`](Self::record_bottom) before this step of length `dt`.
    pub fn project(&mut self, g: &CurvedLine, s: &mut TwoLayerState, dt: f64) {
        self.project_storing(g, s, dt, dt);
    }

    /// [`project`](Self::project), storing the pressure p = Π/`dt_p` (`dt_p` = `dt`
    /// but on a step shortened to land on an output time, [`WaterProjectionStage`]).
    pub fn project_storing(&mut self, g: &CurvedLine, s: &mut TwoLayerState, dt: f64, dt_p: f64) {
        let n = self.layers;
        let nx = g.line.nx;
        let inv_dt = 1.0 / dt;
        bottom(g, s, &mut self.zb);
        for ((r, &z), &z0) in self.zb_rate.iter_mut().zip(&self.zb).zip(&self.zb_old) {
            *r = (z - z0) * inv_dt;
        }
        self.op.set_bottom(&self.zb);
        let water = s
            .water
            .as_mut()
            .expect("a non-hydrostatic water carries its column");
        // The column in the multilayer variables, h = d, hu_α = d u_α, hw_α = d w̃_α,
        // with u'_α and w_α advected by U₁ on the way (`advect`).
        let lam = dt / g.line.dx;
        {
            let LayeredState {
                h, hu, tracers, nh, ..
            } = &mut self.column;
            let hw = &mut tracers
                .iter_mut()
                .find(|t: &&mut Tracer| t.name == HW)
                .expect("the column carries hw")
                .q;
            let cells = Cells {
                h1: &s.h1[1..=nx],
                rate: &self.zb_rate[1..=nx],
            };
            let (q1, cos2) = (&s.q1[1..=nx], &g.cos2[1..=nx]);
            let (du, w) = (&water.du[..], &water.w[..]);
            // The layer count as a constant for the common few (loops unrolled).
            match n {
                1 => load_column::<1>(n, lam, &cells, q1, cos2, du, w, h, hu, hw),
                2 => load_column::<2>(n, lam, &cells, q1, cos2, du, w, h, hu, hw),
                3 => load_column::<3>(n, lam, &cells, q1, cos2, du, w, h, hu, hw),
                _ => load_column::<0>(n, lam, &cells, q1, cos2, du, w, h, hu, hw),
            }
            let (h1, cos2) = (&s.h1[..nx + 2], &g.cos2[..nx + 2]);
            h[0] = h1[0] * cos2[0];
            h[nx + 1] = h1[nx + 1] * cos2[nx + 1];
            // Non-incremental: the correction's pressure is the whole p^{n+1}.
            nh.as_mut()
                .expect("the column is non-hydrostatic")
                .p
                .fill(0.0);
            fill_tracer_ghosts(hw, nx, n);
        }
        // Ghosts: h as the state's, hu copied or reversed.
        self.column.fill_ghosts(&g.line);
        self.op.update(&g.line, &self.column);
        let coupled = self.grain_weights(g, &s.h2, &s.q2);
        {
            let water = self.op.rows(&self.column);
            if coupled {
                let rows = CoupledRows {
                    water,
                    op: &self.op,
                    diag: &self.diag,
                    lower: &self.lower,
                    terms: self.grain_faces.clone(),
                };
                self.solver.solve(&rows, &mut self.pi);
            } else {
                self.solver.solve(&water, &mut self.pi);
            }
        }
        self.op.correct(&g.line, &mut self.column, &self.pi, dt_p);
        if coupled {
            push_grains(
                &self.kappa,
                &self.pi,
                n,
                self.coupling,
                &s.h2,
                &g.cos,
                g.line.dx,
                &mut s.q2,
            );
        }
        let (h, hu, hw) = (&self.column.h[..], &self.column.hu[..], self.column.hw());
        let cells = Cells {
            h1: &s.h1[1..=nx],
            rate: &self.zb_rate[1..=nx],
        };
        let d = &h[1..=nx];
        let (q1, l) = (&mut s.q1[1..=nx], &self.l[..]);
        let (du, w) = (&mut water.du[..], &mut water.w[..]);
        match n {
            1 => read_column::<1>(n, l, &cells, d, hu, hw, q1, du, w),
            2 => read_column::<2>(n, l, &cells, d, hu, hw, q1, du, w),
            3 => read_column::<3>(n, l, &cells, d, hu, hw, q1, du, w),
            _ => read_column::<0>(n, l, &cells, d, hu, hw, q1, du, w),
        }
        water
            .p
            .copy_from_slice(&self.column.nh.as_ref().expect("non-hydrostatic").p);
        s.fill_ghosts(g);
        s.water.as_mut().expect("checked above").fill_ghosts(
            nx,
            g.line.left.discharge_sign(),
            g.line.right.discharge_sign(),
        );
    }
}

impl WaterProjection {
    /// κ_i = r A₁ cos⁴θ_i H₂,i/Δx² of the cells whose grains move (Q₂ ≠ 0 after the
    /// two-layer step) next to a face with unknowns, 0 elsewhere (held or absent
    /// grains, ghosts, the edge cell of a merged outflow face): [`grains`]. Returns
    /// whether any is positive (else the projection is the water's alone, bit for bit).
    fn grain_weights(&mut self, g: &CurvedLine, h2: &[f64], q2: &[f64]) -> bool {
        let nx = g.line.nx;
        self.kappa.fill(0.0);
        if self.coupling <= 0.0 {
            return false;
        }
        let scale = self.coupling / (g.line.dx * g.line.dx);
        let (merged_left, merged_right) = self.op.merged_edges();
        let (mut first, mut last) = (usize::MAX, 0);
        let cells = self.kappa[1..=nx]
            .iter_mut()
            .zip(&h2[1..=nx])
            .zip(&q2[1..=nx])
            .zip(&g.cos2[1..=nx]);
        for (i, (((kappa, &h2), &q2), &c2)) in (1..).zip(cells) {
            // Moving grains first (the cheap test that fails in most cells).
            let thick = h2 * c2 > self.film;
            if q2 == 0.0 || !thick {
                continue;
            }
            let wet = self.op.carries_unknowns(i - 1) || self.op.carries_unknowns(i);
            let edge = (merged_left && i == 1) || (merged_right && i == nx);
            if wet && !edge {
                *kappa = scale * c2 * c2 * h2;
                first = first.min(i);
                last = i;
            }
        }
        let any = first <= last;
        if any {
            self.grain_faces = CoupledRows::face_terms(
                &self.op,
                &self.kappa,
                first..last + 1,
                &mut self.diag,
                &mut self.lower,
            );
        }
        any
    }
}

/// Per-cell values of the physical cells 1..=nx (no ghosts) for [`load_column`] and
/// [`read_column`].
struct Cells<'a> {
    /// H₁.
    h1: &'a [f64],
    /// ż_b.
    rate: &'a [f64],
}

/// The water column of the physical cells in the multilayer variables: h = d =
/// H₁cos²θ, hu_α = d (U₁ + u'_α), hw_α = d (w_α − ż_b), with u'_α (`du`) and w_α (`w`,
/// cell-major with ghosts) advected by U₁ ([`advect`]), Q₁ and cos²θ per physical cell. `h`,
/// `hu`, `hw` with ghosts
/// (left as they are). `N` is the layer count n, or 0 for any n (read at run time).
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)] // layer a indexes the cell's slices
#[inline(always)]
fn load_column<const N: usize>(
    n: usize,
    lam: f64,
    c: &Cells,
    q1: &[f64],
    cos2: &[f64],
    du: &[f64],
    w: &[f64],
    h: &mut [f64],
    hu: &mut [f64],
    hw: &mut [f64],
) {
    let n = if N == 0 { n } else { N };
    let nx = c.h1.len();
    let m = (nx + 2) * n;
    let (du, w) = (&du[..m], &w[..m]);
    let cells = h[1..=nx].iter_mut().zip(c.h1).zip(q1).zip(cos2).zip(c.rate);
    // Per cell: its n values of hu, hw and those of u', w in it and its two neighbours.
    let columns = hu[n..m - n]
        .chunks_exact_mut(n)
        .zip(hw[n..m - n].chunks_exact_mut(n))
        .zip(
            du.chunks_exact(n)
                .zip(du[n..].chunks_exact(n))
                .zip(du[2 * n..].chunks_exact(n)),
        )
        .zip(
            w.chunks_exact(n)
                .zip(w[n..].chunks_exact(n))
                .zip(w[2 * n..].chunks_exact(n)),
        );
    for (((((h, &h1), &q1), &cos2), &rate), (((hu, hw), ((dl, dc), dr)), ((wl, wc), wr))) in
        cells.zip(columns)
    {
        let d = h1 * cos2;
        *h = d;
        let u1 = if h1 > H_DRY_TWO_LAYER { q1 / h1 } else { 0.0 };
        let (c_up, c_down) = (lam * u1.max(0.0), lam * u1.min(0.0));
        let (hu, hw, dl, dc, dr) = (&mut hu[..n], &mut hw[..n], &dl[..n], &dc[..n], &dr[..n]);
        let (wl, wc, wr) = (&wl[..n], &wc[..n], &wr[..n]);
        for a in 0..n {
            hu[a] = d * (u1 + advect(dl[a], dc[a], dr[a], c_up, c_down));
            hw[a] = d * (advect(wl[a], wc[a], wr[a], c_up, c_down) - rate);
        }
    }
}

/// The state's water from the projected column (the inverse of [`load_column`]):
/// Q₁ = H₁ Σ l_α u_α, u'_α = u_α − Σ l_β u_β, w_α = w̃_α + ż_b with u_α = hu_α/d,
/// w̃_α = hw_α/d, d per physical cell; u' = w = 0 (and Q₁ unchanged) in dry cells.
/// `hu`, `hw`, `du`, `w` with ghosts (the ghosts left as they are).
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)] // layer a indexes the cell's slices
#[inline(always)]
fn read_column<const N: usize>(
    n: usize,
    l: &[f64],
    c: &Cells,
    d: &[f64],
    hu: &[f64],
    hw: &[f64],
    q1: &mut [f64],
    du: &mut [f64],
    w: &mut [f64],
) {
    let n = if N == 0 { n } else { N };
    let nx = c.h1.len();
    let m = (nx + 2) * n;
    let l = &l[..n];
    let cells = q1.iter_mut().zip(c.h1).zip(d).zip(c.rate);
    let columns = hu[n..m - n]
        .chunks_exact(n)
        .zip(hw[n..m - n].chunks_exact(n))
        .zip(du[n..m - n].chunks_exact_mut(n))
        .zip(w[n..m - n].chunks_exact_mut(n));
    for ((((q1, &h1), &d), &rate), (((hu, hw), du), w)) in cells.zip(columns) {
        let (hu, hw, du, w) = (&hu[..n], &hw[..n], &mut du[..n], &mut w[..n]);
        if h1 <= H_DRY_TWO_LAYER || d <= 0.0 {
            du.fill(0.0);
            w.fill(0.0);
            continue;
        }
        let inv_d = 1.0 / d;
        let mut mean = 0.0;
        for a in 0..n {
            mean += l[a] * hu[a] * inv_d;
        }
        *q1 = h1 * mean;
        for a in 0..n {
            du[a] = hu[a] * inv_d - mean;
            w[a] = hw[a] * inv_d + rate;
        }
    }
}

/// First-order upwind advection ∂_t f + U₁ ∂_x f = 0 of a per-layer value f of a cell,
/// from its values `left`, `here`, `right` in the cell and its two neighbours, with the
/// Courant numbers c_up = λ max(U₁, 0) and c_down = λ min(U₁, 0) of the cell
/// (λ = Δt/Δx; |U₁| λ ≤ 1 by the CFL condition of the two-layer step, whose speed
/// bounds contain U₁).
#[inline(always)]
fn advect(left: f64, here: f64, right: f64, c_up: f64, c_down: f64) -> f64 {
    here - c_up * (here - left) - c_down * (right - here)
}

/// The projection as the second stage of a submarine run with non-hydrostatic water.
///
/// A step shortened to land on an output time stores p = Π/Δt_full, Δt_full the step
/// the CFL condition allowed ([`StepClock::rate_step`]), as the granular projections do
/// ([`super::projection`], "Shortened steps"): Π does not shrink with Δt where the
/// two-layer step changes the grains' discharge by an amount that does not (grains
/// stopped or started by the Coulomb rule under the water, which the coupled
/// projection answers with an impulse of the same size), so Π/Δt on a step shortened
/// a thousandfold stored a pressure a thousand times the full step's. The velocities
/// take Π whatever the step; only the stored p, an output, changes.
#[derive(Debug)]
pub struct WaterProjectionStage {
    pub projection: WaterProjection,
}

impl WaterProjectionStage {
    /// The stage of `projection`.
    pub fn new(projection: WaterProjection) -> Self {
        WaterProjectionStage { projection }
    }
}

impl Stage<CurvedLine, TwoLayerState> for WaterProjectionStage {
    fn name(&self) -> &'static str {
        "water_projection"
    }

    fn prepare(&mut self, grid: &CurvedLine, _: StepClock, state: &TwoLayerState) {
        self.projection.record_bottom(grid, state);
    }

    fn apply(
        &mut self,
        grid: &CurvedLine,
        clock: StepClock,
        state: &mut TwoLayerState,
    ) -> Result<(), StageError> {
        self.projection
            .project_storing(grid, state, clock.dt, clock.rate_step());
        Ok(())
    }
}
