//! The layered state on a raster: the multilayer model of `state::layered` in two
//! horizontal dimensions. One material split into N layers of fixed fractions l_α
//! (Σ l_α = 1; Fernández-Nieto et al. 2016, eq. 19, Escalante et al. 2023 notation),
//! each with its velocity (u_α, v_α):
//!
//!   h per cell (nx·ny, row-major, cell = j·nx + i),
//!   (hu)_α = h u_α and (hv)_α = h v_α per cell and layer ((nx·ny)·N, cell-major:
//!   `hu[cell·N + α]`, so that a column is contiguous for the viscous step).
//!
//! No ghost ring: the boundary rules (a wall mirrors h and reverses the normal
//! discharges, an outflow copies the edge cell) are applied by the stages at the edge
//! faces, as for the monolayer raster state (`state::layered_2d`).

use crate::physics::shallow::velocity;

/// h and the layer discharges per cell of a raster of `nx` × `ny` cells.
#[derive(Debug, PartialEq)]
pub struct LayeredRaster {
    pub nx: usize,
    pub ny: usize,
    pub layers: usize,
    /// Layer fractions l_α (Σ l_α = 1).
    pub l: Vec<f64>,
    /// Total thickness, nx·ny.
    pub h: Vec<f64>,
    /// Layer discharges along x and y, (nx·ny)·N each, cell-major.
    pub hu: Vec<f64>,
    pub hv: Vec<f64>,
}

// `Clone` by hand: the run loop copies the state into its backup every step, and the
// derived `clone_from` would allocate new buffers.
impl Clone for LayeredRaster {
    fn clone(&self) -> Self {
        LayeredRaster {
            nx: self.nx,
            ny: self.ny,
            layers: self.layers,
            l: self.l.clone(),
            h: self.h.clone(),
            hu: self.hu.clone(),
            hv: self.hv.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        (self.nx, self.ny, self.layers) = (source.nx, source.ny, source.layers);
        self.l.clone_from(&source.l);
        self.h.clone_from(&source.h);
        self.hu.clone_from(&source.hu);
        self.hv.clone_from(&source.hv);
    }
}

impl LayeredRaster {
    /// The state of `nx` × `ny` cells with layer fractions `l`, thickness `h` (nx·ny)
    /// and every layer moving with the depth-averaged velocity (`u`, `v`) of its cell.
    pub fn from_velocities(
        (nx, ny): (usize, usize),
        l: &[f64],
        h: Vec<f64>,
        u: &[f64],
        v: &[f64],
    ) -> LayeredRaster {
        let n = l.len();
        assert!(n >= 1 && h.len() == nx * ny && u.len() == h.len() && v.len() == h.len());
        let mut hu = vec![0.0; nx * ny * n];
        let mut hv = vec![0.0; nx * ny * n];
        for k in 0..nx * ny {
            hu[k * n..(k + 1) * n].fill(h[k] * u[k]);
            hv[k * n..(k + 1) * n].fill(h[k] * v[k]);
        }
        LayeredRaster {
            nx,
            ny,
            layers: n,
            l: l.to_vec(),
            h,
            hu,
            hv,
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.h.len()
    }

    /// The depth-averaged discharges (h ū, h v̄) = Σ_α l_α (hu, hv)_α of `cell`.
    pub fn mean_discharge(&self, cell: usize) -> (f64, f64) {
        let n = self.layers;
        let mean = |q: &[f64]| -> f64 {
            q[cell * n..(cell + 1) * n]
                .iter()
                .zip(&self.l)
                .map(|(q, l)| q * l)
                .sum()
        };
        (mean(&self.hu), mean(&self.hv))
    }

    /// The depth-averaged velocity (ū, v̄) of `cell` (0 in a dry cell).
    pub fn mean_velocity(&self, cell: usize) -> (f64, f64) {
        let (qx, qy) = self.mean_discharge(cell);
        let h = self.h[cell];
        (velocity(h, qx), velocity(h, qy))
    }

    /// The velocity (u_α, v_α) of layer `a` in `cell` (0 in a dry cell).
    pub fn layer_velocity(&self, cell: usize, a: usize) -> (f64, f64) {
        let (h, k) = (self.h[cell], cell * self.layers + a);
        (velocity(h, self.hu[k]), velocity(h, self.hv[k]))
    }

    /// Per-layer velocities for output: u_α and v_α layer-major (α·nx·ny + cell), 0 in
    /// dry cells (the HDF5 datasets `u_layers`, `v_layers` of shape (N, ny, nx)).
    pub fn layer_fields(&self) -> (Vec<f64>, Vec<f64>) {
        let (cells, n) = (self.cells(), self.layers);
        let mut u = vec![0.0; n * cells];
        let mut v = vec![0.0; n * cells];
        for k in 0..cells {
            for a in 0..n {
                (u[a * cells + k], v[a * cells + k]) = self.layer_velocity(k, a);
            }
        }
        (u, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clone_from_copies_into_the_existing_buffers() {
        let s = LayeredRaster::from_velocities(
            (2, 1),
            &[0.5, 0.5],
            vec![1.0, 2.0],
            &[0.5, 0.0],
            &[0.0, -1.0],
        );
        assert_eq!(s.hv, vec![0.0, 0.0, -2.0, -2.0]);
        assert_eq!(s.mean_velocity(1), (0.0, -1.0));
        let mut backup = s.clone();
        let before = (backup.h.as_ptr(), backup.hu.as_ptr(), backup.hv.as_ptr());
        let mut t = s.clone();
        t.h[1] = 7.0;
        backup.clone_from(&t);
        assert_eq!(backup, t);
        let after = (backup.h.as_ptr(), backup.hu.as_ptr(), backup.hv.as_ptr());
        assert_eq!(after, before);
    }
}
