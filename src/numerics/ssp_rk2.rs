//! The second-order time step (`numerics.order = 2`) of the monolayer hydrostatic
//! model on a line: Heun's method, the two-stage strong-stability-preserving
//! Runge–Kutta scheme of Shu & Osher 1988 (eq. 2.18), around the whole splitting,
//! with the second-order hyperbolic step H_Δt of [`super::muscl`] and the implicit
//! friction step F_Δt of [`super::friction`]:
//!
//!   U⁽¹⁾ = F_Δt(H_Δt(Uⁿ)),
//!   Uⁿ⁺¹ = F_{Δt/2}(½ Uⁿ + ½ H_Δt(U⁽¹⁾)).
//!
//! Without friction this is Heun's method, ½Uⁿ + ½(U⁽¹⁾ + Δt L(U⁽¹⁾)): second order
//! in time, and a convex combination of forward-Euler steps, so every bound one Euler
//! step keeps under its CFL condition (h ≥ 0, Audusse et al. 2004, §3: Δt max(|u| +
//! √(g_n h)) ≤ Δx/2 over the edge states) holds for the whole step. For the friction
//! alone (dq/dt = −σ sgn q, σ = μ g_n h constant over the step) it is exact: a sliding
//! mass loses Δt σ (q⁽¹⁾ = q − Δt σ, then ½(q + q⁽¹⁾) − ½Δt σ = q − Δt σ), and a mass
//! that stops within the step stops exactly (q < Δt σ gives q⁽¹⁾ = 0 and ½q ≤ ½Δt σ).
//! Averaging the two stages after the friction of each (½(Uⁿ + F(H(U⁽¹⁾)))) would
//! instead halve a stopping discharge every step without ever reaching 0.
//!
//! Where friction depends on the state (μ(I), Voellmy; also every sgn q change) the
//! splitting's error stays O(Δt²) per step: for a linear model with transport A and
//! friction B the step is exp(Δt(A + B)) + Δt²(½BA + ½B²) + O(Δt³). The
//! cases of docs/validation.md where order 2 is measured are frictionless (Ritter,
//! Stoker, the smooth wave) or have a constant Coulomb force while they slide.
//!
//! At rest every cell is reconstructed to first order ([`super::muscl`]), the first
//! stage returns Uⁿ exactly (the first-order step holds it), the second returns
//! q* = −Δt (the cell's pressure force), and F_{Δt/2} holds ½q* exactly when F_Δt held
//! q*: masses at rest stay at rest, to the bit.
//!
//! N > 1 layers ([`HeunLayers`]): the same scheme with the N-layer hyperbolic step of
//! [`super::hydrostatic`] at order 2 and the μ(I) viscous columns V_Δt of
//! [`super::viscous`] in place of F_Δt,
//!
//!   U⁽¹⁾ = V_Δt(H_Δt(Uⁿ)),   Uⁿ⁺¹ = V_{Δt/2}(½ Uⁿ + ½ H_Δt(U⁽¹⁾)),
//!
//! where U holds h, every layer's discharge and the tracers (h c per layer: their
//! average is the average of two conservative updates, so mass and tracer content are
//! conserved exactly). The viscous step's coefficients frozen at tⁿ (`prepare`) serve
//! both of its calls. At rest the argument above holds column by column: the basal
//! Coulomb threshold of V_{Δt/2} is half that of V_Δt.

use super::friction::CoulombFrictionStep;
use super::friction_2d::{CellFriction, FrictionStep2d};
use super::hydrostatic::HydrostaticStep;
use super::hydrostatic_2d::HydrostaticStep2d;
use super::muscl::Limiter;
use super::viscous::{MultilayerViscousStep, ViscousOptions};
use super::workers::Workers;
use super::{Stage, StageError, StepClock};
use crate::grid::{Line, Raster2d};
use crate::physics::rheology::{BasalFriction, LocalFriction};
use crate::physics::shallow::H_DRY;
use crate::state::layered::LayeredState;
use crate::state::State2d;

/// Heun's method around the hyperbolic and friction steps (module documentation).
#[derive(Debug)]
pub struct HeunSplitting<L: BasalFriction> {
    hyperbolic: HydrostaticStep<L>,
    friction: CoulombFrictionStep<L>,
    /// Uⁿ (h and hu with ghosts).
    h0: Vec<f64>,
    hu0: Vec<f64>,
}

impl<L: BasalFriction> HeunSplitting<L> {
    pub fn new(law: L, nx: usize, limiter: Limiter) -> Self {
        HeunSplitting {
            hyperbolic: HydrostaticStep::second_order(law, nx, limiter),
            friction: CoulombFrictionStep::new(law),
            h0: vec![0.0; nx + 2],
            hu0: vec![0.0; nx + 2],
        }
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for HeunSplitting<L> {
    fn name(&self) -> &'static str {
        "ssp_rk2"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, 1);
        self.h0.copy_from_slice(&state.h);
        self.hu0.copy_from_slice(&state.hu);
        self.hyperbolic.apply(mesh, clock, state)?;
        self.friction.apply(mesh, clock, state)?;
        self.hyperbolic.apply(mesh, clock, state)?;
        let cells = state.h.iter_mut().zip(state.hu.iter_mut());
        for ((h, q), (h0, q0)) in cells.zip(self.h0.iter().zip(&self.hu0)) {
            *h = 0.5 * (*h0 + *h);
            *q = if *h <= H_DRY { 0.0 } else { 0.5 * (*q0 + *q) };
        }
        state.fill_ghosts(mesh);
        self.friction.apply(mesh, clock.halved(), state)
    }
}

/// Heun's method around the 2-D hyperbolic and friction steps of a raster
/// ([`super::hydrostatic_2d`] at order 2, [`super::friction_2d`]): the same scheme as
/// [`HeunSplitting`], over the stepped tiles (`state::tiles`). The stage U⁽¹⁾ steps
/// the tiles S₁ of Uⁿ, the second stage those S₂ of U⁽¹⁾; a cell outside S₁ ∪ S₂ is
/// unchanged by both and keeps Uⁿ to the bit (½(a + a) = a), so the average is formed
/// over S₁ ∪ S₂ alone, with Uⁿ saved over S₁ and, on S₂ outside S₁ (where U⁽¹⁾ = Uⁿ),
/// taken from U⁽¹⁾. The tiles of S₂ are re-classified at the next step as after any
/// hyperbolic stage; where S₁ has tiles outside S₂ (the flow left them in the first
/// stage) the average may have changed them too: every tile is classified again for
/// the last friction step, and the tiles are left unknown after it (the run loop then
/// copies the whole state, and the next step classifies every tile).
#[derive(Debug)]
pub struct Heun2d<L: BasalFriction> {
    hyperbolic: HydrostaticStep2d<L>,
    friction: FrictionStep2d<L>,
    /// Uⁿ over S₁ ∪ S₂ (h, hu, hv per cell; other entries stale).
    h0: Vec<f64>,
    hu0: Vec<f64>,
    hv0: Vec<f64>,
    /// Per tile: whether it is in S₁, and S₁ itself.
    in_first: Vec<bool>,
    first: Vec<u32>,
}

impl<L: BasalFriction> Heun2d<L> {
    /// Heun's method with the second-order reconstruction of `limiter` on `raster`,
    /// the friction of its cells `friction`, its tiles run by `workers`.
    pub fn new(
        friction: CellFriction<L>,
        raster: &Raster2d,
        workers: Workers,
        limiter: Limiter,
    ) -> Self {
        let cells = raster.nx() * raster.ny();
        Heun2d {
            hyperbolic: HydrostaticStep2d::second_order(
                friction.clone(),
                raster,
                workers.clone(),
                limiter,
            ),
            friction: FrictionStep2d::with_friction(friction, workers),
            h0: vec![0.0; cells],
            hu0: vec![0.0; cells],
            hv0: vec![0.0; cells],
            in_first: Vec::new(),
            first: Vec::new(),
        }
    }

    /// Copies the state's cells of tile `t` into Uⁿ.
    fn save(&mut self, state: &State2d, t: usize) {
        for cells in state.tiles.row_segments(t) {
            self.h0[cells.clone()].copy_from_slice(&state.h[cells.clone()]);
            self.hu0[cells.clone()].copy_from_slice(&state.hu[cells.clone()]);
            self.hv0[cells.clone()].copy_from_slice(&state.hv[cells]);
        }
    }

    /// ½(Uⁿ + U) on the cells of tile `t`, the discharges 0 where dry.
    fn average(&self, state: &mut State2d, t: usize) {
        let State2d { h, hu, hv, tiles } = state;
        for cells in tiles.row_segments(t) {
            for k in cells {
                h[k] = 0.5 * (self.h0[k] + h[k]);
                if h[k] <= H_DRY {
                    (hu[k], hv[k]) = (0.0, 0.0);
                } else {
                    hu[k] = 0.5 * (self.hu0[k] + hu[k]);
                    hv[k] = 0.5 * (self.hv0[k] + hv[k]);
                }
            }
        }
    }
}

impl<L: BasalFriction> Stage<Raster2d, State2d> for Heun2d<L> {
    fn name(&self) -> &'static str {
        "ssp_rk2"
    }

    fn apply(
        &mut self,
        raster: &Raster2d,
        clock: StepClock,
        state: &mut State2d,
    ) -> Result<(), StageError> {
        let (nx, ny) = (raster.nx(), raster.ny());
        state.refresh_tiles(nx, ny);
        self.in_first = vec![false; state.tiles.count()];
        self.first = state.tiles.stepped().to_vec();
        for k in 0..self.first.len() {
            let t = self.first[k] as usize;
            self.in_first[t] = true;
            self.save(state, t);
        }
        self.hyperbolic.apply(raster, clock, state)?;
        self.friction.apply(raster, clock, state)?;
        state.refresh_tiles(nx, ny);
        let second = state.tiles.stepped().to_vec();
        for &t in &second {
            if !self.in_first[t as usize] {
                self.save(state, t as usize);
            }
        }
        self.hyperbolic.apply(raster, clock, state)?;
        let mut left = false;
        let mut in_second = vec![false; state.tiles.count()];
        for &t in &second {
            in_second[t as usize] = true;
            self.average(state, t as usize);
        }
        for &t in &self.first {
            if !in_second[t as usize] {
                left = true;
                self.average(state, t as usize);
            }
        }
        if !left {
            return self.friction.apply(raster, clock.halved(), state);
        }
        // The average changed tiles outside the stepped set S₂: the friction steps every
        // tile with a live cell, and the tiles are left unknown, so that the run loop's
        // copy of the state and the next step see every cell.
        state.tiles.touch();
        state.refresh_tiles(nx, ny);
        let done = self.friction.apply(raster, clock.halved(), state);
        state.tiles.touch();
        done
    }
}

/// Heun's method around the N-layer hyperbolic step and the viscous columns (module
/// documentation, "N > 1 layers").
#[derive(Debug)]
pub struct HeunLayers<L: BasalFriction + LocalFriction> {
    hyperbolic: HydrostaticStep<L>,
    viscous: MultilayerViscousStep<L>,
    /// Uⁿ: h, the layer discharges and each tracer, with ghosts.
    h0: Vec<f64>,
    hu0: Vec<f64>,
    tracers0: Vec<Vec<f64>>,
}

impl<L: BasalFriction + LocalFriction> HeunLayers<L> {
    /// The step for the layer fractions `l` (N = `l.len()` > 1).
    pub fn new(law: L, nx: usize, l: &[f64], opts: ViscousOptions, limiter: Limiter) -> Self {
        let n = l.len();
        HeunLayers {
            hyperbolic: HydrostaticStep::second_order_with_layers(law, nx, n, limiter),
            viscous: MultilayerViscousStep::new(law, nx, l, opts),
            h0: vec![0.0; nx + 2],
            hu0: vec![0.0; (nx + 2) * n],
            tracers0: Vec::new(),
        }
    }
}

impl<L: BasalFriction + LocalFriction> Stage<Line, LayeredState> for HeunLayers<L> {
    fn name(&self) -> &'static str {
        "ssp_rk2"
    }

    fn prepare(&mut self, mesh: &Line, clock: StepClock, state: &LayeredState) {
        self.viscous.prepare(mesh, clock, state);
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let n = state.layers;
        self.h0.copy_from_slice(&state.h);
        self.hu0.copy_from_slice(&state.hu);
        self.tracers0.resize_with(state.tracers.len(), Vec::new);
        for (saved, t) in self.tracers0.iter_mut().zip(&state.tracers) {
            saved.clone_from(&t.q);
        }
        self.hyperbolic.apply(mesh, clock, state)?;
        self.viscous.apply(mesh, clock, state)?;
        self.hyperbolic.apply(mesh, clock, state)?;
        for (j, (h, h0)) in state.h.iter_mut().zip(&self.h0).enumerate() {
            *h = 0.5 * (*h0 + *h);
            let (q, q0) = (
                &mut state.hu[j * n..(j + 1) * n],
                &self.hu0[j * n..(j + 1) * n],
            );
            for (q, q0) in q.iter_mut().zip(q0) {
                *q = if *h <= H_DRY { 0.0 } else { 0.5 * (*q0 + *q) };
            }
        }
        for (t, saved) in state.tracers.iter_mut().zip(&self.tracers0) {
            for (q, q0) in t.q.iter_mut().zip(saved) {
                *q = 0.5 * (*q0 + *q);
            }
        }
        state.fill_ghosts(mesh);
        self.viscous.apply(mesh, clock.halved(), state)
    }
}
