//! Pointwise physics: no grids, no loops over cells.
//!
//! - [`rheology`]: basal friction laws (Coulomb, μ(I)) and the inertial number.
//! - [`shallow`]: wave speeds and velocity desingularisation of the shallow layer.

pub mod rheology;
pub mod shallow;

/// Gravitational acceleration (m/s²), as in the seeds' experiments.
pub const GRAVITY: f64 = 9.81;
