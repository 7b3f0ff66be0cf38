//! Step 2 of the splitting for a monolayer: semi-implicit Coulomb friction with its
//! stopping criterion (Garres-Díaz et al. 2021, §3 step 2):
//!
//!   σ_i = μ_i g_n ĥ_i,
//!   (hu)_i ← (hu)*_i − Δt σ_i sgn((hu)*_i)   if Δt σ_i < |(hu)*_i|,
//!   (hu)_i ← 0                                 otherwise,
//!
//! so friction can stop a mass but never reverse it. μ_i is the law at the post-
//! advection state (a constant for Coulomb; μ(I) with I from Garres-Díaz et al. 2021, eq. 15e).
//!
//! The friction acts on the cell's own depth h_i: step 1 gives each cell the share
//! g_n h_i Δη/2 of the pressure source of each of its faces (`hydrostatic.rs`), so a
//! cell at rest feels g_n h_i (η_{i+1} − η_{i−1})/(2Δx) and a mass whose free surface
//! satisfies |η_{i+1} − η_{i−1}| ≤ 2Δx μ_s has |(hu)*| ≤ Δt σ exactly and stays at rest,
//! for any profile. Escalante et al. 2023's well-balancing thickness ĥ of eq. (25) compensates the
//! centred split ½ g_n h̄ Δη of the printed scheme and is not needed (docs/numerics.md).
//!
//! On a bed-normal line ([`BedNormalFrictionStep`]) the raster's rule of the frame
//! ([`super::friction_2d::bed_normal_friction`], on its one row with v = 0): the law's
//! scalar update acts on the speed along the bed |U| = |u|/c with the normal
//! thickness h = c H and the normal stress per unit mass c (g + b_xx u²)₊ (the
//! centrifugal term dropped with `domain.curvature = false`), and scales H u.

use super::friction_2d::bed_normal_friction;
use super::{Stage, StageError, StepClock};
use crate::grid::Line;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::H_DRY;
use crate::state::layered::LayeredState;

#[derive(Debug)]
pub struct CoulombFrictionStep<L: BasalFriction> {
    law: L,
}

impl<L: BasalFriction> CoulombFrictionStep<L> {
    pub fn new(law: L) -> Self {
        CoulombFrictionStep { law }
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for CoulombFrictionStep<L> {
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
        let nx = mesh.nx;
        for (q, &h) in state.hu[1..=nx].iter_mut().zip(&state.h[1..=nx]) {
            if *q == 0.0 {
                continue;
            }
            if h <= H_DRY {
                *q = 0.0;
                continue;
            }
            *q = self.law.friction_update(*q, h, dt, g_n);
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}

/// The friction step of the monolayer on a bed-normal line (module documentation).
#[derive(Debug)]
pub struct BedNormalFrictionStep<L: BasalFriction> {
    law: L,
}

impl<L: BasalFriction> BedNormalFrictionStep<L> {
    pub fn new(law: L) -> Self {
        BedNormalFrictionStep { law }
    }
}

impl<L: BasalFriction> Stage<Line, LayeredState> for BedNormalFrictionStep<L> {
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
        let m = mesh.metric().expect("a bed-normal line");
        let nx = mesh.nx;
        let cells = state.hu[1..=nx].iter_mut().zip(&state.h[1..=nx]);
        for (k, (q, &h)) in cells.enumerate() {
            (*q, _) = bed_normal_friction(&self.law, m, k, (*q, 0.0), h, dt);
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}
