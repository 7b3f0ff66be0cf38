//! The second-order time step (`numerics.order = 2`) of the dilatant model's split
//! scheme ([`super::split`]): Heun's method, the two-stage strong-stability-preserving
//! Runge–Kutta scheme of Shu & Osher 1988 (eq. 2.18), around the whole splitting, as
//! for the monolayer ([`crate::numerics::ssp_rk2`]). H_Δt is the split scheme's
//! hyperbolic step with the second-order reconstruction ([`crate::numerics::muscl`],
//! μ_eff per face as at order 1) followed by the φ transport with limited linear φ in
//! the donor cells (`SplitScheme::transport_second_order`); C_Δt is its cell pass
//! (friction with μ_eff, the dilatancy step (3.15)–(3.19) of Bouchut et al. 2021, the
//! stabilisation where ξ ≠ 0):
//!
//!   U⁽¹⁾ = C_Δt(H_Δt(Uⁿ)),
//!   Uⁿ⁺¹ = C_{Δt/2}(½ Uⁿ + ½ H_Δt(U⁽¹⁾)),
//!
//! with U = (h, hv, φh), the conservative variables of (2.3)–(2.5): the average keeps
//! h and hv as the monolayer does and forms φ from the grains, φ = (φⁿhⁿ + φ⁽²⁾h⁽²⁾) /
//! (hⁿ + h⁽²⁾) (an h-weighted mean of the two φ, so it stays between them; where both
//! φ are equal it is that φ, to the bit). ∫h and ∫φh are then conserved to round-off
//! (each stage conserves them, the average of two conservative updates is
//! conservative), and every bound one stage keeps (h ≥ 0, φ within its neighbours'
//! bounds) holds for the step.
//!
//! At rest every cell is reconstructed to first order, the first stage returns Uⁿ
//! exactly (the order-1 split step holds it: friction stops the discharge, the
//! dilatancy step leaves a cell at rest), the second returns the discharge q* = −Δt ×
//! (the cell's pressure and φ-gradient force) with h and φ unchanged, and C_{Δt/2}
//! holds ½q* exactly where C_Δt held q* (its static threshold is Δt μ_eff(0) g_c h,
//! halved with Δt): masses at rest stay at rest, to the bit.
//!
//! As for the monolayer, the splitting error of a state-dependent friction (μ(I),
//! tan ψ) and of the dilatancy relaxation is O(Δt²) per step (docs/numerics.md,
//! "Second order"); the observed order on a smooth flow is measured in
//! tests/second_order_dilatant.rs.

use super::split::SplitScheme;
use super::step::DilatantOptions;
use crate::grid::Line;
use crate::numerics::muscl::Limiter;
use crate::numerics::{Stage, StageError, StepClock};
use crate::physics::dilatancy::DilatantLaw;
use crate::physics::shallow::H_DRY;
use crate::state::DilatantState;

/// Heun's method around the split scheme's hyperbolic step and cell pass (module
/// documentation).
#[derive(Debug)]
pub struct HeunSplit {
    scheme: SplitScheme,
    /// Uⁿ: h, hv and φ with ghosts (nx + 2).
    h0: Vec<f64>,
    hu0: Vec<f64>,
    phi0: Vec<f64>,
}

impl HeunSplit {
    /// The second-order step of the law `law` on `nx` cells (`phi_ref`: the material's
    /// φ, as [`SplitScheme::new`]), reconstructing with `limiter`.
    pub fn new(
        law: DilatantLaw,
        opt: DilatantOptions,
        nx: usize,
        phi_ref: f64,
        limiter: Limiter,
    ) -> Self {
        HeunSplit {
            scheme: SplitScheme::second_order(law, opt, nx, phi_ref, limiter),
            h0: vec![0.0; nx + 2],
            hu0: vec![0.0; nx + 2],
            phi0: vec![0.0; nx + 2],
        }
    }

    /// Advances `s` by `dt`; on error `s` is as it was (for a driver without the run
    /// loop: the stage of a run leaves that to the run loop).
    pub fn step(&mut self, mesh: &Line, s: &mut DilatantState, dt: f64) -> Result<(), StageError> {
        let result = self.heun(mesh, s, dt);
        if result.is_err() {
            s.h.copy_from_slice(&self.h0);
            s.hu.copy_from_slice(&self.hu0);
            s.phi.copy_from_slice(&self.phi0);
        }
        result
    }

    /// Saves Uⁿ (the average needs it) and runs both stages; on error `s` is part-way.
    fn heun(&mut self, mesh: &Line, s: &mut DilatantState, dt: f64) -> Result<(), StageError> {
        self.h0.copy_from_slice(&s.h);
        self.hu0.copy_from_slice(&s.hu);
        self.phi0.copy_from_slice(&s.phi);
        self.scheme.split_step(mesh, s, dt)?;
        self.scheme.hyperbolic_step(mesh, s, dt)?;
        self.average(mesh, s);
        self.scheme.cell_step(mesh, s, 0.5 * dt)
    }

    /// ½(Uⁿ + U) in (h, hv, φh), the discharge 0 where dry, the ghosts refilled.
    fn average(&self, mesh: &Line, s: &mut DilatantState) {
        let cells = s.h.iter_mut().zip(s.hu.iter_mut()).zip(s.phi.iter_mut());
        let saved = self.h0.iter().zip(&self.hu0).zip(&self.phi0);
        for (((h, q), phi), ((&h0, &q0), &phi0)) in cells.zip(saved) {
            let both = h0 + *h;
            if phi0 != *phi && both > 0.0 {
                *phi = (phi0 * h0 + *phi * *h) / both;
            }
            *h = 0.5 * both;
            *q = if *h <= H_DRY { 0.0 } else { 0.5 * (q0 + *q) };
        }
        s.fill_thickness_ghosts(mesh);
        let nx = s.nx;
        s.phi[0] = s.phi[1];
        s.phi[nx + 1] = s.phi[nx];
    }
}

impl Stage<Line, DilatantState> for HeunSplit {
    fn name(&self) -> &'static str {
        "ssp_rk2"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut DilatantState,
    ) -> Result<(), StageError> {
        // On error the run loop restores the state of tⁿ.
        self.heun(mesh, state, clock.dt)
    }
}
