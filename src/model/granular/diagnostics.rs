//! Diagnostics of a layered state in one pass over the cells: mass ∫h dx, kinetic
//! energy ∫½h|u|² dx, maximum speed, the signal speed of the CFL step, and the front
//! position (largest cell centre where h − h_bed exceeds a threshold, output contract
//! `/front`). The pass also detects non-finite values, so a NaN stops the run at the
//! step that produced it.
//!
//! Signal speed of the CFL step (Escalante et al. 2023, eq. 14), a bound on every wave speed the HLL
//! flux of step 1 uses, taken per cell:
//!
//! - N = 1: s = max_i (|u_i| + √(g_n h_i)). It bounds the Einfeldt–Roe speeds
//!   |u_roe| + √(g_n h_roe) of every face too: with a = √h_L, b = √h_R and both cells
//!   below s, |u_roe| ≤ s − (a² + b²)/(a + b) ≤ s − √((a² + b²)/2) (since
//!   a² + b² ≥ 2ab), i.e. |u_roe| + √(g_n (h_L + h_R)/2) ≤ s (g_n = 1 without loss).
//! - N > 1, with the shear term σ_i = 3 Σ l_α (u_α − ū)² of the sheared celerity: the
//!   smaller of max_i(|ū_i| + √(g_n h_i)) + √(max_i σ_i) (the same argument, with
//!   √(x + y) ≤ √x + √y for the averaged shear of a face) and the column-blind bound
//!   max_i |ū_i| + √(g_n max_i h_i + max_i σ_i); both bound every face speed.
//!
//! In the bed-normal frame (N = 1) the line holds H = h/c and the horizontal discharge
//! H u, as a raster does: the mass is ∫H dx, the kinetic energy ∫½H|U|² dx and the
//! largest speed max |U| with |U| = |u|/c the speed along the bed, the signal speed
//! max_i (|u_i| + √(g c_i² H_i)) (the raster's, whose faces' waves run at
//! √(g c_f² G⁻¹_xx H) = c_f² √(g H)), and the front counts the normal thickness
//! c (H − H_bed).
//!
//! The global bound max_i |u_i| + √(g_n max_i h_i), maxima taken over different cells,
//! is never smaller and often much larger (a fast thin front and a slow thick column):
//! it would take more steps than the flux needs.

use crate::grid::Line;
use crate::model::Diagnostics;
use crate::physics::shallow::{celerity, velocity, H_DRY};
use crate::physics::GRAVITY;
use crate::state::layered::LayeredState;

pub fn diagnose(
    mesh: &Line,
    state: &LayeredState,
    h_bed: &[f64],
    front_threshold: f64,
) -> Diagnostics {
    let n = state.layers;
    let nx = mesh.nx;
    let h = &state.h[1..=nx];
    let hu = &state.hu[n..(nx + 1) * n];
    let (mut mass, mut ke, mut q_sum, mut max_speed, mut h_max) = (0.0, 0.0, 0.0, 0.0f64, 0.0f64);
    let (mut u_mean_max, mut shear_max, mut cell_max) = (0.0f64, 0.0f64, 0.0f64);
    let mut front = None;
    for (i, ((&h, q), &bed)) in h.iter().zip(hu.chunks_exact(n)).zip(h_bed).enumerate() {
        mass += h;
        h_max = h_max.max(h);
        let normal = mesh.metric().map_or(1.0, |m| m.cos[i]);
        if let Some(m) = mesh.metric() {
            q_sum += q[0];
            let u = velocity(h, q[0]);
            let (speed, c) = (m.speed(i, u, 0.0), m.cos[i]);
            ke += h * speed * speed;
            max_speed = max_speed.max(speed);
            cell_max = cell_max.max(u.abs() + celerity(GRAVITY * c * c, h));
        } else if n == 1 {
            q_sum += q[0];
            let u = velocity(h, q[0]);
            ke += h * u * u;
            max_speed = max_speed.max(u.abs());
            cell_max = cell_max.max(u.abs() + celerity(mesh.g_n, h));
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
                cell_max = cell_max.max(mean.abs() + celerity(mesh.g_n, h));
            }
        }
        if normal * (h - bed) > front_threshold {
            front = Some(i);
        }
    }
    let signal_speed = if n == 1 {
        cell_max
    } else {
        let per_cell = cell_max + shear_max.sqrt();
        per_cell.min(u_mean_max + (mesh.g_n * h_max + shear_max).sqrt())
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
        wet_cells: None,
    }
}

/// The first cell with the largest speed of [`diagnose`] (|u| of the monolayer, the
/// largest |u_α| of a column of layers).
pub fn fastest_cell(state: &LayeredState) -> Option<usize> {
    let n = state.layers;
    let nx = state.nx;
    let h = &state.h[1..=nx];
    let hu = &state.hu[n..(nx + 1) * n];
    let speed = |(&h, q): (&f64, &[f64])| {
        if n == 1 {
            velocity(h, q[0]).abs()
        } else if h > H_DRY {
            q.iter().fold(0.0f64, |m, q| m.max(q.abs())) * (1.0 / h)
        } else {
            0.0
        }
    };
    crate::model::first_maximum(h.iter().zip(hu.chunks_exact(n)).map(speed))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Coordinates, LineSpec};
    use crate::physics::shallow::sheared_celerity;
    use proptest::prelude::*;

    /// The Einfeldt bounds S_L, S_R of every face, from their definition (Garres-Díaz et al. 2021, after
    /// eq. 21, with the sheared celerity of Escalante et al. 2023 for N > 1): the speeds the HLL
    /// flux of step 1 uses. The CFL signal speed must bound them all.
    fn largest_face_speed(mesh: &Line, s: &LayeredState) -> f64 {
        let n = s.layers;
        let column = |j: usize| {
            let h = s.h[j];
            if h <= H_DRY {
                return (h, 0.0, 0.0);
            }
            let (mean, shear) = mean_and_shear(&s.hu[j * n..(j + 1) * n], &s.l, 1.0 / h);
            (h, mean, if n == 1 { 0.0 } else { shear })
        };
        let mut largest = 0.0f64;
        for k in 1..mesh.nx {
            let ((hl, ul, sl), (hr, ur, sr)) = (column(k), column(k + 1));
            if hl <= H_DRY && hr <= H_DRY {
                continue;
            }
            let (al, ar) = (hl.sqrt(), hr.sqrt());
            let u_roe = (al * ul + ar * ur) / (al + ar);
            let c_roe = sheared_celerity(mesh.g_n, 0.5 * (hl + hr), 0.5 * (sl + sr));
            let s_left = (ul - sheared_celerity(mesh.g_n, hl, sl)).min(u_roe - c_roe);
            let s_right = (ur + sheared_celerity(mesh.g_n, hr, sr)).max(u_roe + c_roe);
            largest = largest.max(s_left.abs()).max(s_right.abs());
        }
        largest
    }

    fn state(layers: usize, h: &[f64], q: &[f64]) -> (Line, LayeredState) {
        let nx = h.len();
        let spec = LineSpec {
            x_min: 0.0,
            x_max: 1.0,
            cells: nx,
            slope_deg: 20.0,
            coordinates: Coordinates::Local,
            left: BoundaryKind::Wall,
            right: BoundaryKind::Wall,
        };
        let mesh = Line::new(&spec, vec![0.0; nx]);
        let l = vec![1.0 / layers as f64; layers];
        let mut s = LayeredState::from_profiles(&mesh, &l, h, &vec![0.0; nx]);
        for i in 0..nx {
            for a in 0..layers {
                s.hu[(i + 1) * layers + a] = q[i * layers + a];
            }
        }
        s.fill_ghosts(&mesh);
        (mesh, s)
    }

    proptest! {
        /// Thin fast cells next to thick slow ones, dry cells, sheared columns: the
        /// per-cell signal speed bounds every face speed of the HLL flux.
        #[test]
        fn signal_speed_bounds_every_face_speed(
            layers in 1usize..4,
            cells in prop::collection::vec((0.0f64..1.0, -3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0, 0usize..4), 2..40),
        ) {
            let h: Vec<f64> = cells.iter().map(|c| match c.4 { 0 => 0.0, 1 => 1e-4 * c.0, _ => c.0 }).collect();
            let q: Vec<f64> = cells
                .iter()
                .zip(&h)
                .flat_map(|(c, &h)| [c.1 * h, c.2 * h, c.3 * h].into_iter().take(layers))
                .collect();
            let (mesh, s) = state(layers, &h, &q);
            let d = diagnose(&mesh, &s, &vec![0.0; h.len()], 1e-3);
            let faces = largest_face_speed(&mesh, &s);
            prop_assert!(faces <= d.signal_speed * (1.0 + 1e-12), "faces {faces} > signal {}", d.signal_speed);
        }
    }

    /// The per-cell bound is tighter than the old max|u| + √(g_n max h) when the fast
    /// and the deep cells differ: a thin fast front ahead of a thick slow column.
    #[test]
    fn per_cell_bound_beats_the_sum_of_maxima() {
        let (mesh, s) = state(1, &[0.5, 0.001], &[0.0, 0.001 * 3.0]);
        let d = diagnose(&mesh, &s, &[0.0; 2], 1e-3);
        let g_n = mesh.g_n;
        let old = 3.0 + (g_n * 0.5).sqrt();
        assert!(
            (d.signal_speed - (g_n * 0.5).sqrt().max(3.0 + (g_n * 0.001).sqrt())).abs() < 1e-12
        );
        assert!(d.signal_speed < 0.7 * old, "{} vs {old}", d.signal_speed);
    }
}
