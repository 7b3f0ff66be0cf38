//! Basal friction laws, as pointwise functions of the local flow state.
//!
//! The friction force per unit area is μ p_b u/|u| with p_b the basal pressure
//! (seed 000 eq. 5 and 15b). Each law implements [`BasalFriction`]; stages are generic
//! over it, so a constant-Coulomb run is compiled without any μ(I) evaluation
//! ("leave out what a scene does not need").

mod coulomb;
mod mu_i;

pub use coulomb::Coulomb;
pub use mu_i::{inertial_number, local_inertial_number, MuI};

/// Basal friction law (seed 000 eq. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// Constant Coulomb coefficient μ (classical Savage–Hutter).
    Coulomb { mu: f64 },
    /// μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I).
    MuI { mu_s: f64, mu_2: f64, i0: f64 },
}

/// A basal friction law μ(state).
pub trait BasalFriction: Copy + Send + Sync + std::fmt::Debug {
    /// Friction coefficient for depth-averaged speed |u| (m/s), thickness h (m) and
    /// basal pressure over density p_b/ρ (m²/s², g_n h for a hydrostatic layer).
    fn mu(&self, speed: f64, h: f64, p_over_rho: f64) -> f64;
}

/// The friction coefficient of the bulk rheology at a point of the flow, used by the
/// multilayer model between layers and at the bed (seed 001 eq. 25–26, seed 003
/// eq. 10): μ(I) with the local inertial number I = d_s |∂_z u| / √(p/ρ_s), or a
/// constant μ (seed 001's "μ_s-MSM").
pub trait LocalFriction: Copy + Send + Sync + std::fmt::Debug {
    /// d_s / √(p/ρ_s) for the pressure over density p/ρ (m²/s²): times a shear rate it
    /// gives I (0 for a law that does not use I).
    fn inertial_scale(&self, p_over_rho: f64) -> f64;

    /// μ at the inertial number I.
    fn mu_at(&self, inertial_number: f64) -> f64;

    /// μ for a shear rate |∂_z u| (1/s) under the pressure over density p/ρ (m²/s²).
    #[inline(always)]
    fn mu_local(&self, shear_rate: f64, p_over_rho: f64) -> f64 {
        self.mu_at(shear_rate * self.inertial_scale(p_over_rho))
    }
}
