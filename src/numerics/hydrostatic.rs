//! Step 1 of the splitting: the hyperbolic (hydrostatic) problem (seed 000 eq. 17–24,
//! seed 003 eq. 19–21), for the total mass and the discharge of a monolayer:
//!
//!   ∂_t h + ∂_X(hu) = 0,   ∂_t(hu) + ∂_X(hu²) + g_n h ∂_X(h + z) = 0.
//!
//! Path-conservative finite volumes with the HLL-type PVM diffusion:
//!
//!   U_i ← U_i − Δt/Δx (𝓕_{i+1/2} − 𝓕_{i−1/2} + ½(𝓢_{i+1/2} + 𝓢_{i−1/2})),
//!   𝓕 = ½(F_c(U_L) + F_c(U_R)) − ½[α_0 (Ũ⁺ − Ũ⁻) + α_1 (F_c(U_R) − F_c(U_L) + 𝓢̃)],
//!   𝓢 = (0, g_n ½(h_L + h_R)(h⁺ − h⁻)),
//!
//! with the hydrostatic reconstruction h⁻ = max(0, h_L − (Δb)_+), h⁺ = max(0, h_R − (−Δb)_+)
//! over the bed b relative to the reference plane (seed 003 eq. 20), the plane's own
//! slope entering 𝓢 as the jump Δb̃ of the potential (zero across a wall). The source
//! enters with a minus sign: seed 000 eq. (20) prints "+", which contradicts
//! ∂_t(hu) = −g_n h ∂_X(h + z).
//!
//! Two deliberate departures from the printed flux, both for positivity and both
//! tested (`tests/properties.rs`, `tests/analytic.rs`):
//! - F_c is evaluated at the reconstructed states U^± = (h^±, h^± u) (as in Audusse
//!   et al.'s hydrostatic reconstruction), not at the cell states: with cell states a
//!   wet cell moving away from a dry step drains the dry cell, for any Δt.
//! - Reconstructing over b only (not b + b̃) keeps thin layers on steep planes
//!   visible: over b + b̃ every layer thinner than tan θ Δx (2 mm at 22° with
//!   Δx = 5 mm, thicker than the erodible beds of seed 001 §4.2) would be clipped
//!   to h⁺ = 0 and feel a reduced gravity.
//!
//! Granular masses at rest with |∂_X(h + z)| ≤ μ_s are kept exactly at rest by the
//! Coulomb-aware reconstruction Ũ^± (seed 000 eq. 22–24, seed 003 §4 step 1): the
//! jump Δz is replaced by Δz + ΔC, ΔC = −f Δx / g_n,
//!
//!   f = −proj_{g_n μ}( u_{1/2}/Δt − g_n (η_R − η_L)/Δx ),   η = h + z,
//!
//! so that at rest ĥ⁻ = ĥ⁺ and the mass diffusion vanishes; 𝓢̃ uses ĥ^± too
//! (seed 003 eq. 21). We follow seed 003's sign of u/Δt (seed 000 eq. 23 has the
//! opposite sign, which would make friction accelerate a moving mass) and its
//! division by g_n (without it ΔC is not a length).
//!
//! Positivity: if a step would empty a cell (possible at wet/dry fronts, where the
//! Coulomb-aware diffusion and the HLL bounds stop matching, e.g. a thin layer
//! leaving a dry cell on a slope), the outgoing mass and momentum fluxes of that cell
//! are scaled to what it holds (the "draining time" limiter of Bollermann, Chen,
//! Kurganov & Noelle 2013). Each interface flux is used by both neighbours, so mass
//! stays exactly conserved; steps that need no limiting are untouched.
//!
//! Wave speeds S_L, S_R: Einfeldt-type bounds with Roe averages (seed 000 after eq. 21).
//! Wet/dry fronts: an emerging bed (h_L > 0, h_R dry, h_L + z_L < z_R, and its mirror)
//! is seen with the wet state's velocity set to zero (seed 003 Remark 2).

use super::{Stage, StageError};
use crate::mesh::Mesh;
use crate::physics::rheology::BasalFriction;
use crate::physics::shallow::{celerity, velocity, H_DRY};
use crate::state::State;

/// The hydrostatic step for N = 1, generic over the basal friction law (used in ΔC).
#[derive(Debug)]
pub struct HydrostaticStep<L: BasalFriction> {
    law: L,
    /// Per interface (nx + 1): mass flux, momentum flux, pressure source 𝓢.
    flux_h: Vec<f64>,
    flux_hu: Vec<f64>,
    source: Vec<f64>,
    h_new: Vec<f64>,
    /// Draining factors θ_j ∈ [0, 1] (nx + 2), used only when a cell would empty.
    drain: Vec<f64>,
}

/// Left or right state of an interface.
#[derive(Debug, Clone, Copy)]
struct Side {
    h: f64,
    u: f64,
    /// Bed over the reference plane.
    b: f64,
    /// Potential elevation b + b̃.
    z: f64,
    /// √h, computed once per cell (it serves both interfaces of the cell).
    sqrt_h: f64,
}

/// Interface contribution: (mass flux, momentum flux, pressure source 𝓢).
#[inline(always)]
fn interface<L: BasalFriction>(
    law: &L,
    mut l: Side,
    mut r: Side,
    g_n: f64,
    dx: f64,
    dt: f64,
) -> (f64, f64, f64) {
    let l_dry = l.h <= H_DRY;
    let r_dry = r.h <= H_DRY;
    if l_dry && r_dry {
        return (0.0, 0.0, 0.0);
    }
    // Emerging bed: the wet side cannot push mass up a dry step it does not overtop.
    if r_dry && l.h + l.b < r.b {
        l.u = 0.0;
    }
    if l_dry && r.h + r.b < l.b {
        r.u = 0.0;
    }
    let db = r.b - l.b;
    let dz = r.z - l.z;
    let d_plane = dz - db;
    let h_minus = (l.h - db.max(0.0)).max(0.0);
    let h_plus = (r.h - (-db).max(0.0)).max(0.0);

    // Roe averages and HLL wave-speed bounds.
    let (sl, sr) = (l.sqrt_h, r.sqrt_h);
    let u_roe = (sl * l.u + sr * r.u) / (sl + sr);
    let h_roe = 0.5 * (l.h + r.h);
    let c_roe = celerity(g_n, h_roe);
    let sqrt_g = g_n.sqrt();
    let s_left = (l.u - sqrt_g * sl).min(u_roe - c_roe);
    let s_right = (r.u + sqrt_g * sr).max(u_roe + c_roe);
    let spread = s_right - s_left;
    if spread <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let alpha0 = (s_right * s_left.abs() - s_left * s_right.abs()) / spread;
    let alpha1 = (s_right.abs() - s_left.abs()) / spread;

    // Coulomb-aware reconstruction (ΔC): friction up to its threshold acts as bed.
    let mu = law.mu(u_roe.abs(), h_roe, g_n * h_roe);
    let threshold = g_n * mu;
    let drive = u_roe / dt - g_n * ((r.h + r.z) - (l.h + l.z)) / dx;
    let f = -drive.clamp(-threshold, threshold);
    let dz_c = dz - f * dx / g_n;
    let hc_minus = (l.h - dz_c.max(0.0)).max(0.0);
    let hc_plus = (r.h - (-dz_c).max(0.0)).max(0.0);

    let (q_l, q_r) = (h_minus * l.u, h_plus * r.u);
    let (m_l, m_r) = (q_l * l.u, q_r * r.u);
    let g_hbar = g_n * h_roe;
    let source = g_hbar * (h_plus - h_minus + d_plane);
    let source_c = g_hbar * (hc_plus - hc_minus);

    let flux_h = 0.5 * (q_l + q_r) - 0.5 * (alpha0 * (hc_plus - hc_minus) + alpha1 * (q_r - q_l));
    let flux_hu = 0.5 * (m_l + m_r)
        - 0.5 * (alpha0 * (hc_plus * r.u - hc_minus * l.u) + alpha1 * (m_r - m_l + source_c));
    (flux_h, flux_hu, source)
}

impl<L: BasalFriction> HydrostaticStep<L> {
    pub fn new(law: L, nx: usize) -> Self {
        HydrostaticStep {
            law,
            flux_h: vec![0.0; nx + 1],
            flux_hu: vec![0.0; nx + 1],
            source: vec![0.0; nx + 1],
            h_new: vec![0.0; nx + 2],
            drain: vec![1.0; nx + 2],
        }
    }
}

impl<L: BasalFriction> HydrostaticStep<L> {
    /// h_new = h − r (F_{i+1/2} − F_{i−1/2}); returns the smallest value and its cell.
    fn update_mass(&mut self, h: &[f64], r: f64) -> (f64, usize) {
        let mut worst = (f64::INFINITY, 1usize);
        let interior = &h[1..h.len() - 1];
        for (k, (hi, f)) in interior.iter().zip(self.flux_h.windows(2)).enumerate() {
            let hn = hi - r * (f[1] - f[0]);
            self.h_new[k + 1] = hn;
            if hn < worst.0 {
                worst = (hn, k + 1);
            }
        }
        worst
    }

    /// Scales every interface flux by the draining factor of its donor cell,
    /// θ_j = min(1, h_j / (r · outflow_j)).
    fn limit_draining(&mut self, h: &[f64], r: f64) {
        let nx = h.len() - 2;
        let interior = &h[1..=nx];
        for (k, (hj, f)) in interior.iter().zip(self.flux_h.windows(2)).enumerate() {
            let need = r * (f[1].max(0.0) + (-f[0]).max(0.0));
            self.drain[k + 1] = if need > *hj { hj.max(0.0) / need } else { 1.0 };
        }
        for k in 0..=nx {
            let donor = if self.flux_h[k] > 0.0 { k } else { k + 1 };
            let theta = self.drain[donor];
            self.flux_h[k] *= theta;
            self.flux_hu[k] *= theta;
        }
        self.drain[1..=nx].fill(1.0);
    }
}

impl<L: BasalFriction> Stage for HydrostaticStep<L> {
    fn name(&self) -> &'static str {
        "hyperbolic"
    }

    fn apply(&mut self, mesh: &Mesh, dt: f64, state: &mut State) -> Result<(), StageError> {
        debug_assert_eq!(state.layers, 1);
        let nx = mesh.nx;
        let (g_n, dx) = (mesh.g_n, mesh.dx);
        let side = |j: usize| Side {
            h: state.h[j],
            u: velocity(state.h[j], state.hu[j]),
            b: mesh.b_ghost[j],
            z: mesh.z[j],
            sqrt_h: state.h[j].max(0.0).sqrt(),
        };
        let mut left = side(0);
        for k in 0..=nx {
            let right = side(k + 1);
            let (fh, fhu, s) = interface(&self.law, left, right, g_n, dx, dt);
            self.flux_h[k] = fh;
            self.flux_hu[k] = fhu;
            self.source[k] = s;
            left = right;
        }

        // Mass first; limit the fluxes of cells that would empty, then refuse the step
        // (state untouched) if anything is still negative beyond round-off.
        let r = dt / dx;
        let mut worst = self.update_mass(&state.h, r);
        if worst.0 < 0.0 {
            self.limit_draining(&state.h, r);
            worst = self.update_mass(&state.h, r);
        }
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                x: mesh.x[worst.1 - 1],
                h: worst.0,
            });
        }
        for i in 1..=nx {
            // Clip round-off below zero; `f64::max` would also turn a NaN into 0 and
            // hide a blow-up from the run's NaN check.
            let hn = self.h_new[i];
            state.h[i] = if hn < 0.0 { 0.0 } else { hn };
            state.hu[i] -= r
                * (self.flux_hu[i] - self.flux_hu[i - 1]
                    + 0.5 * (self.source[i] + self.source[i - 1]));
            if state.h[i] <= H_DRY {
                state.hu[i] = 0.0;
            }
        }
        state.fill_ghosts(mesh);
        Ok(())
    }
}

// Non-hydrostatic extension (issue 3): the mass fluxes of the last step transport the
// normal discharge hw as a passive scalar (src/numerics/nonhydrostatic.rs).
impl<L: BasalFriction> HydrostaticStep<L> {
    /// Mass fluxes 𝓕^h of the last step at the faces k = 0..=nx (face k lies between
    /// the ghost-inclusive cells k and k + 1).
    pub fn mass_flux(&self) -> &[f64] {
        &self.flux_h
    }
}
