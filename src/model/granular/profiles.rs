//! The vertical structure a multilayer state carries beyond h and u_α, computed for
//! output (Fernández-Nieto et al. 2016, §3.2 and §4.2.5).
//!
//! Normal velocities follow from the incompressibility condition (Fernández-Nieto et al. 2016, eq. 20),
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
//! no layer does; Fernández-Nieto et al. 2016, §4.2.5 uses 1e-3 m/s).

use crate::grid::Coordinates;
use crate::grid::Line;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::layered::LayeredState;

/// Normal velocity of every layer at its midpoint, layer-major (α·nx + i), into `w`.
pub fn normal_velocities(mesh: &Line, state: &LayeredState, w: &mut [f64]) {
    let (nx, n) = (mesh.nx, state.layers);
    assert_eq!(w.len(), n * nx);
    let two_dx = 2.0 * mesh.dx;
    let plane_slope = match mesh.coordinates {
        Coordinates::Local => mesh.theta.tan(),
        Coordinates::Cartesian | Coordinates::BedNormal => 0.0,
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
pub fn static_interface(state: &LayeredState, threshold: f64, out: &mut [f64]) {
    let n = state.layers;
    for (i, out) in out.iter_mut().enumerate() {
        let j = i + 1;
        let h = state.h[j];
        if h <= H_DRY {
            *out = 0.0;
            continue;
        }
        let q = &state.hu[j * n..(j + 1) * n];
        let flowing = q.iter().position(|&q| velocity(h, q).abs() > threshold);
        *out = interface_height(&state.l, h, flowing);
    }
}

/// Height above the bed of the base of layer `flowing` (the lowest flowing layer) in a
/// column of thickness `h` and layer fractions `l`: h when no layer flows.
pub(crate) fn interface_height(l: &[f64], h: f64, flowing: Option<usize>) -> f64 {
    match flowing {
        Some(a) => l[..a].iter().sum::<f64>() * h,
        None => h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::BoundaryKind;
    use crate::grid::LineSpec;

    fn mesh(slope_deg: f64, coordinates: Coordinates, b: impl Fn(f64) -> f64) -> Line {
        let spec = LineSpec {
            x_min: 0.0,
            x_max: 1.0,
            cells: 10,
            slope_deg,
            coordinates,
            left: BoundaryKind::Outflow,
            right: BoundaryKind::Outflow,
        };
        let bed = spec.centres().iter().map(|&x| b(x)).collect();
        Line::new(&spec, bed)
    }

    /// Uniform thickness, flat bed, every layer with u = a x: incompressibility gives
    /// w = −a z at height z (Fernández-Nieto et al. 2016, eq. 20).
    #[test]
    fn stretching_flow_has_linear_normal_velocity() {
        let m = mesh(10.0, Coordinates::Local, |_| 0.0);
        let l = [0.2, 0.3, 0.5];
        let rate = 0.7;
        let u: Vec<f64> = m.x.iter().map(|x| rate * x).collect();
        let mut state = LayeredState::from_profiles(&m, &l, &[0.4; 10], &u);
        // Extrapolated ghosts so the centred differences hold at the ends too.
        for a in 0..3 {
            state.hu[a] = 0.4 * rate * (m.x[0] - m.dx);
            state.hu[11 * 3 + a] = 0.4 * rate * (m.x[9] + m.dx);
        }
        let mut w = vec![0.0; 3 * 10];
        normal_velocities(&m, &state, &mut w);
        let mid = [0.1 * 0.4, 0.35 * 0.4, 0.75 * 0.4];
        for a in 0..3 {
            for i in 0..10 {
                assert!(
                    (w[a * 10 + i] + rate * mid[a]).abs() < 1e-12,
                    "layer {a}, cell {i}"
                );
            }
        }
    }

    /// A flow at rest on a bump has w = 0; a uniform layer sliding over a bed of slope
    /// s follows it: w = u s in every layer.
    #[test]
    fn sliding_layer_follows_the_bed() {
        for coordinates in [Coordinates::Local, Coordinates::Cartesian] {
            let m = mesh(0.0, coordinates, |x| 0.1 * x);
            let l = [0.5, 0.5];
            let state = LayeredState::from_profiles(&m, &l, &[0.2; 10], &[2.0; 10]);
            let mut w = vec![0.0; 20];
            normal_velocities(&m, &state, &mut w);
            for i in 1..9 {
                assert!((w[i] - 0.2).abs() < 1e-12 && (w[10 + i] - 0.2).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn static_interface_is_the_base_of_the_first_flowing_layer() {
        let m = mesh(0.0, Coordinates::Local, |_| 0.0);
        let l = [0.25, 0.25, 0.5];
        let mut state = LayeredState::from_profiles(&m, &l, &[0.4; 10], &[0.0; 10]);
        // Cell 0 at rest, cell 1 flows above the first layer, cell 2 flows at the bed,
        // cell 3 is dry.
        let n = 3;
        state.hu[2 * n + 1] = 0.4 * 0.5;
        state.hu[2 * n + 2] = 0.4 * 1.0;
        state.hu[3 * n] = 0.4 * 0.01;
        state.h[4] = 0.0;
        let mut out = vec![-1.0; 10];
        static_interface(&state, 1e-3, &mut out);
        assert_eq!(out[0], 0.4);
        assert_eq!(out[1], 0.25 * 0.4);
        assert_eq!(out[2], 0.0);
        assert_eq!(out[3], 0.0);
    }
}
