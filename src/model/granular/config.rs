//! The granular model's own options, as validated from the scenario (`scenario/`
//! fills them; the model never reads the TOML).

use crate::numerics::viscous::{
    BasalCondition, Regularization, Sidewall, ViscosityTime, ViscousOptions,
};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pressure {
    Hydrostatic,
    NonHydrostatic,
}

/// Options of the multilayer model (`model.layers > 1`); the monolayer model ignores
/// `regularization`, `c_msm` and `static_threshold` and rejects the others.
#[derive(Debug, Clone, PartialEq)]
pub struct MultilayerSpec {
    /// Layer fractions l_α, bottom first (`model.layer_fractions`, uniform by default).
    pub layer_fractions: Vec<f64>,
    pub basal: BasalCondition,
    pub regularization: Regularization,
    pub sidewall: Option<Sidewall>,
    /// Second-order strain-rate correction of Fernández-Nieto et al. 2016, eq. (32) ("C-MSM").
    pub c_msm: bool,
    /// Viscosities of the viscous step at t^n or at the new speed (`rheology.viscosity`).
    pub viscosity: ViscosityTime,
    /// Speed (m/s) above which a layer flows, for `/snapshots/static_interface`.
    pub static_threshold: f64,
}

impl MultilayerSpec {
    /// The options of the μ(I) viscous step (line and raster).
    pub fn viscous_options(&self) -> ViscousOptions {
        ViscousOptions {
            basal: self.basal,
            regularization: self.regularization,
            sidewall: self.sidewall,
            c_msm: self.c_msm,
            viscosity: self.viscosity,
        }
    }
}
