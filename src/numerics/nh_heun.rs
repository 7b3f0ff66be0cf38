//! The second-order time step (`numerics.order = 2`) of the non-hydrostatic models on
//! a line, the monolayer of Garres-Díaz et al. 2021 and the N-layer model of Escalante
//! et al. 2023: Heun's method (Shu & Osher 1988, eq. 2.18) around the whole split
//! step, as [`super::ssp_rk2`] does for the hydrostatic model. With H_Δt the hyperbolic
//! step at order 2 ([`super::muscl`]; it carries h w as a tracer), R_Δt the rest of the
//! first-order split step (step 2, the explicit pressure terms of the stored p and the
//! friction or μ(I) viscous step, [`super::nonhydrostatic`] / [`super::nh_multilayer`];
//! step 3, the projection, [`super::projection`]):
//!
//!   U⁽¹⁾ = R_Δt(H_Δt(Uⁿ)),                 p⁽¹⁾ = pⁿ + Π₁/Δt,
//!   Uⁿ⁺¹ = R_{Δt/2}(½ Uⁿ + ½ H_Δt(U⁽¹⁾)),   pⁿ⁺¹ = p⁽¹⁾ + Π₂/(Δt/2),
//!
//! U holding h, every layer discharge and every tracer (h w among them); the pressure
//! p is the state's (`NonHydrostatic::p`), not averaged: each R applies the stored p
//! explicitly and leaves its projection's pressure in the state.
//!
//! **The pressure.** Without friction, write the first stage U⁽¹⁾ = H(Uⁿ) + Δt 𝒯pⁿ +
//! 𝒯Π₁ = H(Uⁿ) + Δt 𝒯p⁽¹⁾, the second ½Uⁿ + ½H(U⁽¹⁾) + ½Δt 𝒯p⁽¹⁾ + 𝒯Π₂. With H(U) =
//! U + Δt L(U) the step is
//!
//!   Uⁿ⁺¹ = Uⁿ + ½Δt (L(Uⁿ) + L(U⁽¹⁾)) + ½Δt 𝒯(p⁽¹⁾ + p⁽²⁾),   p⁽²⁾ = p⁽¹⁾ + 2Π₂/Δt:
//!
//! Heun's average of the transport and the trapezoidal rule on the pressure, with p⁽¹⁾
//! the pressure that holds the constraint for the state of tⁿ (it is found with
//! U⁽¹⁾ ≈ U(tⁿ⁺¹) only through the increment) and p⁽²⁾ = pⁿ⁺¹ that of U⁽¹⁾ ≈ U(tⁿ⁺¹).
//! What the next step needs from this one is that p: it lives in the state, as at
//! order 1, and so does `lagged_hu` (the N-layer viscous step writes it after each of
//! its solves, the second one last). The projection ends the step, so the constraint
//! holds at tⁿ⁺¹ to round-off as at order 1 (the average of two states that hold it
//! would not: the constraint is not linear in (h, hu, hw)). For a linear constraint
//! with a fixed 𝒯 the projection P is linear and PUⁿ = Uⁿ, so projecting the average
//! is averaging the projections, and each stage R∘H is a forward-Euler step of the
//! projected flow, which Heun's average makes second order.
//!
//! **Shortened steps.** The projection takes the rate of its impulse over the full step
//! when the step was shortened to land on an output time (`projection`, "Shortened
//! steps"): each R gets the step's clock, halved for the second.
//!
//! **At rest** (u = 0, w = 0, p = 0): the first stage returns Uⁿ exactly (the first-
//! order step does), the second is that of [`super::ssp_rk2`] (the average holds
//! ½q*, which the friction or viscous step of Δt/2 holds when that of Δt held q*) with
//! p = 0 and w = 0, and the projection of a state at rest has a zero right-hand side:
//! Π = 0. Masses at rest stay at rest to the bit; h is a convex combination of two
//! non-negative states, so positivity holds under the hyperbolic step's condition.
//!
//! **h w at order 2.** The hyperbolic step carries h w with the upwind cell's edge
//! value of a limited reconstruction of w (`tracer`, `TracerTransport::second_order`):
//! with the cell mean (first-order upwind) the observed order on a smooth dispersive
//! flow fell from 1.85 to 1.25 under refinement (docs/numerics.md).
//!
//! **N layers.** The step is built for N > 1 too (the viscous step's coefficients
//! frozen at tⁿ serve both stages) and is second order on a smooth flow, but the
//! validation refuses it: a dam break over a random bed with random velocities
//! (`tests/second_order_nh.rs`, the wet/dry case) stops with two layers on the speed
//! bound at t = 0.63 s, where order 1 runs to the end.

use super::hydrostatic::HydrostaticStep;
use super::muscl::Limiter;
use super::{Stage, StageError, StepClock};
use crate::grid::Line;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::state::layered::LayeredState;

/// Heun's method around the non-hydrostatic split step (module documentation).
pub struct NhHeun<L: BasalFriction> {
    hyperbolic: HydrostaticStep<L>,
    /// R: step 2 and the projection, applied in order after the hyperbolic step.
    rest: Vec<Box<dyn Stage<Line, LayeredState>>>,
    /// Uⁿ: h, the layer discharges and each tracer, with ghosts.
    h0: Vec<f64>,
    hu0: Vec<f64>,
    tracers0: Vec<Vec<f64>>,
}

impl<L: BasalFriction> std::fmt::Debug for NhHeun<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.rest.iter().map(|s| s.name()).collect();
        f.debug_struct("NhHeun").field("rest", &names).finish()
    }
}

impl<L: BasalFriction> NhHeun<L> {
    /// Heun's method with the order-2 hyperbolic step of `layers` layers (limiter
    /// `limiter`) followed by the stages `rest` (step 2, then the projection).
    pub fn new(
        law: L,
        nx: usize,
        layers: usize,
        limiter: Limiter,
        rest: Vec<Box<dyn Stage<Line, LayeredState>>>,
    ) -> Self {
        NhHeun {
            hyperbolic: HydrostaticStep::second_order_with_layers(law, nx, layers, limiter),
            rest,
            h0: vec![0.0; nx + 2],
            hu0: vec![0.0; (nx + 2) * layers],
            tracers0: Vec::new(),
        }
    }

    /// One first-order-in-structure split step of length `clock.dt` after the
    /// hyperbolic one: R_dt.
    fn rest(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        for stage in &mut self.rest {
            stage.apply(mesh, clock, state)?;
        }
        Ok(())
    }

    /// Saves Uⁿ (h, discharges, tracers).
    fn save(&mut self, state: &LayeredState) {
        self.h0.copy_from_slice(&state.h);
        self.hu0.copy_from_slice(&state.hu);
        self.tracers0.resize_with(state.tracers.len(), Vec::new);
        for (saved, t) in self.tracers0.iter_mut().zip(&state.tracers) {
            saved.clone_from(&t.q);
        }
    }

    /// U ← ½(Uⁿ + U), the discharges and tracers 0 where the column is dry.
    fn average(&self, mesh: &Line, state: &mut LayeredState) {
        let n = state.layers;
        for (j, (h, h0)) in state.h.iter_mut().zip(&self.h0).enumerate() {
            *h = 0.5 * (*h0 + *h);
            let dry = *h <= H_DRY;
            let q = &mut state.hu[j * n..(j + 1) * n];
            for (q, q0) in q.iter_mut().zip(&self.hu0[j * n..(j + 1) * n]) {
                *q = if dry { 0.0 } else { 0.5 * (*q0 + *q) };
            }
            for (t, saved) in state.tracers.iter_mut().zip(&self.tracers0) {
                let q = &mut t.q[j * n..(j + 1) * n];
                for (q, q0) in q.iter_mut().zip(&saved[j * n..(j + 1) * n]) {
                    *q = if dry { 0.0 } else { 0.5 * (*q0 + *q) };
                }
            }
        }
        state.fill_ghosts(mesh);
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for NhHeun<L> {
    fn name(&self) -> &'static str {
        "nh_heun"
    }

    fn prepare(&mut self, mesh: &Line, clock: StepClock, state: &LayeredState) {
        // Coefficients frozen at tⁿ (the μ(I) viscous step) serve both stages.
        for stage in &mut self.rest {
            stage.prepare(mesh, clock, state);
        }
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        self.save(state);
        self.hyperbolic.apply(mesh, clock, state)?;
        self.rest(mesh, clock, state)?;
        self.hyperbolic.apply(mesh, clock, state)?;
        self.average(mesh, state);
        self.rest(mesh, clock.halved(), state)
    }
}
