//! Pointwise physics: no grids, no loops over cells.
//!
//! - [`dilatancy`]: the compressible μ(I)–φ law of Bouchut et al. 2021 (volume fraction φ).
//! - [`rheology`]: basal friction laws (Coulomb, μ(I)) and the inertial number.
//! - [`shallow`]: wave speeds and velocity desingularisation of the shallow layer.

pub mod dilatancy;
pub mod rheology;
pub mod shallow;
pub mod two_layer;

/// Gravitational acceleration (m/s²), as in the papers' experiments.
pub const GRAVITY: f64 = 9.81;

/// The granular material (Garres-Díaz et al. 2021, Table 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Grain density ρ_s (kg/m³).
    pub rho_s: f64,
    /// Solid volume fraction φ_s (flow density ρ = φ_s ρ_s).
    pub phi: f64,
    /// Grain diameter d_s (m).
    pub d_s: f64,
}
