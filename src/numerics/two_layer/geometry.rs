//! Bed geometry of the two-layer model in Cartesian coordinates (seed 004 §4): the bed
//! b(x) at the cell centres and the bed angle θ_i with tan θ_i = b'(x_i), from the
//! midpoint (centred) difference of b (seed 004 Remark 11 and §5.2: at a slope break
//! the bed is seen as a parabola, so the curvature ∂_x(cos²θ), ∂_x(sin θ) stays
//! finite: one cell on each side of the break carries the mean slope).
//!
//! Arrays have one ghost cell on each side (index 0 and nx + 1). A ghost copies the
//! edge cell's bed and angle, so the boundary face carries no bed jump: a free
//! (zero-gradient) boundary lets a uniform state leave unchanged, a wall mirrors it.

use crate::mesh::BoundaryKind;

#[derive(Debug, Clone)]
pub struct TwoLayerGeometry {
    pub nx: usize,
    pub dx: f64,
    pub x_min: f64,
    /// Bed elevation b with ghosts (nx + 2).
    pub b: Vec<f64>,
    /// cos θ, cos²θ, sin θ with ghosts (nx + 2).
    pub cos: Vec<f64>,
    pub cos2: Vec<f64>,
    pub sin: Vec<f64>,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
}

impl TwoLayerGeometry {
    /// Geometry from the bed sampled at the nx cell centres x_i = x_min + (i + ½)Δx.
    pub fn new(x_min: f64, dx: f64, bed: &[f64], left: BoundaryKind, right: BoundaryKind) -> Self {
        let nx = bed.len();
        assert!(nx >= 2, "the two-layer scheme needs at least two cells");
        let mut b = Vec::with_capacity(nx + 2);
        b.push(bed[0]);
        b.extend_from_slice(bed);
        b.push(bed[nx - 1]);
        let mut cos = vec![1.0; nx + 2];
        let mut cos2 = vec![1.0; nx + 2];
        let mut sin = vec![0.0; nx + 2];
        for i in 1..=nx {
            // Midpoint formula inside, one-sided at the two edge cells.
            let slope = if i == 1 {
                (b[2] - b[1]) / dx
            } else if i == nx {
                (b[nx] - b[nx - 1]) / dx
            } else {
                (b[i + 1] - b[i - 1]) / (2.0 * dx)
            };
            let c2 = 1.0 / (1.0 + slope * slope);
            cos2[i] = c2;
            cos[i] = c2.sqrt();
            sin[i] = slope * cos[i];
        }
        for (g, e) in [(0, 1), (nx + 1, nx)] {
            cos[g] = cos[e];
            cos2[g] = cos2[e];
            sin[g] = sin[e];
        }
        TwoLayerGeometry {
            nx,
            dx,
            x_min,
            b,
            cos,
            cos2,
            sin,
            left,
            right,
        }
    }

    /// Centre of physical cell i (1-based, as in the arrays).
    pub fn x(&self, i: usize) -> f64 {
        self.x_min + (i as f64 - 0.5) * self.dx
    }

    pub fn x_max(&self) -> f64 {
        self.x_min + self.nx as f64 * self.dx
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_slope_gives_its_angle_and_a_break_is_smoothed_over_two_cells() {
        let dx = 0.5;
        let bed: Vec<f64> = (0..8)
            .map(|i| {
                let x = (i as f64 + 0.5) * dx;
                if x < 2.0 {
                    1.0 - x / 5.0
                } else {
                    0.6
                }
            })
            .collect();
        let g = TwoLayerGeometry::new(0.0, dx, &bed, BoundaryKind::Outflow, BoundaryKind::Outflow);
        let c = 1.0 / (1.0f64 + 0.04).sqrt();
        assert!((g.cos[2] - c).abs() < 1e-15);
        assert!((g.sin[2] + 0.2 * c).abs() < 1e-15);
        // Cells 4 and 5 straddle the break at x = 2: the centred differences see the
        // slopes −0.15 and −0.05 (the parabola through three samples), then flat.
        let c4 = 1.0 / (1.0f64 + 0.0225).sqrt();
        let c5 = 1.0 / (1.0f64 + 0.0025).sqrt();
        assert!((g.cos[4] - c4).abs() < 1e-15 && (g.cos[5] - c5).abs() < 1e-15);
        assert_eq!(g.cos[7], 1.0);
    }
}
