//! The layered state (architecture note, "one state, many models").
//!
//! Cell averages of the total thickness h and of the layer discharges (hu)_α = h u_α,
//! α = 1..N (seed 003 notation: layer α has thickness l_α h), with one ghost cell on
//! each side (index 0 and nx + 1). The depth-averaged discharge is Σ_α l_α (hu)_α.
//! Discharges are stored cell-major, `hu[j * N + α]`, so the per-column work of the
//! multilayer viscous step reads contiguous memory. N = 1 is the Savage–Hutter model.

use crate::mesh::Mesh;
use crate::physics::shallow::velocity;
use crate::scenario::BoundaryKind;

#[derive(Debug, Clone, PartialEq)]
pub struct State {
    pub nx: usize,
    pub layers: usize,
    /// Layer fractions l_α (Σ l_α = 1).
    pub l: Vec<f64>,
    /// Total thickness, nx + 2 with ghosts.
    pub h: Vec<f64>,
    /// Layer discharges, (nx + 2)·N, cell-major.
    pub hu: Vec<f64>,
}

impl State {
    /// A state with thickness `h` and depth-averaged velocity `u` (physical cells),
    /// every layer moving with u.
    pub fn from_profiles(mesh: &Mesh, l: &[f64], h: &[f64], u: &[f64]) -> State {
        let nx = mesh.nx;
        let layers = l.len();
        assert!(h.len() == nx && u.len() == nx && layers >= 1);
        let mut s = State {
            nx,
            layers,
            l: l.to_vec(),
            h: vec![0.0; nx + 2],
            hu: vec![0.0; (nx + 2) * layers],
        };
        for i in 0..nx {
            s.h[i + 1] = h[i];
            for a in 0..layers {
                s.hu[(i + 1) * layers + a] = h[i] * u[i];
            }
        }
        s.fill_ghosts(mesh);
        s
    }

    /// Ghost cells per seed 003 Remark 6: thickness copied (homogeneous Neumann);
    /// discharge copied (outflow) or reversed (wall).
    pub fn fill_ghosts(&mut self, mesh: &Mesh) {
        let (nx, n) = (self.nx, self.layers);
        self.h[0] = self.h[1];
        self.h[nx + 1] = self.h[nx];
        let sign = |kind: BoundaryKind| match kind {
            BoundaryKind::Wall => -1.0,
            BoundaryKind::Outflow => 1.0,
        };
        let (sl, sr) = (sign(mesh.left), sign(mesh.right));
        for a in 0..n {
            self.hu[a] = sl * self.hu[n + a];
            self.hu[(nx + 1) * n + a] = sr * self.hu[nx * n + a];
        }
    }

    /// Depth-averaged velocity of cell j (ghost-inclusive index).
    #[inline(always)]
    pub fn mean_velocity(&self, j: usize) -> f64 {
        let n = self.layers;
        if n == 1 {
            return velocity(self.h[j], self.hu[j]);
        }
        let q: f64 = self.hu[j * n..(j + 1) * n]
            .iter()
            .zip(&self.l)
            .map(|(q, l)| q * l)
            .sum();
        velocity(self.h[j], q)
    }

    /// Physical-cell thickness (without ghosts).
    pub fn h_interior(&self) -> &[f64] {
        &self.h[1..=self.nx]
    }
}
