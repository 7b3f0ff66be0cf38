//! The 1-D finite-volume grid and its geometry (seed 000 §2.1 and §4.1).
//!
//! Cells V_i = [x_{i−1/2}, x_{i+1/2}] of uniform width Δx along the reference plane
//! (local coordinates) or the horizontal (Cartesian). The gravity potential that
//! drives the flow is g_n (h + z) with
//!
//! - local coordinates: z = b(X) + b̃(X), b̃ = −X tan θ (the plane, up to a constant)
//!   and g_n = g cos θ (seed 000 eq. 15b);
//! - Cartesian coordinates: z = b(x), g_n = g (seed 000 §4.1).
//!
//! Arrays carry one ghost cell on each side: index 0 and nx + 1.

use crate::physics::GRAVITY;

/// Frame in which the shallow model is written (seed 000 §4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Along and normal to a reference plane of slope θ; gravity g cos θ normal to it.
    Local,
    /// Horizontal x, vertical z; the slope lives inside b(x) and gravity is g.
    Cartesian,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundaryKind {
    /// Reflecting wall: ghost discharge opposite, thickness mirrored (seed 003 Remark 6).
    Wall,
    /// Free outflow: ghost state copied (homogeneous Neumann).
    Outflow,
}

#[derive(Debug, Clone)]
pub struct Mesh {
    pub nx: usize,
    pub x_min: f64,
    pub dx: f64,
    /// Cell centres of the physical cells (nx).
    pub x: Vec<f64>,
    /// Bed elevation over the reference plane at the centres (nx).
    pub b: Vec<f64>,
    /// Bed over the reference plane with ghosts (nx + 2): the jumps that the
    /// hydrostatic reconstruction sees (seed 003 eq. 20).
    pub b_ghost: Vec<f64>,
    /// Potential elevation z = b + b̃ with ghosts (nx + 2).
    pub z: Vec<f64>,
    /// Gravity normal to the reference plane.
    pub g_n: f64,
    pub theta: f64,
    pub coordinates: Coordinates,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
}

/// What a mesh is built from; `b` is sampled at the cell centres.
#[derive(Debug, Clone)]
pub struct MeshSpec {
    pub x_min: f64,
    pub x_max: f64,
    pub cells: usize,
    pub slope_deg: f64,
    pub coordinates: Coordinates,
    pub left: BoundaryKind,
    pub right: BoundaryKind,
}

impl MeshSpec {
    /// Cell centres x_i = x_min + (i + ½) Δx.
    pub fn centres(&self) -> Vec<f64> {
        let dx = (self.x_max - self.x_min) / self.cells as f64;
        (0..self.cells)
            .map(|i| self.x_min + (i as f64 + 0.5) * dx)
            .collect()
    }
}

/// What the generic layers (the run loop, the output sinks, the sweeps) need of a
/// grid. A 2-D mesh would implement it with its cell list; its stages would bring
/// their own face loops (owner/neighbour cells, normals, lengths) in place of the 1-D
/// loops over k = 0..=nx, and its ghost fill in place of `fill_ghosts`.
pub trait Grid {
    /// Number of physical cells.
    fn cells(&self) -> usize;
    /// Cell centres (`/grid/x`).
    fn centres(&self) -> &[f64];
    /// Bed elevation at the centres (`/grid/b`).
    fn bed(&self) -> &[f64];
    /// Length in the CFL condition Δt ≤ CFL · length / speed (Δx in 1-D).
    fn cfl_length(&self) -> f64;
}

impl Grid for Mesh {
    fn cells(&self) -> usize {
        self.nx
    }
    fn centres(&self) -> &[f64] {
        &self.x
    }
    fn bed(&self) -> &[f64] {
        &self.b
    }
    fn cfl_length(&self) -> f64 {
        self.dx
    }
}

impl Mesh {
    /// Builds the mesh with the bed `b` sampled at the centres (`b.len() == cells`).
    pub fn new(spec: &MeshSpec, b: Vec<f64>) -> Mesh {
        assert_eq!(b.len(), spec.cells, "bed sampled at every cell centre");
        let nx = spec.cells;
        let dx = (spec.x_max - spec.x_min) / nx as f64;
        let theta = spec.slope_deg.to_radians();
        let (g_n, tan_theta) = match spec.coordinates {
            Coordinates::Local => (GRAVITY * theta.cos(), theta.tan()),
            Coordinates::Cartesian => (GRAVITY, 0.0),
        };
        let x = spec.centres();
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
        Mesh {
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
        }
    }

    pub fn x_max(&self) -> f64 {
        self.x_min + self.nx as f64 * self.dx
    }
}
