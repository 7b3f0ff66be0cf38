//! Diagnostics of a layered state in one pass over the cells: mass ∫h dx, kinetic
//! energy ∫½h|u|² dx, maximum speed, the signal speed of the CFL step, and the front
//! position (largest cell centre where h − h_bed exceeds a threshold, output contract
//! `/front`). The pass also detects non-finite values, so a NaN stops the run at the
//! step that produced it.
//!
//! Signal speed (seed 003 eq. 14): max(|ū|) + √(g_n max h + max 3 Σ l_α (u_α − ū)²) over
//! the wet cells, the sheared celerity of `physics::shallow` (the shear term is 0 for
//! N = 1). The two maxima bound the Roe-averaged HLL speeds of every interface.

use crate::mesh::Mesh;
use crate::model::granular::state::LayeredState;
use crate::model::Diagnostics;
use crate::physics::shallow::{celerity, velocity, H_DRY};

pub fn diagnose(
    mesh: &Mesh,
    state: &LayeredState,
    h_bed: &[f64],
    front_threshold: f64,
) -> Diagnostics {
    let n = state.layers;
    let nx = mesh.nx;
    let h = &state.h[1..=nx];
    let hu = &state.hu[n..(nx + 1) * n];
    let (mut mass, mut ke, mut q_sum, mut max_speed, mut h_max) = (0.0, 0.0, 0.0, 0.0f64, 0.0f64);
    let (mut u_mean_max, mut shear_max) = (0.0f64, 0.0f64);
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
                let (mean, shear) = mean_and_shear(q, &state.l, inv_h);
                u_mean_max = u_mean_max.max(mean.abs());
                shear_max = shear_max.max(shear);
            }
        }
        if h - bed > front_threshold {
            front = Some(i);
        }
    }
    let signal_speed = if n == 1 {
        max_speed + celerity(mesh.g_n, h_max)
    } else {
        u_mean_max + (mesh.g_n * h_max + shear_max).sqrt()
    };
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
        signal_speed,
        front_x: front.map_or(f64::NAN, |i| mesh.x[i]),
        h_max,
        non_finite_at,
    }
}

/// Mean velocity ū = Σ l_α u_α and shear term 3 Σ l_α (u_α − ū)² of a column with layer
/// discharges `q` and 1/h = `inv_h`.
#[inline(always)]
fn mean_and_shear(q: &[f64], l: &[f64], inv_h: f64) -> (f64, f64) {
    let mean: f64 = q.iter().zip(l).map(|(q, l)| l * q).sum::<f64>() * inv_h;
    let shear: f64 = q
        .iter()
        .zip(l)
        .map(|(q, l)| {
            let d = q * inv_h - mean;
            l * d * d
        })
        .sum();
    (mean, 3.0 * shear)
}
