//! μ(I) friction of Jop, Forterre & Pouliquen (seed 000 eq. 6):
//!
//!   μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I),
//!
//! with the basal inertial number of seed 000 eq. (15e),
//!
//!   I = d_s γ̇ / √(p_b / ρ_s),   p_b/ρ_s = φ_s p_b/ρ   (ρ = φ_s ρ_s),
//!
//! and, for the monolayer model, the shear rate of the Bagnold profile
//! γ̇ = 5|ū| / (2h) (seed 002 eq. 2.15).

use super::{BasalFriction, LocalFriction};
use crate::physics::shallow::H_DRY;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuI {
    pub mu_s: f64,
    pub mu_2: f64,
    pub i0: f64,
    /// Grain diameter d_s (m).
    pub d_s: f64,
    /// Solid volume fraction φ_s.
    pub phi: f64,
}

/// Basal inertial number of a monolayer flow (seed 000 eq. 15e, seed 002 eq. 2.15).
#[inline(always)]
pub fn inertial_number(d_s: f64, phi: f64, speed: f64, h: f64, p_over_rho: f64) -> f64 {
    if h <= H_DRY || p_over_rho <= 0.0 {
        return 0.0;
    }
    let shear_rate = 2.5 * speed / h;
    d_s * shear_rate / (phi * p_over_rho).sqrt()
}

/// Local inertial number I = d_s |∂_z u| / √(p/ρ_s), p/ρ_s = φ_s p/ρ (seed 003 eq. 10;
/// with it the steady Bagnold profile is seed 001 eq. 29). Zero where p ≤ 0.
#[inline(always)]
pub fn local_inertial_number(d_s: f64, phi: f64, shear_rate: f64, p_over_rho: f64) -> f64 {
    if p_over_rho <= 0.0 {
        return 0.0;
    }
    d_s * shear_rate / (phi * p_over_rho).sqrt()
}

impl MuI {
    /// μ(I), written as μ_s + (μ_2 − μ_s)/(1 + I_0/I) so that I = ∞ gives μ_2 and
    /// I = 0 gives μ_s without a 0/0 or ∞/∞.
    #[inline(always)]
    pub fn mu_of_i(&self, i: f64) -> f64 {
        self.mu_s + (self.mu_2 - self.mu_s) / (1.0 + self.i0 / i)
    }
}

impl BasalFriction for MuI {
    #[inline(always)]
    fn mu(&self, speed: f64, h: f64, p_over_rho: f64) -> f64 {
        self.mu_of_i(inertial_number(self.d_s, self.phi, speed, h, p_over_rho))
    }
}

impl LocalFriction for MuI {
    #[inline(always)]
    fn inertial_scale(&self, p_over_rho: f64) -> f64 {
        local_inertial_number(self.d_s, self.phi, 1.0, p_over_rho)
    }

    #[inline(always)]
    fn mu_at(&self, inertial_number: f64) -> f64 {
        self.mu_of_i(inertial_number)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn beads() -> MuI {
        MuI {
            mu_s: 25.5f64.to_radians().tan(),
            mu_2: 36f64.to_radians().tan(),
            i0: 0.279,
            d_s: 0.7e-3,
            phi: 0.62,
        }
    }

    #[test]
    fn mu_is_static_at_rest_and_tends_to_mu2() {
        let law = beads();
        assert_eq!(law.mu(0.0, 0.1, 9.81 * 0.1), law.mu_s);
        assert_relative_eq!(law.mu_of_i(1e12), law.mu_2, max_relative = 1e-10);
        assert_relative_eq!(law.mu_of_i(law.i0), 0.5 * (law.mu_s + law.mu_2));
        assert_eq!(law.mu_of_i(f64::INFINITY), law.mu_2);
        assert_eq!(law.mu_of_i(0.0), law.mu_s);
    }

    #[test]
    fn local_friction_uses_the_local_shear_rate() {
        let law = beads();
        // γ̇ = 100 1/s under p/ρ = 9.81·0.05: I = d_s γ̇ / √(φ p/ρ).
        let i = 0.7e-3 * 100.0 / (0.62f64 * 9.81 * 0.05).sqrt();
        assert_relative_eq!(
            law.mu_local(100.0, 9.81 * 0.05),
            law.mu_of_i(i),
            max_relative = 1e-14
        );
        assert_eq!(law.mu_local(0.0, 1.0), law.mu_s);
        assert_eq!(law.mu_local(1.0, 0.0), law.mu_s);
    }

    #[test]
    fn inertial_number_matches_hand_computation() {
        // u = 1 m/s, h = 1 cm: γ̇ = 250 1/s, p/ρ_s = 0.62·9.81·0.01.
        let i = inertial_number(0.7e-3, 0.62, 1.0, 0.01, 9.81 * 0.01);
        assert_relative_eq!(
            i,
            0.7e-3 * 250.0 / (0.62f64 * 0.0981).sqrt(),
            max_relative = 1e-14
        );
    }
}
