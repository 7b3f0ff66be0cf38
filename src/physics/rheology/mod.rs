//! Basal friction laws, as pointwise functions of the local flow state.
//!
//! The friction force per unit area is μ p_b u/|u| with p_b the basal pressure
//! (Garres-Díaz et al. 2021, eq. 5 and 15b). Each law implements [`BasalFriction`]; stages are generic
//! over it, so a constant-Coulomb run is compiled without any μ(I) evaluation
//! ("leave out what a scene does not need").

mod coulomb;
mod mu_i;
mod voellmy;

pub use coulomb::Coulomb;
pub use mu_i::{
    backward_euler_discharge, backward_euler_speed, inertial_number, local_inertial_number, MuI,
    STATIC_ROUNDOFF,
};
pub use voellmy::Voellmy;

/// Applies a friction impulse `dt_sigma` ≥ 0 against the discharge `q`, stopping it
/// if the impulse is large enough. A NaN impulse propagates (it must reach the
/// run's NaN check, not silently stop the flow).
#[inline(always)]
pub fn coulomb_update(q: f64, dt_sigma: f64) -> f64 {
    if dt_sigma >= q.abs() {
        0.0
    } else {
        q - dt_sigma * q.signum()
    }
}

/// Basal friction law (Garres-Díaz et al. 2021, eq. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// Constant Coulomb coefficient μ (classical Savage–Hutter).
    Coulomb { mu: f64 },
    /// μ(I) = μ_s + (μ_2 − μ_s) I / (I_0 + I).
    MuI { mu_s: f64, mu_2: f64, i0: f64 },
    /// Voellmy: τ = μ p + ρ g |u|²/ξ (turbulence coefficient ξ in m/s²; [`Voellmy`]).
    Voellmy { mu: f64, xi: f64 },
}

/// A basal friction law μ(state).
pub trait BasalFriction: Copy + Send + Sync + std::fmt::Debug {
    /// Friction coefficient for depth-averaged speed |u| (m/s), thickness h (m) and
    /// basal pressure over density p_b/ρ (m²/s², g_n h for a hydrostatic layer).
    fn mu(&self, speed: f64, h: f64, p_over_rho: f64) -> f64;

    /// The discharge after the friction step of a hydrostatic monolayer (Garres-Díaz et al. 2021, §3
    /// step 2, `numerics::friction`) from the discharge `q` the other steps left, for
    /// thickness `h` > H_DRY, time step `dt` and normal gravity `g_n`: friction stops
    /// the mass or slows it, never reverses it. By default μ is taken at the speed of
    /// `q` (exact for a constant μ); a law whose μ grows with the speed overrides this
    /// with a backward-Euler solve ([`MuI`]).
    #[inline(always)]
    fn friction_update(&self, q: f64, h: f64, dt: f64, g_n: f64) -> f64 {
        let mu = self.mu(crate::physics::shallow::velocity(h, q).abs(), h, g_n * h);
        coulomb_update(q, dt * mu * g_n * h)
    }

    /// The same for the non-hydrostatic monolayer (`numerics::nonhydrostatic`): the
    /// friction μ · max(p_total, 0) with the total basal pressure over density
    /// `p_total` = g_n h + p̄ (also the pressure of I), acting on the discharge `q`
    /// after the explicit pressure terms; `q_old` is the discharge before them, whose
    /// speed the default (explicit in μ) evaluates μ at.
    #[inline(always)]
    fn nh_friction_update(&self, q: f64, q_old: f64, h: f64, dt: f64, p_total: f64) -> f64 {
        let mu = self.mu(
            crate::physics::shallow::velocity(h, q_old).abs(),
            h,
            p_total,
        );
        let sigma = mu * p_total.max(0.0);
        coulomb_update(q, dt * sigma)
    }
}

/// The friction coefficient of the bulk rheology at a point of the flow, used by the
/// multilayer model between layers and at the bed (Fernández-Nieto et al. 2016, eq. 25–26, Escalante et al. 2023,
/// eq. 10): μ(I) with the local inertial number I = d_s |∂_z u| / √(p/ρ_s), or a
/// constant μ (Fernández-Nieto et al. 2016's "μ_s-MSM").
pub trait LocalFriction: Copy + Send + Sync + std::fmt::Debug {
    /// d_s / √(p/ρ_s) for the pressure over density p/ρ (m²/s²): times a shear rate it
    /// gives I (0 for a law that does not use I).
    fn inertial_scale(&self, p_over_rho: f64) -> f64;

    /// μ at the inertial number I.
    fn mu_at(&self, inertial_number: f64) -> f64;

    /// dμ/dI at the inertial number I ≥ 0 (the Newton iteration of the implicit
    /// viscous step, `rheology.viscosity = "implicit"`).
    fn mu_slope_at(&self, inertial_number: f64) -> f64;

    /// μ for a shear rate |∂_z u| (1/s) under the pressure over density p/ρ (m²/s²).
    #[inline(always)]
    fn mu_local(&self, shear_rate: f64, p_over_rho: f64) -> f64 {
        self.mu_at(shear_rate * self.inertial_scale(p_over_rho))
    }
}

#[cfg(test)]
mod tests {
    use super::coulomb_update;

    #[test]
    fn friction_stops_but_never_reverses() {
        assert_eq!(coulomb_update(1.0, 0.25), 0.75);
        assert_eq!(coulomb_update(-1.0, 0.25), -0.75);
        assert_eq!(coulomb_update(0.1, 0.25), 0.0);
        assert_eq!(coulomb_update(-0.1, 0.25), 0.0);
        assert!(coulomb_update(0.1, f64::NAN).is_nan());
    }
}
