//! Adaptive time step from the CFL condition (seed 003 eq. 14):
//! Δt = CFL Δx / max_i(|u_i| + √(g_n h_i)), bounded above so output times are hit.

use crate::mesh::Mesh;
use crate::physics::shallow::{celerity, H_DRY};
use crate::state::State;

/// Largest signal speed max(|u|) + max(√(g_n h)) over the physical cells.
///
/// The sum of the two maxima bounds the Roe-averaged HLL speeds of every interface.
pub fn max_signal_speed(mesh: &Mesh, state: &State) -> f64 {
    let mut u_max: f64 = 0.0;
    let mut h_max: f64 = 0.0;
    for j in 1..=mesh.nx {
        let h = state.h[j];
        if h > H_DRY {
            u_max = u_max.max(state.mean_velocity(j).abs());
            h_max = h_max.max(h);
        }
    }
    u_max + celerity(mesh.g_n, h_max)
}

/// The CFL time step, or `None` when nothing moves and the domain is dry.
pub fn cfl_dt(mesh: &Mesh, state: &State, cfl: f64) -> Option<f64> {
    let s = max_signal_speed(mesh, state);
    (s > 0.0).then(|| cfl * mesh.dx / s)
}
