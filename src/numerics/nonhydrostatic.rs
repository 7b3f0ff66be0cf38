//! Steps 1 and 2 of the splitting for the weakly non-hydrostatic monolayer model
//! (seed 000 §3). Step 3, the projection, is in [`super::projection`].
//!
//! Only non-hydrostatic pipelines build these stages; the hydrostatic pipeline is left
//! exactly as it is (same stages, same arithmetic, no branch on the model).
//!
//! **Step 1** ([`NhHyperbolicStep`]): the hydrostatic step, unchanged, then the normal
//! discharge transported as a passive scalar by its upwinded mass flux (seed 000 after
//! eq. 24): (hw)_i ← (hw)_i − Δt/Δx (𝓕^h_{i+1/2} w^up_{i+1/2} − 𝓕^h_{i−1/2} w^up_{i−1/2}),
//! w^up the velocity w^n = hw/h of the upwind cell.
//!
//! **Step 2** ([`NhFrictionStep`]): the explicit pressure terms of p^n, then Coulomb
//! friction with the total basal pressure (seed 000 step 2, its two key points):
//!
//!   (hu)* = (hu) − Δt (∂_X(h q̄) + 2q̄ ∂_X b)_i   (the discrete operator of step 3),
//!   σ_i = μ(I) (g_n h_i + 2q̄_i),  I from p_b/ρ = g_n h + 2q̄ (seed 000 eq. 15e),
//!   if Δt σ_i < |(hu)*|:  hu ← (hu)* − Δt σ_i sgn((hu)*),  hw ← hw + 2Δt q̄_i,
//!   otherwise:            hu ← 0,  hw ← 0,
//!
//! with q̄_i = p_i/2, p_i = (p_{i−1/2} + p_{i+1/2})/2 (p the basal pressure stored at the
//! faces). The pressure terms use the same discrete operator as the correction of step 3
//! (see [`super::projection::monolayer`]), so the total pressure force of a step is that
//! operator applied to p^{n+1} = p^n + p̃. As in the hydrostatic friction step the
//! weight is the cell's own g_n h_i (`friction.rs`); a negative total pressure (the
//! grains are lifted) gives no friction.

use super::friction::coulomb_update;
use super::hydrostatic::HydrostaticStep;
use super::projection::monolayer::{cell_coefficients, doubled_bed};
use super::{Stage, StageError};
use crate::mesh::Mesh;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::State;

/// Step 1 with the normal discharge transported by the hydrostatic mass flux.
#[derive(Debug)]
pub struct NhHyperbolicStep<L: BasalFriction> {
    inner: HydrostaticStep<L>,
    /// w^n per cell with ghosts, kept from before the hydrostatic update.
    w: Vec<f64>,
    /// Upwinded fluxes of hw at the faces.
    flux_hw: Vec<f64>,
}

impl<L: BasalFriction> NhHyperbolicStep<L> {
    pub fn new(law: L, nx: usize) -> Self {
        NhHyperbolicStep {
            inner: HydrostaticStep::new(law, nx),
            w: vec![0.0; nx + 2],
            flux_hw: vec![0.0; nx + 1],
        }
    }
}

impl<L: BasalFriction> Stage for NhHyperbolicStep<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, 1);
        // The loops below are branch-free (selects) so that they vectorise.
        {
            let nh = state.nh.as_ref().expect("non-hydrostatic state");
            for ((w, &h), &hw) in self.w.iter_mut().zip(&state.h).zip(&nh.hw) {
                let v = hw / h.max(H_DRY);
                *w = if h > H_DRY { v } else { 0.0 };
            }
        }
        self.inner.apply(mesh, dt, state)?;
        let nx = mesh.nx;
        let r = dt / mesh.dx;
        let flux = self.inner.mass_flux();
        let (w_left, w_right) = (&self.w[..nx + 1], &self.w[1..]);
        for (((f_hw, &f), &wl), &wr) in self.flux_hw.iter_mut().zip(flux).zip(w_left).zip(w_right) {
            *f_hw = f * if f > 0.0 { wl } else { wr };
        }
        let nh = state.nh.as_mut().expect("non-hydrostatic state");
        let cells = nh.hw[1..=nx]
            .iter_mut()
            .zip(&state.h[1..=nx])
            .zip(self.flux_hw.windows(2));
        for ((hw, &h), f) in cells {
            let v = *hw - r * (f[1] - f[0]);
            *hw = if h > H_DRY { v } else { 0.0 };
        }
        nh.fill_ghosts(nx, 1);
        Ok(())
    }
}

/// Step 2: explicit p^n terms and Coulomb friction with the total basal pressure.
#[derive(Debug)]
pub struct NhFrictionStep<L: BasalFriction> {
    law: L,
    two_b: Vec<f64>,
}

impl<L: BasalFriction> NhFrictionStep<L> {
    pub fn new(law: L, mesh: &Mesh) -> Self {
        NhFrictionStep {
            law,
            two_b: doubled_bed(mesh),
        }
    }
}

impl<L: BasalFriction> Stage for NhFrictionStep<L> {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, 1);
        let g_n = mesh.g_n;
        let inv_dx = 1.0 / mesh.dx;
        let nh = state.nh.as_mut().expect("non-hydrostatic state");
        let (h, p) = (&state.h, &nh.p);
        for i in 1..=mesh.nx {
            let hi = h[i];
            if hi <= H_DRY {
                state.hu[i] = 0.0;
                nh.hw[i] = 0.0;
                continue;
            }
            let (pl, pr) = (p[i - 1], p[i]);
            let p_b = 0.5 * (pl + pr);
            let mut q = state.hu[i];
            let mut hw = nh.hw[i];
            if pl != 0.0 || pr != 0.0 {
                let (a, b) = cell_coefficients(&self.two_b, h, i, mesh.nx, inv_dx);
                q += dt * (a * pl + b * pr);
                hw += dt * p_b;
            }
            if q == 0.0 && hw == 0.0 {
                continue;
            }
            let p_total = g_n * hi + p_b;
            let mu = self.law.mu(velocity(hi, state.hu[i]).abs(), hi, p_total);
            let sigma = mu * (g_n * hi + p_b).max(0.0);
            let q_new = coulomb_update(q, dt * sigma);
            state.hu[i] = q_new;
            nh.hw[i] = if q_new == 0.0 { 0.0 } else { hw };
        }
        nh.fill_ghosts(mesh.nx, 1);
        state.fill_ghosts(mesh);
        Ok(())
    }
}
