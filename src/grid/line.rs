//! The line: the 1-D finite-volume grid and its geometry (Garres-Díaz et al. 2021, §2.1 and §4.1).
//!
//! Cells V_i = [x_{i−1/2}, x_{i+1/2}] of uniform width Δx along the reference plane
//! (local coordinates) or the horizontal (Cartesian). The gravity potential that
//! drives the flow is g_n (h + z) with
//!
//! - local coordinates: z = b(X) + b̃(X), b̃ = −X tan θ (the plane, up to a constant)
//!   and g_n = g cos θ (Garres-Díaz et al. 2021, eq. 15b);
//! - Cartesian coordinates: z = b(x), g_n = g (Garres-Díaz et al. 2021, §4.1);
//! - the bed-normal frame (docs/numerics.md, "The bed-normal frame"): z = b(x), the
//!   cells horizontal, with the bed's metric ([`BedMetric`] of one row: b_x, cos θ,
//!   b_xx); an outflow's ghost bed continues the edge cell's slope, as on a raster.
//!
//! Arrays carry one ghost cell on each side: index 0 and nx + 1.

use super::{BedMetric, BoundaryKind, Coordinates, Grid, GridSpec, LineGeometry, Point, Stencil};
use crate::physics::GRAVITY;

/// A uniform 1-D grid of nx cells with its bed, potential and boundary kinds: the grid
/// of the layered and dilatant models, and the base of [`super::CurvedLine`].
#[derive(Debug, Clone)]
pub struct Line {
    pub nx: usize,
    pub x_min: f64,
    pub dx: f64,
    /// Cell centres of the physical cells (nx).
    pub x: Vec<f64>,
    /// Bed elevation over the reference plane at the centres (nx).
    pub b: Vec<f64>,
    /// Bed over the reference plane with ghosts (nx + 2): the jumps that the
    /// hydrostatic reconstruction sees (Escalante et al. 2023, eq. 20).
    pub b_ghost: Vec<f64>,
    /// Potential elevation z = b + b̃ with ghosts (nx + 2).
    pub z: Vec<f64>,
    /// Gravity normal to the reference plane.
    pub g_n: f64,
    pub theta: f64,
    pub coordinates: Coordinates,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
    /// The bed's gradient, cos θ and curvature in the bed-normal frame (one row:
    /// b_y = 0), else `None`.
    metric: Option<BedMetric>,
}

/// What a line is built from; `b` is sampled at the cell centres.
#[derive(Debug, Clone)]
pub struct LineSpec {
    pub x_min: f64,
    pub x_max: f64,
    pub cells: usize,
    pub slope_deg: f64,
    pub coordinates: Coordinates,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
}

impl LineSpec {
    /// Cell width Δx = (x_max − x_min) / cells.
    pub fn dx(&self) -> f64 {
        (self.x_max - self.x_min) / self.cells as f64
    }

    /// Cell centres x_i = x_min + (i + ½) Δx ([`cell_centre`]).
    pub fn centres(&self) -> Vec<f64> {
        let dx = self.dx();
        (0..self.cells)
            .map(|i| cell_centre(self.x_min, dx, i))
            .collect()
    }
}

/// Centre x_min + (i + ½) Δx of cell i (0-based) of a uniform line: the one place
/// the formula is written.
#[inline]
pub fn cell_centre(x_min: f64, dx: f64, i: usize) -> f64 {
    x_min + (i as f64 + 0.5) * dx
}

impl Line {
    /// Builds the line with the bed `b` sampled at the centres (`b.len() == cells`).
    pub fn new(spec: &LineSpec, b: Vec<f64>) -> Line {
        assert_eq!(b.len(), spec.cells, "bed sampled at every cell centre");
        Line::with_spacing(spec, spec.dx(), b)
    }

    /// A line of horizontal cells of width `dx` from `x_min` in Cartesian coordinates,
    /// with the bed `b` at its centres (one cell per value), e.g. for the two-layer
    /// scheme's tests and benchmarks, which give Δx rather than x_max.
    pub fn cartesian(
        x_min: f64,
        dx: f64,
        b: &[f64],
        left: BoundaryKind,
        right: BoundaryKind,
    ) -> Line {
        let spec = LineSpec {
            x_min,
            x_max: x_min + b.len() as f64 * dx,
            cells: b.len(),
            slope_deg: 0.0,
            coordinates: Coordinates::Cartesian,
            left,
            right,
        };
        Line::with_spacing(&spec, dx, b.to_vec())
    }

    /// The line of `spec` with the cell width `dx` (that of `spec` or the caller's).
    fn with_spacing(spec: &LineSpec, dx: f64, b: Vec<f64>) -> Line {
        let nx = spec.cells;
        let theta = spec.slope_deg.to_radians();
        let (g_n, tan_theta) = match spec.coordinates {
            Coordinates::Local => (GRAVITY * theta.cos(), theta.tan()),
            Coordinates::Cartesian | Coordinates::BedNormal => (GRAVITY, 0.0),
        };
        let x: Vec<f64> = (0..nx).map(|i| cell_centre(spec.x_min, dx, i)).collect();
        let plane = |x: f64| -x * tan_theta;
        let mut z = vec![0.0; nx + 2];
        for i in 0..nx {
            z[i + 1] = b[i] + plane(x[i]);
        }
        // Ghost beds: a wall mirrors the edge cell (no step at the wall); an outflow
        // continues the reference plane with the edge bed, so a uniform layer on the
        // plane stays uniform through the boundary.
        z[0] = match spec.left {
            BoundaryKind::Wall => z[1],
            BoundaryKind::Outflow => b[0] + plane(x[0] - dx),
        };
        z[nx + 1] = match spec.right {
            BoundaryKind::Wall => z[nx],
            BoundaryKind::Outflow => b[nx - 1] + plane(x[nx - 1] + dx),
        };
        let mut b_ghost = Vec::with_capacity(nx + 2);
        b_ghost.push(b[0]);
        b_ghost.extend_from_slice(&b);
        b_ghost.push(b[nx - 1]);
        let metric = (spec.coordinates == Coordinates::BedNormal)
            .then(|| BedMetric::new(nx, 1, dx, dx, &b, &[]));
        if let Some(m) = &metric {
            // As a raster's west and east ghosts (`Raster2d::with_walls`): an outflow
            // continues the bed's slope (the edge cell's gradient), so that a flow on
            // a slope cut by the edge leaves it; a wall keeps the edge cell's bed. The
            // potential is the bed.
            let ghost = |kind: BoundaryKind, edge: f64, slope: f64| match kind {
                BoundaryKind::Wall => edge,
                BoundaryKind::Outflow => edge + slope,
            };
            b_ghost[0] = ghost(spec.left, b[0], -m.gx[0] * dx);
            b_ghost[nx + 1] = ghost(spec.right, b[nx - 1], m.gx[nx - 1] * dx);
            z.copy_from_slice(&b_ghost);
        }
        Line {
            nx,
            x_min: spec.x_min,
            dx,
            x,
            b,
            b_ghost,
            z,
            g_n,
            theta,
            coordinates: spec.coordinates,
            left: spec.left,
            right: spec.right,
            metric,
        }
    }

    pub fn x_max(&self) -> f64 {
        self.x_min + self.nx as f64 * self.dx
    }

    /// The bed's metric in the bed-normal frame (`None` in the other frames).
    #[inline(always)]
    pub fn metric(&self) -> Option<&BedMetric> {
        self.metric.as_ref()
    }

    /// The line without the centrifugal term in the basal normal stress of the
    /// bed-normal frame (`domain.curvature = false`; nothing changes in the others).
    pub fn without_friction_curvature(mut self) -> Line {
        if let Some(m) = &mut self.metric {
            m.in_friction = false;
        }
        self
    }
}

impl Grid for Line {
    fn cells(&self) -> usize {
        self.nx
    }

    fn centre(&self, cell: usize) -> Point {
        Point {
            x: self.x[cell],
            y: 0.0,
        }
    }

    fn axis_names(&self) -> &'static [&'static str] {
        &["x"]
    }

    fn axis(&self, axis: usize) -> &[f64] {
        assert_eq!(axis, 0, "a line has one axis");
        &self.x
    }

    fn bed(&self) -> &[f64] {
        &self.b
    }

    fn has_outflow(&self) -> bool {
        self.left == BoundaryKind::Outflow || self.right == BoundaryKind::Outflow
    }

    /// Linear interpolation between the two centres around `p.x`
    /// ([`interpolate`]); the boundary cell's value outside them.
    fn locate(&self, p: Point) -> Stencil {
        let (i, w) = interpolate(&self.x, self.dx, p.x);
        if w == 0.0 {
            Stencil::one(i)
        } else {
            Stencil::two((i, 1.0 - w), (i + 1, w))
        }
    }

    fn cfl_length(&self) -> f64 {
        self.dx
    }

    fn grid_spec(&self) -> GridSpec {
        GridSpec::Line(LineGeometry {
            nx: self.nx,
            x_min: self.x_min,
            x_max: self.x_max(),
            dx: self.dx,
        })
    }
}

/// Left cell and weight of the linear interpolation at `xg` between the cell centres
/// `x` (uniform spacing `dx`): v(xg) = (1 − w) v\[i\] + w v\[i + 1\] (v\[i\] alone when
/// w = 0, which is also the answer outside the centres).
pub fn interpolate(x: &[f64], dx: f64, xg: f64) -> (usize, f64) {
    let n = x.len();
    if n < 2 || xg <= x[0] {
        return (0, 0.0);
    }
    if xg >= x[n - 1] {
        return (n - 1, 0.0);
    }
    let mut i = (((xg - x[0]) / dx).floor() as usize).min(n - 2);
    // Guard the floor against rounding of the centres.
    if xg < x[i] && i > 0 {
        i -= 1;
    } else if xg >= x[i + 1] {
        i += 1;
    }
    if xg == x[i] {
        return (i, 0.0);
    }
    (i, ((xg - x[i]) / dx).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(coordinates: Coordinates, left: BoundaryKind, right: BoundaryKind) -> LineSpec {
        LineSpec {
            x_min: 0.0,
            x_max: 4.0,
            cells: 4,
            slope_deg: 0.0,
            coordinates,
            left,
            right,
        }
    }

    /// In the bed-normal frame an outflow's ghost bed continues the edge cell's slope
    /// and a wall's keeps the edge bed, the potential is the bed, and the metric is
    /// the bed's (b = x² at x = 0.5 … 3.5: b_x = 2x where centred, one-sided at the
    /// ends, and b_xx the differences of b_x); the other frames keep the edge bed and
    /// have no metric.
    #[test]
    fn a_bed_normal_line_has_the_rasters_ghost_beds_and_the_beds_metric() {
        let bed: Vec<f64> = (0..4).map(|i| (i as f64 + 0.5).powi(2)).collect();
        let (wall, outflow) = (BoundaryKind::Wall, BoundaryKind::Outflow);
        let line = Line::new(&spec(Coordinates::BedNormal, outflow, wall), bed.clone());
        let m = line.metric().expect("a metric");
        assert_eq!(m.gx, [2.0, 3.0, 5.0, 6.0]);
        assert_eq!(m.gy, [0.0; 4]);
        assert_eq!(m.hxx, [1.0, 1.5, 1.5, 1.0]);
        assert_eq!((m.hxy.clone(), m.hyy.clone()), (vec![0.0; 4], vec![0.0; 4]));
        assert_eq!(line.b_ghost, [0.25 - 2.0, 0.25, 2.25, 6.25, 12.25, 12.25]);
        assert_eq!(line.z, line.b_ghost);
        assert_eq!(line.g_n, GRAVITY);
        assert!(
            m.in_friction
                && !line
                    .without_friction_curvature()
                    .metric()
                    .unwrap()
                    .in_friction
        );
        let flat = Line::new(&spec(Coordinates::Cartesian, outflow, wall), bed);
        assert!(flat.metric().is_none());
        assert_eq!(flat.b_ghost[0], 0.25);
    }
}
