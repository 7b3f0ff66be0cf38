//! The vertical structure of the submarine model's water when its pressure is
//! non-hydrostatic (`submarine.water_pressure = "nonhydrostatic"`): M layers of
//! fractions l_α = 1/M of the water depth, each with its horizontal velocity
//! u_α = U₁ + u'_α (U₁ = Q₁/H₁ the depth mean the two-layer step carries, u'_α the
//! layer's deviation, Σ_α l_α u'_α = 0), its mean vertical velocity w_α, and the
//! non-hydrostatic pressure (over water density) p_{α−1/2} at the base of each layer
//! at the nx + 1 faces. A hydrostatic run carries none of it
//! ([`crate::state::TwoLayerState::water`] is `None`).

/// The non-hydrostatic unknowns of the water, per cell with ghosts (nx + 2) and layer
/// (cell-major, index i·M + α − 1), and per face (face-major, index k·M + α − 1; face
/// k between the ghost-inclusive cells k and k + 1; the surface value p_{M+1/2} = 0
/// is not stored; α = 1 is the interface with the grains).
#[derive(Debug, PartialEq)]
pub struct WaterColumn {
    pub layers: usize,
    /// u'_α: deviation of the layer velocity from the depth mean (m/s).
    pub du: Vec<f64>,
    /// w_α: mean vertical velocity of the layer (m/s).
    pub w: Vec<f64>,
    /// p_{α−1/2} at the faces (m²/s², pressure over water density).
    pub p: Vec<f64>,
}

// `Clone` by hand, as the states: `clone_from` copies into the existing buffers.
impl Clone for WaterColumn {
    fn clone(&self) -> Self {
        WaterColumn {
            layers: self.layers,
            du: self.du.clone(),
            w: self.w.clone(),
            p: self.p.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.layers = source.layers;
        self.du.clone_from(&source.du);
        self.w.clone_from(&source.w);
        self.p.clone_from(&source.p);
    }
}

impl WaterColumn {
    /// M layers at rest with zero pressure on nx cells.
    pub fn at_rest(nx: usize, layers: usize) -> Self {
        assert!(layers >= 1);
        WaterColumn {
            layers,
            du: vec![0.0; (nx + 2) * layers],
            w: vec![0.0; (nx + 2) * layers],
            p: vec![0.0; (nx + 1) * layers],
        }
    }

    /// Ghost cells: u'_α copied (free boundary) or reversed (wall: `sign` = −1, as the
    /// discharges), w_α copied.
    pub fn fill_ghosts(&mut self, nx: usize, sign_left: f64, sign_right: f64) {
        let n = self.layers;
        for a in 0..n {
            self.du[a] = sign_left * self.du[n + a];
            self.w[a] = self.w[n + a];
            self.du[(nx + 1) * n + a] = sign_right * self.du[nx * n + a];
            self.w[(nx + 1) * n + a] = self.w[nx * n + a];
        }
    }

    /// The pressure at the base of the water (the grain interface) at face k.
    #[inline(always)]
    pub fn base_pressure(&self, k: usize) -> f64 {
        self.p[k * self.layers]
    }
}
