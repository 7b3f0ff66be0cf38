//! The vertical structure a multilayer state carries beyond h and u_α, computed for
//! output (seed 001 §3.2 and §4.2.5).
//!
//! Normal velocities follow from the incompressibility condition (seed 001 eq. 20),
//! with no mass crossing the bed (G_{1/2} = 0) and a fixed bed:
//!
//!   w_{1/2}^+ = u_1 ∂_X b,
//!   w_α(z) = w_{α−1/2}^+ − (z − z_{α−1/2}) ∂_X u_α,
//!   w_{α+1/2}^- = w_{α−1/2}^+ − h_α ∂_X u_α,
//!   w_{α+1/2}^+ = w_{α+1/2}^- + (u_{α+1} − u_α) ∂_X z_{α+1/2},
//!
//! with z_{α+1/2} = b + h Σ_{β≤α} l_β. The value reported for layer α is w_α at its
//! midpoint; X-derivatives are centred differences over the neighbouring cells (ghost
//! cells at the ends). b is the bed over the reference plane in local coordinates
//! (z + X tan θ) and the whole bed in Cartesian ones (z).
//!
//! The flow/no-flow interface is the height above the bed of the base of the first
//! layer, from the bottom, whose speed exceeds a threshold (the whole thickness h when
//! no layer does; seed 001 §4.2.5 uses 1e-3 m/s).

use crate::mesh::Mesh;
use crate::physics::shallow::{velocity, H_DRY};
use crate::scenario::Coordinates;
use crate::state::State;

/// Normal velocity of every layer at its midpoint, layer-major (α·nx + i), into `w`.
pub fn normal_velocities(mesh: &Mesh, state: &State, w: &mut [f64]) {
    let (nx, n) = (mesh.nx, state.layers);
    assert_eq!(w.len(), n * nx);
    let two_dx = 2.0 * mesh.dx;
    let plane_slope = match mesh.coordinates {
        Coordinates::Local => mesh.theta.tan(),
        Coordinates::Cartesian => 0.0,
    };
    let u = |j: usize, a: usize| velocity(state.h[j], state.hu[j * n + a]);
    for i in 0..nx {
        let j = i + 1;
        let h = state.h[j];
        if h <= H_DRY {
            for a in 0..n {
                w[a * nx + i] = 0.0;
            }
            continue;
        }
        let db = (mesh.z[j + 1] - mesh.z[j - 1]) / two_dx + plane_slope;
        let dh = (state.h[j + 1] - state.h[j - 1]) / two_dx;
        let mut w_base = u(j, 0) * db;
        let mut depth_below = 0.0;
        for a in 0..n {
            let h_a = state.l[a] * h;
            let du = (u(j + 1, a) - u(j - 1, a)) / two_dx;
            w[a * nx + i] = w_base - 0.5 * h_a * du;
            let w_top = w_base - h_a * du;
            depth_below += state.l[a];
            w_base = if a + 1 < n {
                w_top + (u(j, a + 1) - u(j, a)) * (db + depth_below * dh)
            } else {
                w_top
            };
        }
    }
}

/// Height above the bed of the flow/no-flow interface in every cell, into `out` (nx).
pub fn static_interface(state: &State, threshold: f64, out: &mut [f64]) {
    let n = state.layers;
    for (i, out) in out.iter_mut().enumerate() {
        let j = i + 1;
        let h = state.h[j];
        if h <= H_DRY {
            *out = 0.0;
            continue;
        }
        let q = &state.hu[j * n..(j + 1) * n];
        *out = match q.iter().position(|&q| velocity(h, q).abs() > threshold) {
            Some(a) => state.l[..a].iter().sum::<f64>() * h,
            None => h,
        };
    }
}
