//! A curved line: the grid of the two-layer model in Cartesian coordinates (Fernández-Nieto et al. 2008,
//! §4), a [`Line`] whose bed angle θ_i with tan θ_i = b'(x_i) enters the equations, from the
//! midpoint (centred) difference of b (Fernández-Nieto et al. 2008, Remark 11 and §5.2: at a slope break
//! the bed is seen as a parabola, so the curvature ∂_x(cos²θ), ∂_x(sin θ) stays
//! finite: one cell on each side of the break carries the mean slope).
//!
//! Arrays have one ghost cell on each side (index 0 and nx + 1). A ghost copies the
//! edge cell's bed (the line's `b_ghost`) and angle, so the boundary face carries no bed jump: a free
//! (zero-gradient) boundary lets a uniform state leave unchanged, a wall mirrors it.
//!
//! The face means and differences of cos θ, cos²θ and sin θ that the face kernel
//! (`numerics::two_layer::face`) and the Coulomb step (`numerics::two_layer::coulomb`) use are computed here
//! once, with the same operations as those kernels would do per step (so results do
//! not depend on where they are computed): [`FaceGeometry`] per face, and per cell the
//! mean cos θ and ∂ₓ sin θ of the Coulomb step.

use super::{Grid, Line, Point, Stencil};

#[derive(Debug, Clone)]
pub struct CurvedLine {
    /// The cells, the bed b (`b_ghost`: with ghosts, nx + 2) and the boundaries.
    pub line: Line,
    /// cos θ, cos²θ, sin θ with ghosts (nx + 2).
    pub cos: Vec<f64>,
    pub cos2: Vec<f64>,
    pub sin: Vec<f64>,
    /// Per face j (between cells j and j + 1, nx + 1 faces): derived from `cos`,
    /// `cos2`, `sin` by [`CurvedLine::new`] (do not edit those afterwards).
    faces: Vec<FaceGeometry>,
    /// Per cell with ghosts (nx + 2, interior filled): ½(cos θ_{i−½} + cos θ_{i+½}) and
    /// (sin θ_{i+½} − sin θ_{i−½})/Δx of the Coulomb step.
    coulomb_cos: Vec<f64>,
    coulomb_dsin: Vec<f64>,
}

/// What a face needs of the bed angle: the means cos θ_{j+½} = ½(cos θ_j + cos θ_{j+1}),
/// (cos²θ)_{j+½} and its inverse, and the differences Δcos θ, Δcos²θ, Δsin θ/Δx.
#[derive(Debug, Clone, Copy, Default)]
pub struct FaceGeometry {
    pub cos: f64,
    pub cos2: f64,
    pub inv_cos2: f64,
    pub dcos: f64,
    pub dcos2: f64,
    pub dsin_dx: f64,
}

impl CurvedLine {
    /// The angle terms of `line`'s bed (sampled at its nx cell centres).
    pub fn new(line: Line) -> Self {
        let (nx, dx) = (line.nx, line.dx);
        assert!(nx >= 2, "the two-layer scheme needs at least two cells");
        let b = &line.b_ghost;
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
        let faces = (0..=nx)
            .map(|j| {
                let c2f = 0.5 * (cos2[j] + cos2[j + 1]);
                FaceGeometry {
                    cos: 0.5 * (cos[j] + cos[j + 1]),
                    cos2: c2f,
                    inv_cos2: 1.0 / c2f,
                    dcos: cos[j + 1] - cos[j],
                    dcos2: cos2[j + 1] - cos2[j],
                    dsin_dx: (sin[j + 1] - sin[j]) / dx,
                }
            })
            .collect();
        let mut coulomb_cos = vec![0.0; nx + 2];
        let mut coulomb_dsin = vec![0.0; nx + 2];
        for i in 1..=nx {
            let cl = 0.5 * (cos[i - 1] + cos[i]);
            let cr = 0.5 * (cos[i] + cos[i + 1]);
            let sl = 0.5 * (sin[i - 1] + sin[i]);
            let sr = 0.5 * (sin[i] + sin[i + 1]);
            coulomb_cos[i] = 0.5 * (cl + cr);
            coulomb_dsin[i] = (sr - sl) / dx;
        }
        CurvedLine {
            line,
            cos,
            cos2,
            sin,
            faces,
            coulomb_cos,
            coulomb_dsin,
        }
    }

    /// The nx + 1 faces' angle terms.
    #[inline(always)]
    pub fn faces(&self) -> &[FaceGeometry] {
        &self.faces
    }

    /// Mean cos θ and ∂ₓ sin θ of the Coulomb step at each cell (with ghosts, nx + 2).
    #[inline(always)]
    pub fn coulomb_terms(&self) -> (&[f64], &[f64]) {
        (&self.coulomb_cos, &self.coulomb_dsin)
    }

    /// Centre of physical cell i (1-based, as in the arrays).
    pub fn x(&self, i: usize) -> f64 {
        self.line.x[i - 1]
    }
}

impl Grid for CurvedLine {
    fn cells(&self) -> usize {
        self.line.cells()
    }
    fn centre(&self, cell: usize) -> Point {
        self.line.centre(cell)
    }
    fn axis_names(&self) -> &'static [&'static str] {
        self.line.axis_names()
    }
    fn axis(&self, axis: usize) -> &[f64] {
        self.line.axis(axis)
    }
    fn bed(&self) -> &[f64] {
        self.line.bed()
    }
    fn locate(&self, p: Point) -> Stencil {
        self.line.locate(p)
    }
    fn cfl_length(&self) -> f64 {
        self.line.cfl_length()
    }
    fn grid_spec(&self) -> super::GridSpec {
        self.line.grid_spec()
    }
    fn has_outflow(&self) -> bool {
        self.line.has_outflow()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::BoundaryKind;

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
        let free = BoundaryKind::Outflow;
        let g = CurvedLine::new(Line::cartesian(0.0, dx, &bed, free, free));
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
