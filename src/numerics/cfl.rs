//! Adaptive time step from the CFL condition (seed 003 eq. 14):
//! Δt = CFL Δx / max_i(|u_i| + √(g_n h_i)), bounded above so output times are hit.
//! For N > 1 layers u_i is the mean velocity ū and the wave speed includes the shear
//! of the column, √(g_n h + 3 Σ l_α (u_α − ū)²), as in the hyperbolic step.

use crate::mesh::Mesh;
use crate::physics::shallow::{celerity, H_DRY};
use crate::state::State;

/// Largest signal speed max(|u|) + max(√(g_n h)) over the physical cells.
///
/// The sum of the two maxima bounds the Roe-averaged HLL speeds of every interface.
pub fn max_signal_speed(mesh: &Mesh, state: &State) -> f64 {
    let n = state.layers;
    let mut u_max: f64 = 0.0;
    let mut h_max: f64 = 0.0;
    let mut shear_max: f64 = 0.0;
    for j in 1..=mesh.nx {
        let h = state.h[j];
        if h <= H_DRY {
            continue;
        }
        h_max = h_max.max(h);
        if n == 1 {
            u_max = u_max.max(state.mean_velocity(j).abs());
            continue;
        }
        let inv_h = 1.0 / h;
        let q = &state.hu[j * n..(j + 1) * n];
        let mean: f64 = q.iter().zip(&state.l).map(|(q, l)| l * q).sum::<f64>() * inv_h;
        let shear: f64 = q
            .iter()
            .zip(&state.l)
            .map(|(q, l)| {
                let d = q * inv_h - mean;
                l * d * d
            })
            .sum();
        u_max = u_max.max(mean.abs());
        shear_max = shear_max.max(3.0 * shear);
    }
    if n == 1 {
        u_max + celerity(mesh.g_n, h_max)
    } else {
        u_max + (mesh.g_n * h_max + shear_max).sqrt()
    }
}

/// The CFL time step, or `None` when nothing moves and the domain is dry.
pub fn cfl_dt(mesh: &Mesh, state: &State, cfl: f64) -> Option<f64> {
    let s = max_signal_speed(mesh, state);
    (s > 0.0).then(|| cfl * mesh.dx / s)
}
