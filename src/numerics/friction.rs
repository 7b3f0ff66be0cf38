//! Step 2 of the splitting for a monolayer: semi-implicit Coulomb friction with its
//! stopping criterion (seed 000 §3 step 2):
//!
//!   σ_i = μ_i g_n ĥ_i,
//!   (hu)_i ← (hu)*_i − Δt σ_i sgn((hu)*_i)   if Δt σ_i < |(hu)*_i|,
//!   (hu)_i ← 0                                 otherwise,
//!
//! so friction can stop a mass but never reverse it. μ_i is the law at the post-
//! advection state (a constant for Coulomb; μ(I) with I from seed 000 eq. 15e).
//!
//! ĥ_i is the well-balancing reconstruction of seed 003 eq. (25): where the free
//! surface is below the repose slope, |η_{i+1} − η_{i−1}| ≤ 2Δx μ_s, the friction acts
//! on ĥ_i = ½(h_i + ½(h_{i−1} + h_{i+1})), the thickness the discrete pressure force of
//! step 1 sees (its interface sources use ½(h_i + h_{i±1})). Then a mass at rest with
//! |∂_X η| ≤ μ_s has |(hu)*| ≤ Δt σ exactly and stays at rest. (The printed form
//! h_i + ½(h_{i−1} + h_{i+1}) is twice the thickness; we read the factor ½ as missing.)

use super::{Stage, StageError};
use crate::mesh::Mesh;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::State;

#[derive(Debug)]
pub struct CoulombFrictionStep<L: BasalFriction> {
    law: L,
}

impl<L: BasalFriction> CoulombFrictionStep<L> {
    pub fn new(law: L) -> Self {
        CoulombFrictionStep { law }
    }
}

/// The bound 2Δx μ_s on |η_{i+1} − η_{i−1}| below which ĥ applies. The relative
/// margin keeps round-off from flipping the switch for a surface lying exactly at the
/// repose slope (the limit case of seed 003 §5.3).
#[inline(always)]
pub fn repose_slope_limit(dx: f64, mu_static: f64) -> f64 {
    2.0 * dx * mu_static * (1.0 + 1e-9)
}

/// ĥ_i of seed 003 eq. (25) (module doc): ½(h_i + ½(h_{i−1} + h_{i+1})) where the free
/// surface η = h + z is within `slope_limit`, h_i elsewhere. `i` indexes the
/// ghost-inclusive arrays.
#[inline(always)]
pub fn well_balanced_thickness(h: &[f64], z: &[f64], i: usize, slope_limit: f64) -> f64 {
    let eta_jump = (h[i + 1] + z[i + 1]) - (h[i - 1] + z[i - 1]);
    if eta_jump.abs() <= slope_limit {
        0.5 * h[i] + 0.25 * (h[i - 1] + h[i + 1])
    } else {
        h[i]
    }
}

/// Applies a friction impulse `dt_sigma` ≥ 0 against the discharge `q`, stopping it
/// if the impulse is large enough. A NaN impulse propagates (it must reach the
/// run's NaN check, not silently stop the flow).
#[inline(always)]
pub fn coulomb_update(q: f64, dt_sigma: f64) -> f64 {
    if dt_sigma >= q.abs() {
        0.0
    } else {
        q - dt_sigma * q.signum()
    }
}

impl<L: BasalFriction> Stage for CoulombFrictionStep<L> {
    fn name(&self) -> &'static str {
        "friction"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, 1);
        let g_n = mesh.g_n;
        let slope_limit = repose_slope_limit(mesh.dx, self.law.mu_static());
        let (h, z) = (&state.h, &mesh.z);
        for i in 1..=mesh.nx {
            let q = state.hu[i];
            if q == 0.0 {
                continue;
            }
            let hi = h[i];
            if hi <= H_DRY {
                state.hu[i] = 0.0;
                continue;
            }
            let h_hat = well_balanced_thickness(h, z, i, slope_limit);
            let mu = self.law.mu(velocity(hi, q).abs(), hi, g_n * hi);
            state.hu[i] = coulomb_update(q, dt * mu * g_n * h_hat);
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::coulomb_update;

    #[test]
    fn friction_stops_but_never_reverses() {
        assert_eq!(coulomb_update(1.0, 0.25), 0.75);
        assert_eq!(coulomb_update(-1.0, 0.25), -0.75);
        assert_eq!(coulomb_update(0.1, 0.25), 0.0);
        assert_eq!(coulomb_update(-0.1, 0.25), 0.0);
        assert!(coulomb_update(0.1, f64::NAN).is_nan());
    }
}
