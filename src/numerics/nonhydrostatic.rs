//! Step 2 of the splitting for the weakly non-hydrostatic monolayer model (Garres-Díaz et al. 2021,
//! §3). Step 1 is the hydrostatic step, whose mass fluxes carry the normal discharge
//! hw as a tracer (Garres-Díaz et al. 2021, after eq. 24, `super::tracer`); step 3, the projection, is
//! in [`super::projection`]. Only non-hydrostatic pipelines build these stages.
//!
//! **Step 2** ([`NhFrictionStep`]): the explicit pressure terms of p^n, then Coulomb
//! friction with the total basal pressure (Garres-Díaz et al. 2021, step 2, its two key points):
//!
//!   (hu)* = (hu) − Δt (∂_X(h q̄) + 2q̄ ∂_X b)_i   (the discrete operator of step 3),
//!   σ_i = μ(I) (g_n h_i + 2q̄_i),  I from p_b/ρ = g_n h + 2q̄ (Garres-Díaz et al. 2021, eq. 15e),
//!   (μ(I) at the new speed, backward Euler, for the μ(I) law:
//!   [`BasalFriction::nh_friction_update`]; a constant for Coulomb),
//!   if Δt σ_i < |(hu)*|:  hu ← (hu)* − Δt σ_i sgn((hu)*),  hw ← hw + 2Δt q̄_i,
//!   otherwise:            hu ← 0,  hw ← 0,
//!
//! with q̄_i = p_i/2, p_i = (p_{i−1/2} + p_{i+1/2})/2 (p the basal pressure stored at the
//! faces). The pressure terms use the same discrete operator as the correction of step 3
//! (see [`super::projection::monolayer`]), so the total pressure force of a step is that
//! operator applied to p^{n+1} = p^n + p̃. As in the hydrostatic friction step the
//! weight is the cell's own g_n h_i (`friction.rs`); a negative total pressure (the
//! grains are lifted) gives no friction.

use super::projection::monolayer::{cell_coefficients, doubled_bed};
use super::{Stage, StageError, StepClock};
use crate::grid::Line;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::state::layered::{fill_tracer_ghosts, LayeredState, HW};

/// Step 2: explicit p^n terms and Coulomb friction with the total basal pressure.
#[derive(Debug)]
pub struct NhFrictionStep<L: BasalFriction> {
    law: L,
    two_b: Vec<f64>,
}

impl<L: BasalFriction> NhFrictionStep<L> {
    pub fn new(law: L, mesh: &Line) -> Self {
        NhFrictionStep {
            law,
            two_b: doubled_bed(mesh),
        }
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for NhFrictionStep<L> {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn apply(
        &mut self,
        mesh: &Line,
        clock: StepClock,
        state: &mut LayeredState,
    ) -> Result<(), StageError> {
        let dt = clock.dt;
        debug_assert_eq!(state.layers, 1);
        let g_n = mesh.g_n;
        let inv_dx = 1.0 / mesh.dx;
        let LayeredState {
            h, hu, tracers, nh, ..
        } = state;
        let p = &nh.as_ref().expect("non-hydrostatic state").p;
        let hw_all = &mut tracers
            .iter_mut()
            .find(|t| t.name == HW)
            .expect("non-hydrostatic state carries hw")
            .q;
        for i in 1..=mesh.nx {
            let hi = h[i];
            if hi <= H_DRY {
                hu[i] = 0.0;
                hw_all[i] = 0.0;
                continue;
            }
            let (pl, pr) = (p[i - 1], p[i]);
            let p_b = 0.5 * (pl + pr);
            let mut q = hu[i];
            let mut hw = hw_all[i];
            if pl != 0.0 || pr != 0.0 {
                let (a, b) = cell_coefficients(&self.two_b, h, i, mesh.nx, inv_dx);
                q += dt * (a * pl + b * pr);
                hw += dt * p_b;
            }
            if q == 0.0 && hw == 0.0 {
                continue;
            }
            let p_total = g_n * hi + p_b;
            let q_new = self.law.nh_friction_update(q, hu[i], hi, dt, p_total);
            hu[i] = q_new;
            hw_all[i] = if q_new == 0.0 { 0.0 } else { hw };
        }
        fill_tracer_ghosts(hw_all, mesh.nx, 1);
        state.fill_ghosts(mesh);
        Ok(())
    }
}
