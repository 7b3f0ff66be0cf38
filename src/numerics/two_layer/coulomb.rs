//! Second step of Fernández-Nieto et al. 2008, §4.1: the Coulomb stopping rule (eq. 84–85, after
//! Mangeney et al.), on the grain discharge only:
//!
//!   Q₂ⁿ⁺¹ = Q₂* − Δt N_i tan δ₀ sgn(Q₂*)   if |Q₂*| > Δt N_i tan δ₀,   0 otherwise,
//!
//!   N_i = g f_b H₂,i* ½(cos θ_{i−½} + cos θ_{i+½})
//!         + H₂,i* (U₂*)² (sin θ_{i+½} − sin θ_{i−½})/Δx,   clamped ≥ 0,
//!
//! so the friction can stop a mass but never reverse it (as
//! [`crate::physics::rheology::coulomb_update`]).
//! N_i tan δ₀ is σ*_i/cos θ_i of eq. (85) plus the curvature part T₂* of eq. (84), with
//! the cell's own H₂ where the paper averages the two face means: step 1 gives each
//! cell the static force g cos θ̄ H₂,i Δ(…)/2 of each face (own-depth split, [`super::face`]),
//! so the rest criterion of Theorem 2 (eq. 86) holds face by face exactly as printed
//! (the H₂ factor cancels on both sides).
//!
//! The printed eq. (84) adds (T₁* + T₂*)Δt with T₁* = −σ*_i sgn(Q₂*), while its own test
//! uses σ*_i/cos θ_i and the Cartesian source of eq. (62) is 𝒯/cos θ: we divide T₁* by
//! cos θ_i. The test `uniform_slide_accelerates_at_g_sin_minus_friction` decides: a
//! uniform layer on a constant slope accelerates at g(sin θ − (1 − r) cos θ tan δ₀)
//! along the bed (the exact solution of eq. 45), which the printed form misses by
//! (1 − r) g cos θ(1 − cos θ) tan δ₀.

use super::{CurvedLine, TwoLayerState};
use crate::physics::two_layer::{
    coulomb_normal_stress, layer_velocity, TwoLayerParams, H_DRY_TWO_LAYER,
};

/// Applies the stopping rule to every physical cell (ghosts must be filled). The
/// solver applies [`coulomb_cell`] inside its update pass instead (the same operations).
pub fn coulomb_step(p: &TwoLayerParams, geom: &CurvedLine, state: &mut TwoLayerState, dt: f64) {
    let (cos_mean, dsin_dx) = geom.coulomb_terms();
    for i in 1..=geom.line.nx {
        state.q2[i] = coulomb_cell(
            p,
            state.h1[i],
            state.h2[i],
            state.q2[i],
            cos_mean[i],
            dsin_dx[i],
            dt,
        );
    }
}

/// Q₂ⁿ⁺¹ of one cell from its H₁, H₂, Q₂* and the bed terms ½(cos θ_{i−½} + cos θ_{i+½})
/// and (sin θ_{i+½} − sin θ_{i−½})/Δx ([`CurvedLine::coulomb_terms`]).
#[inline(always)]
pub fn coulomb_cell(
    p: &TwoLayerParams,
    h1: f64,
    h2: f64,
    q2: f64,
    cos_mean: f64,
    dsin_dx: f64,
    dt: f64,
) -> f64 {
    if q2 == 0.0 {
        return q2;
    }
    if h2 <= H_DRY_TWO_LAYER {
        return 0.0;
    }
    let u = layer_velocity(h2, q2);
    let n = coulomb_normal_stress(p, h1, h2, cos_mean, u, dsin_dx);
    // coulomb_update with copysign for signum (the same for every number; one
    // instruction instead of signum's NaN test).
    let dt_sigma = dt * p.tan_delta * n;
    if dt_sigma >= q2.abs() {
        0.0
    } else {
        q2 - dt_sigma * 1.0f64.copysign(q2)
    }
}
