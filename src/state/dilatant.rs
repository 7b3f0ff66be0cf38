//! State of the dilatant model: the conservative variables U = (φh, φhv, φ^α h) of
//! Bouchut et al. 2021, eq. (B.10) per cell, with one ghost cell on each side (index 0 and nx + 1),
//! and the primitive (h, v, φ) derived from them.
//!
//! A dry cell (φh = 0) does not determine φ; the fluxes still need it (Bouchut et al. 2021, §3.1
//! after eq. 3.13), so φ of a dry cell is max(φ_{i−1}, φ_{i+1}) over its wet
//! neighbours (eq. 3.14), or its last value when both are dry.

use crate::grid::Line;
use crate::physics::dilatancy::{phi_from_ratio, phi_power, Conserved, Primitive};
use crate::physics::shallow::{velocity, H_DRY};

#[derive(Debug, PartialEq)]
pub struct DilatantState {
    pub nx: usize,
    /// α of the third variable (Bouchut et al. 2021 uses 2).
    pub alpha: f64,
    /// φh, φhv, φ^α h with ghosts (nx + 2).
    pub m: Vec<f64>,
    pub q: Vec<f64>,
    pub w: Vec<f64>,
    /// Primitive h, v, φ with ghosts, kept in step with (m, q, w) by [`Self::update_primitives`].
    pub h: Vec<f64>,
    pub v: Vec<f64>,
    pub phi: Vec<f64>,
    /// Thickness discharge hv with ghosts. The split scheme (`numerics::dilatant::split`) advances
    /// (h, hv, φ) only and leaves m, q, w, v stale; the Appendix B scheme keeps hv = h v.
    /// Diagnostics, snapshots and [`Self::grain_volume`], [`Self::energy`] read (h, hv, φ).
    pub hu: Vec<f64>,
}

// `Clone` by hand: `clone_from` copies into the existing buffers (the run loop's
// backup of the state at t^n), where the derived one would allocate.
impl Clone for DilatantState {
    fn clone(&self) -> Self {
        DilatantState {
            nx: self.nx,
            alpha: self.alpha,
            m: self.m.clone(),
            q: self.q.clone(),
            w: self.w.clone(),
            h: self.h.clone(),
            v: self.v.clone(),
            phi: self.phi.clone(),
            hu: self.hu.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.nx = source.nx;
        self.alpha = source.alpha;
        self.m.clone_from(&source.m);
        self.q.clone_from(&source.q);
        self.w.clone_from(&source.w);
        self.h.clone_from(&source.h);
        self.v.clone_from(&source.v);
        self.phi.clone_from(&source.phi);
        self.hu.clone_from(&source.hu);
    }
}

impl DilatantState {
    /// A state from thickness, velocity and volume fraction at the physical cells.
    pub fn from_profiles(line: &Line, alpha: f64, h: &[f64], v: &[f64], phi: &[f64]) -> Self {
        let nx = line.nx;
        assert!(h.len() == nx && v.len() == nx && phi.len() == nx);
        let mut s = DilatantState {
            nx,
            alpha,
            m: vec![0.0; nx + 2],
            q: vec![0.0; nx + 2],
            w: vec![0.0; nx + 2],
            h: vec![0.0; nx + 2],
            v: vec![0.0; nx + 2],
            phi: vec![0.0; nx + 2],
            hu: vec![0.0; nx + 2],
        };
        for i in 0..nx {
            let u = Primitive {
                h: h[i],
                v: v[i],
                phi: phi[i],
            }
            .conserved(alpha);
            s.m[i + 1] = u.m;
            s.q[i + 1] = u.q;
            s.w[i + 1] = u.w;
            s.phi[i + 1] = phi[i];
        }
        s.update_primitives(line);
        // h and hv exactly as given (as the monolayer's state has them), not m/φ.
        for i in 0..nx {
            s.h[i + 1] = h[i];
            s.hu[i + 1] = h[i] * v[i];
        }
        s.fill_thickness_ghosts(line);
        s.phi[0] = s.phi[1];
        s.phi[nx + 1] = s.phi[nx];
        s
    }

    /// Ghosts of (h, hv) as the monolayer's: h copied, hv copied (outflow) or
    /// reversed (wall).
    pub fn fill_thickness_ghosts(&mut self, line: &Line) {
        let nx = self.nx;
        self.h[0] = self.h[1];
        self.h[nx + 1] = self.h[nx];
        self.hu[0] = line.left.discharge_sign() * self.hu[1];
        self.hu[nx + 1] = line.right.discharge_sign() * self.hu[nx];
    }

    /// Conservative variables of cell j.
    #[inline(always)]
    pub fn conserved(&self, j: usize) -> Conserved {
        Conserved {
            m: self.m[j],
            q: self.q[j],
            w: self.w[j],
        }
    }

    /// Ghost cells: a wall mirrors the edge cell with the discharge reversed, an
    /// outflow copies it (as the other models, Escalante et al. 2023, Remark 6).
    pub fn fill_ghosts(&mut self, line: &Line) {
        let nx = self.nx;
        for (ghost, edge, kind) in [(0, 1, line.left), (nx + 1, nx, line.right)] {
            self.m[ghost] = self.m[edge];
            self.q[ghost] = kind.discharge_sign() * self.q[edge];
            self.w[ghost] = self.w[edge];
        }
    }

    /// Fills the ghosts and recomputes (h, v, φ) everywhere; dry cells take φ from
    /// eq. (3.14).
    pub fn update_primitives(&mut self, line: &Line) {
        self.fill_ghosts(line);
        for j in 0..self.nx + 2 {
            self.update_cell(j);
        }
        self.fill_dry_fractions();
    }

    /// (h, v, φ) of cell j from (m, q, w); a dry cell gets h = v = 0 and keeps φ.
    #[inline(always)]
    pub fn update_cell(&mut self, j: usize) {
        let m = self.m[j];
        if m > 0.0 {
            let phi = phi_from_ratio(self.w[j] / m, self.alpha);
            let h = m / phi;
            self.phi[j] = phi;
            self.h[j] = h;
            self.v[j] = if h > H_DRY { self.q[j] / m } else { 0.0 };
            self.hu[j] = h * self.v[j];
        } else {
            self.h[j] = 0.0;
            self.v[j] = 0.0;
            self.hu[j] = 0.0;
        }
    }

    /// φ of the dry cells from their wet neighbours (eq. 3.14), ghosts included.
    pub fn fill_dry_fractions(&mut self) {
        let n = self.nx + 2;
        for j in 0..n {
            if self.m[j] > 0.0 {
                continue;
            }
            let wet = |k: usize| (k < n && self.m[k] > 0.0).then(|| self.phi[k]);
            let left = if j > 0 { wet(j - 1) } else { None };
            let right = wet(j + 1);
            let phi = match (left, right) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            if let Some(phi) = phi {
                self.phi[j] = phi;
            }
        }
    }

    /// Sets φ of cell j, keeping φh and v (the dilatancy step, eq. 3.19).
    #[inline(always)]
    pub fn set_fraction(&mut self, j: usize, phi: f64) {
        self.phi[j] = phi;
        self.w[j] = self.m[j] * phi_power(phi, self.alpha);
        if self.m[j] > 0.0 {
            self.h[j] = self.m[j] / phi;
            self.hu[j] = self.h[j] * self.v[j];
        }
    }

    /// Mass of grains ∫φh dx over the physical cells (per unit width, per ρ_s).
    pub fn grain_volume(&self, line: &Line) -> f64 {
        (1..=self.nx).map(|j| self.phi[j] * self.h[j]).sum::<f64>() * line.dx
    }

    /// Total energy ∫(φh v²/2 + g_c φh²/2 + g_c φh b̂) dx (Bouchut et al. 2021, eq. 2.7, per ρ_s).
    pub fn energy(&self, line: &Line) -> f64 {
        (1..=self.nx)
            .map(|j| {
                Primitive {
                    h: self.h[j],
                    v: velocity(self.h[j], self.hu[j]),
                    phi: self.phi[j],
                }
                .energy(line.g_n, line.z[j])
            })
            .sum::<f64>()
            * line.dx
    }
}
