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
//! with the hydrostatic reconstruction h⁻ = max(0, h_L − (Δz)_+),
//! h⁺ = max(0, h_R − (−Δz)_+) (seed 000 eq. 19). The source enters with a minus sign:
//! seed 000 eq. (20) prints "+", which contradicts ∂_t(hu) = −g_n h ∂_X(h + z).
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
}

/// Left or right state of an interface.
#[derive(Debug, Clone, Copy)]
struct Side {
    h: f64,
    u: f64,
    z: f64,
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
    if r_dry && l.h + l.z < r.z {
        l.u = 0.0;
    }
    if l_dry && r.h + r.z < l.z {
        r.u = 0.0;
    }
    let dz = r.z - l.z;
    let h_minus = (l.h - dz.max(0.0)).max(0.0);
    let h_plus = (r.h - (-dz).max(0.0)).max(0.0);

    // Roe averages and HLL wave-speed bounds.
    let (sl, sr) = (l.h.max(0.0).sqrt(), r.h.max(0.0).sqrt());
    let u_roe = (sl * l.u + sr * r.u) / (sl + sr);
    let h_roe = 0.5 * (l.h + r.h);
    let c_roe = celerity(g_n, h_roe);
    let s_left = (l.u - celerity(g_n, l.h)).min(u_roe - c_roe);
    let s_right = (r.u + celerity(g_n, r.h)).max(u_roe + c_roe);
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

    let (q_l, q_r) = (l.h * l.u, r.h * r.u);
    let (m_l, m_r) = (q_l * l.u, q_r * r.u);
    let g_hbar = g_n * h_roe;
    let source = g_hbar * (h_plus - h_minus);
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
        }
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
            z: mesh.z[j],
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

        // Mass first: refuse the step (state untouched) if it would empty a cell.
        let r = dt / dx;
        let mut worst = (f64::INFINITY, 0usize);
        for i in 1..=nx {
            let h = state.h[i] - r * (self.flux_h[i] - self.flux_h[i - 1]);
            self.h_new[i] = h;
            if h < worst.0 {
                worst = (h, i);
            }
        }
        // Round-off below zero is clipped; anything larger is a CFL violation.
        let tolerance = -1e-14 * (1.0 + state.h[worst.1].abs());
        if worst.0 < tolerance {
            return Err(StageError::NegativeThickness {
                x: mesh.x[worst.1 - 1],
                h: worst.0,
            });
        }
        for i in 1..=nx {
            state.h[i] = self.h_new[i].max(0.0);
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
