//! Constant Coulomb friction (classical Savage–Hutter): μ ≡ μ_c.

use super::{BasalFriction, LocalFriction};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coulomb {
    pub mu: f64,
}

impl BasalFriction for Coulomb {
    #[inline(always)]
    fn mu(&self, _speed: f64, _h: f64, _p_over_rho: f64) -> f64 {
        self.mu
    }
}

impl LocalFriction for Coulomb {
    #[inline(always)]
    fn inertial_scale(&self, _p_over_rho: f64) -> f64 {
        0.0
    }

    #[inline(always)]
    fn mu_at(&self, _inertial_number: f64) -> f64 {
        self.mu
    }

    #[inline(always)]
    fn mu_slope_at(&self, _inertial_number: f64) -> f64 {
        0.0
    }
}
