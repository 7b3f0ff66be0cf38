//! The state of the two-layer submarine model (Fernández-Nieto et al. 2008): water (layer 1) over a
//! fluidised granular layer (layer 2), thicknesses H_k and discharges Q_k = H_k U_k
//! measured normal to and along the bed of a [`CurvedLine`].

use crate::grid::CurvedLine;
use crate::state::water_column::WaterColumn;

/// Two-layer state with one ghost cell on each side (length nx + 2).
#[derive(Debug, PartialEq)]
pub struct TwoLayerState {
    pub h1: Vec<f64>,
    pub q1: Vec<f64>,
    pub h2: Vec<f64>,
    pub q2: Vec<f64>,
    /// The water's layers and non-hydrostatic pressure; `None` for hydrostatic water,
    /// which carries nothing more.
    pub water: Option<WaterColumn>,
}

// `Clone` by hand: `clone_from` copies into the existing buffers (the run loop's
// backup of the state at t^n), where the derived one would allocate.
impl Clone for TwoLayerState {
    fn clone(&self) -> Self {
        TwoLayerState {
            h1: self.h1.clone(),
            q1: self.q1.clone(),
            h2: self.h2.clone(),
            q2: self.q2.clone(),
            water: self.water.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.h1.clone_from(&source.h1);
        self.q1.clone_from(&source.q1);
        self.h2.clone_from(&source.h2);
        self.q2.clone_from(&source.q2);
        self.water.clone_from(&source.water);
    }
}

impl TwoLayerState {
    pub fn zeros(nx: usize) -> Self {
        TwoLayerState {
            h1: vec![0.0; nx + 2],
            q1: vec![0.0; nx + 2],
            h2: vec![0.0; nx + 2],
            q2: vec![0.0; nx + 2],
            water: None,
        }
    }

    pub fn nx(&self) -> usize {
        self.h1.len() - 2
    }

    /// Fills the ghosts: a wall mirrors thicknesses and reverses discharges; a free
    /// boundary copies the edge state (zero gradient).
    pub fn fill_ghosts(&mut self, geom: &CurvedLine) {
        let nx = self.nx();
        for (ghost, edge, kind) in [(0, 1, geom.line.left), (nx + 1, nx, geom.line.right)] {
            let sign = kind.discharge_sign();
            self.h1[ghost] = self.h1[edge];
            self.h2[ghost] = self.h2[edge];
            self.q1[ghost] = sign * self.q1[edge];
            self.q2[ghost] = sign * self.q2[edge];
        }
    }

    /// Volume Σ H_k Δx of layer k ∈ {1, 2} over the physical cells.
    pub fn volume(&self, layer: usize, dx: f64) -> f64 {
        let h = if layer == 1 { &self.h1 } else { &self.h2 };
        h[1..=self.nx()].iter().sum::<f64>() * dx
    }

    /// Water free surface η = b + (H₁ + H₂) cos²θ at physical cell i (1-based).
    pub fn eta(&self, geom: &CurvedLine, i: usize) -> f64 {
        geom.line.b_ghost[i] + (self.h1[i] + self.h2[i]) * geom.cos2[i]
    }

    /// Interface ζ = b + H₂ cos²θ at physical cell i (1-based).
    pub fn interface(&self, geom: &CurvedLine, i: usize) -> f64 {
        geom.line.b_ghost[i] + self.h2[i] * geom.cos2[i]
    }
}
