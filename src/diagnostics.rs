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
    let mut d = Diagnostics {
        mass: 0.0,
        kinetic_energy: 0.0,
        max_speed: 0.0,
        front_x: f64::NAN,
        h_max: 0.0,
        non_finite_at: None,
    };
    for (i, &bed) in h_bed.iter().enumerate().take(mesh.nx) {
        let j = i + 1;
        let h = state.h[j];
        let q = &state.hu[j * n..(j + 1) * n];
        if !h.is_finite() || q.iter().any(|v| !v.is_finite()) {
            d.non_finite_at.get_or_insert(i);
            continue;
        }
        d.mass += h;
        d.h_max = d.h_max.max(h);
        if n == 1 {
            let u = velocity(h, q[0]);
            d.kinetic_energy += 0.5 * state.l[0] * h * u * u;
            d.max_speed = d.max_speed.max(u.abs());
        } else if h > H_DRY {
            // Σ_α ½ l_α h u_α² = ½ Σ_α l_α q_α² / h, one division per cell.
            let inv_h = 1.0 / h;
            let (mut energy, mut q_max) = (0.0, 0.0f64);
            for (&qa, &la) in q.iter().zip(&state.l) {
                energy += la * qa * qa;
                q_max = q_max.max(qa.abs());
            }
            d.kinetic_energy += 0.5 * energy * inv_h;
            d.max_speed = d.max_speed.max(q_max * inv_h);
        }
        if h - bed > front_threshold {
            d.front_x = mesh.x[i];
        }
    }
    d.mass *= mesh.dx;
    d.kinetic_energy *= mesh.dx;
    d
}
