//! Diagnostics of a state: mass ∫h dx, kinetic energy ∫½h|u|² dx, maximum speed, and
//! the front position (largest cell centre where h − h_bed exceeds a threshold,
//! output contract `/front`). One pass over the cells; it also detects non-finite
//! values, so a NaN stops the run at the step that produced it.

use crate::mesh::Mesh;
use crate::physics::shallow::{velocity, H_DRY};
use crate::state::State;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diagnostics {
    pub mass: f64,
    pub kinetic_energy: f64,
    pub max_speed: f64,
    /// NaN when no cell exceeds the threshold.
    pub front_x: f64,
    pub h_max: f64,
    /// First cell (physical index) holding a non-finite value, if any.
    pub non_finite_at: Option<usize>,
}

pub fn diagnose(mesh: &Mesh, state: &State, h_bed: &[f64], front_threshold: f64) -> Diagnostics {
    let n = state.layers;
    let nx = mesh.nx;
    let h = &state.h[1..=nx];
    let hu = &state.hu[n..(nx + 1) * n];
    let (mut mass, mut ke, mut q_sum, mut max_speed, mut h_max) = (0.0, 0.0, 0.0, 0.0f64, 0.0f64);
    let mut front = None;
    for (i, ((&h, q), &bed)) in h.iter().zip(hu.chunks_exact(n)).zip(h_bed).enumerate() {
        mass += h;
        h_max = h_max.max(h);
        if n == 1 {
            q_sum += q[0];
            let u = velocity(h, q[0]);
            ke += h * u * u;
            max_speed = max_speed.max(u.abs());
        } else {
            // Σ_α l_α h u_α² = Σ_α l_α q_α² / h, one division per cell.
            let (mut energy, mut q_max) = (0.0, 0.0f64);
            for (&qa, &la) in q.iter().zip(&state.l) {
                q_sum += qa;
                energy += la * qa * qa;
                q_max = q_max.max(qa.abs());
            }
            if h > H_DRY {
                let inv_h = 1.0 / h;
                ke += energy * inv_h;
                max_speed = max_speed.max(q_max * inv_h);
            }
        }
        if h - bed > front_threshold {
            front = Some(i);
        }
    }
    // A non-finite h or discharge poisons these sums; only then search for the cell.
    // (The kinetic energy may overflow for finite, absurd states: not a failure.)
    let non_finite_at = if (mass + q_sum).is_finite() {
        None
    } else {
        h.iter()
            .zip(hu.chunks_exact(n))
            .position(|(h, q)| !h.is_finite() || q.iter().any(|v| !v.is_finite()))
            .or(Some(0))
    };
    Diagnostics {
        mass: mass * mesh.dx,
        kinetic_energy: 0.5 * ke * mesh.dx,
        max_speed,
        front_x: front.map_or(f64::NAN, |i| mesh.x[i]),
        h_max,
        non_finite_at,
    }
}
